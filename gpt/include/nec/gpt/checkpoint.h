// GPT checkpoints: the text-to-token transformer with everything generation
// needs, so one directory is all `nec generate` reads.
//
//   <dir>/config.json   {"format": "nec-gpt", "version": 1, "architecture": "TokenGpt", "gpt": GptConfig,
//                        "fps": 30, "downsampling": 4, "training_step": 3000, "data": "cache/ (1,400 clips)",
//                        "tensors": "tensors.pt", "pieces": "pieces.model", "tat": "tat"}
//   <dir>/tensors.pt    the GPT's parameters (its text encoder included)
//   <dir>/pieces.model  the caption piece model its text encoder reads
//   <dir>/tat/          the tokenizer checkpoint whose tokens it predicts (with the OwO encoder in tat/owo/)
//   <dir>/training.json, optimizer.pt   optional: the training state for --resume
//
//   save_gpt_checkpoint("runs/gpt", *gpt, pieces_bytes, tokenizer, info);
//   LoadedGpt g = load_gpt_checkpoint("runs/gpt");   // CPU, eval mode; g.tat_dir for tat::open_tokenizer_session
#pragma once

#include "nec/gpt/model.h"
#include "nec/tat/checkpoint.h"
#include "nec/text/piece_model.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace nec::gpt {

constexpr const char* kGptCheckpointFormat = "nec-gpt";
constexpr int kGptCheckpointVersion = 1;

struct GptCheckpointInfo {
  double fps = 30.0;           // the corpus fps of the tokens
  int64_t training_step = 0;
  std::string data;            // what it was trained on
};

// Writes `dir` atomically: config, tensors, the piece model's bytes and the
// tokenizer (`tokenizer`'s models and info); `extra` may add files first.
void save_gpt_checkpoint(const std::string& dir, TokenGptImpl& model, const std::string& piece_model_bytes,
                         tat::LoadedTatCheckpoint& tokenizer, const GptCheckpointInfo& info,
                         const std::function<void(const std::string&)>& extra = {});

struct LoadedGpt {
  TokenGpt model{nullptr};  // CPU, eval mode
  std::optional<text::PieceModel> pieces;
  std::string piece_model_path;
  std::string tat_dir;      // the tokenizer checkpoint inside
  GptCheckpointInfo info;
};

// InputError naming the file for a missing or damaged checkpoint, one of
// another kind (e.g. a tokenizer given for a GPT) or version, with a hint.
LoadedGpt load_gpt_checkpoint(const std::string& dir);

}  // namespace nec::gpt
