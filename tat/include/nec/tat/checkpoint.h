// TAT checkpoints: a trained tokenizer together with the frozen OwO encoder it
// was trained with, so one directory is all `nec encode|decode|transfer` need.
//
//   <dir>/config.json   {"format": "nec-tat", "version": 5, "architecture": "Tokenizer",
//                        "tokenizer": TatConfig, "window_frames": 64, "fps": 30,
//                        "training_step": 4000, "data": "cache/ (1,036 clips)",
//                        "training": {... free-form state for --resume ...},
//                        "tensors": "tensors.pt", "owo": "owo"}
//   <dir>/tensors.pt    the tokenizer's parameters and buffers by dotted name
//   <dir>/owo/          the OwO checkpoint (owo/checkpoint.h) whose encoder gives h_j
//   <dir>/optimizer.pt  optional: optimizer state, for resuming training
//
//   save_tat_checkpoint("runs/tat", *tokenizer, *owo, info, &optimizer);
//   LoadedTatCheckpoint m = load_tat_checkpoint("runs/tat");   // CPU, eval mode
#pragma once

#include "nec/owo/pretrain.h"
#include "nec/tat/tokenizer.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

namespace torch::optim {
class Optimizer;
}

namespace nec::tat {

constexpr const char* kTatCheckpointFormat = "nec-tat";
constexpr int kTatCheckpointVersion = 9;  // 2: the encoder scales the root displacement up; 3: the decoder
                                           // predicts it scaled; 4: windows start with the clip's start
                                           // heading (turn_to_heading, align_window_headings); 5: the
                                           // virtual joint starts from the root joint's input; 6: the
                                           // networks see Θ in model space (model_space.h); 7: the
                                           // joint embeddings are centred over the skeleton; 8: the NEC
                                           // decoder reads the root's path from the virtual joint; 9: model
                                           // space holds the root's height per frame, not Θ's Δy

struct TatCheckpointInfo {
  int64_t window_frames = 64;   // training window T, e.g. 64; inference uses windows of this size
  double fps = 30.0;            // corpus frame rate the model was trained at
  int64_t training_step = 0;    // optimizer steps taken
  std::string data;             // description of the training data
  nlohmann::json training = nlohmann::json::object();  // trainer state (loader position, options), for --resume
};

struct LoadedTatCheckpoint {
  Tokenizer tokenizer{nullptr};  // CPU, eval mode
  owo::OwoPretrainer owo{nullptr};  // CPU, eval mode; owo->encoder gives h_j
  TatCheckpointInfo info;
  std::string optimizer_path;    // "<dir>/optimizer.pt" when present, else ""
};

// Writes atomically (owo/checkpoint_io.h); `optimizer` may be null.
void save_tat_checkpoint(const std::string& dir, TokenizerImpl& tokenizer, owo::OwoPretrainerImpl& owo,
                         const TatCheckpointInfo& info, torch::optim::Optimizer* optimizer = nullptr);

// Throws nec::InputError naming the file and the problem for a missing,
// foreign, other-version, damaged or mismatched checkpoint.
LoadedTatCheckpoint load_tat_checkpoint(const std::string& dir);

// TatConfig <-> JSON (the "tokenizer" object); from_json throws InputError via
// `file` naming the bad field. Also used for training config files.
nlohmann::json to_json(const TatConfig& config);
TatConfig tat_config_from_json(const nlohmann::json& object, const std::string& file, const std::string& where);

}  // namespace nec::tat
