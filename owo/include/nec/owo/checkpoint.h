// OwO checkpoints: a pretrained OwoPretrainer (encoder + heads) as a directory
//
//   <dir>/config.json   {"format": "nec-owo", "version": 3, "architecture": "OwoPretrainer",
//                        "encoder": OwoConfig, "pretrain": PretrainConfig,
//                        "training_step": 1200, "data": "zoo: 512 creatures, seed 3",
//                        "tensors": "tensors.pt"}
//   <dir>/tensors.pt    every parameter and buffer by its dotted name (torch archive)
//
//   save_owo_checkpoint("runs/owo", model, {/*training_step=*/1200, "zoo: 512 creatures"});
//   LoadedOwoCheckpoint loaded = load_owo_checkpoint("runs/owo");  // CPU; ->to(device) after
//   OwoOutput out = loaded.model->encoder->forward(batch);
//
// Saving writes a temporary sibling directory and renames it into place, so a
// failed save leaves the old checkpoint (or nothing) behind. Loading compares
// format, version, architecture and every tensor's name and shape against
// config.json before touching the model, and throws nec::InputError naming the
// file, the problem and what to do.
#pragma once

#include "nec/owo/pretrain.h"

#include <cstdint>
#include <string>

namespace nec::owo {

constexpr const char* kOwoCheckpointFormat = "nec-owo";  // config.json "format"
// config.json "version" this nec reads and writes; 2: the LCA pointer's ancestry term (lca_ancestry.*);
// 3: trained on skeletons in the canonical rest pose (corpus/rest_pose.h).
constexpr int kOwoCheckpointVersion = 3;

// What a checkpoint records besides the architecture.
struct OwoCheckpointInfo {
  int64_t training_step = 0;  // optimizer steps taken, e.g. 1200
  std::string data;           // free-form description of the training data, e.g. "zoo: 512 creatures, seed 3"
};

struct LoadedOwoCheckpoint {
  OwoPretrainer model{nullptr};  // on the CPU, in training mode
  OwoCheckpointInfo info;
};

// Writes `model` (any device) to the directory `dir`, replacing an earlier
// checkpoint there. Throws std::runtime_error naming the path when it cannot
// write, or when `dir` exists and is not an OwO checkpoint (nothing is deleted).
void save_owo_checkpoint(const std::string& dir, OwoPretrainerImpl& model, const OwoCheckpointInfo& info);

// Throws nec::InputError (file: problem; hint) for a missing, foreign,
// newer/older, edited or truncated checkpoint.
LoadedOwoCheckpoint load_owo_checkpoint(const std::string& dir);

}  // namespace nec::owo
