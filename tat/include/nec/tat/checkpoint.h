// TAT checkpoints: a trained tokenizer together with the frozen OwO encoder it
// was trained with, so one directory is all `nec encode|decode|transfer` need.
//
//   <dir>/config.json   {"format": "nec-tat", "version": 10, "architecture": "Tokenizer",
//                        "tokenizer": TatConfig, "window_frames": 64, "fps": 30,
//                        "training_step": 4000, "data": "cache/ (1,036 clips)",
//                        "tensors": "tensors.pt", "owo": "owo"}
//   <dir>/tensors.pt    the tokenizer's parameters and buffers by dotted name
//   <dir>/owo/          the OwO checkpoint (owo/checkpoint.h) whose encoder gives h_j
//   <dir>/training.json, optimizer.pt   optional: the training state (train/training_state.h) for --resume
//
//   save_tat_checkpoint("runs/tat", *tokenizer, *owo, info);             // a model alone
//   save_tat_checkpoint("runs/tat", *tokenizer, *owo, info, [&](const std::string& temp) {
//     train::write_training_state(temp, state, optimizer);              // TatTrainer::save
//   });
//   LoadedTatCheckpoint m = load_tat_checkpoint("runs/tat");   // CPU, eval mode
#pragma once

#include "nec/owo/pretrain.h"
#include "nec/tat/tokenizer.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <string>


namespace nec::tat {

constexpr const char* kTatCheckpointFormat = "nec-tat";
constexpr int kTatCheckpointVersion = 11;  // version 11: the root's rise read from the virtual joint; history in docs/checkpoint-format.md

struct TatCheckpointInfo {
  int64_t window_frames = 64;   // training window T, e.g. 64; inference uses windows of this size
  double fps = 30.0;            // corpus frame rate the model was trained at
  int64_t training_step = 0;    // optimizer steps taken
  std::string data;             // description of the training data
};

struct LoadedTatCheckpoint {
  Tokenizer tokenizer{nullptr};  // CPU, eval mode
  owo::OwoPretrainer owo{nullptr};  // CPU, eval mode; owo->encoder gives h_j
  TatCheckpointInfo info;
};

// Writes atomically (train/checkpoint_io.h); `extra` writes more files into
// the temporary directory before the swap (the training state).
void save_tat_checkpoint(const std::string& dir, TokenizerImpl& tokenizer, owo::OwoPretrainerImpl& owo,
                         const TatCheckpointInfo& info,
                         const std::function<void(const std::string& temp_dir)>& extra = {});

// Throws nec::InputError naming the file and the problem for a missing,
// foreign, other-version, damaged or mismatched checkpoint.
LoadedTatCheckpoint load_tat_checkpoint(const std::string& dir);

}  // namespace nec::tat
