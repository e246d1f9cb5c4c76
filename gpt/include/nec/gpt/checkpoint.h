// GPT checkpoints: the text-to-token transformer with everything generation
// needs, so one directory is all `nec generate` reads.
//
//   <dir>/config.json   {"format": "nec-gpt", "version": 1, "architecture": "TokenGpt", "gpt": GptConfig,
//                        "fps": 30, "downsampling": 4, "training_step": 3000, "data": "cache/ (1,400 clips)",
//                        "tensors": "tensors.pt", "pieces": "pieces.model", "tat": "tat"}
//   <dir>/tensors.pt    the GPT's parameters (its text encoder included)
//   <dir>/pieces.model  the caption piece model its text encoder reads (backbone "pieces" only)
//   <dir>/tat/          the tokenizer checkpoint whose tokens it predicts (with the OwO encoder in tat/owo/)
//   <dir>/training.json, optimizer.pt   optional: the training state for --resume
//
//   save_gpt_checkpoint("runs/gpt", *gpt, captions, tokenizer, info);
//   LoadedGpt g = load_gpt_checkpoint("runs/gpt");   // CPU, eval mode; g.tat_dir for tat::open_tokenizer_session
#pragma once

#include "nec/gpt/model.h"
#include "nec/tat/checkpoint.h"
#include "nec/text/text_encoder.h"

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

// Writes `dir` atomically: config, tensors, what the captions need
// (text::save_checkpoint_captions) and the tokenizer (`tokenizer`'s models and
// info); `extra` may add files first.
void save_gpt_checkpoint(const std::string& dir, TokenGptImpl& model, const text::CaptionReader& captions,
                         tat::LoadedTatCheckpoint& tokenizer, const GptCheckpointInfo& info,
                         const std::function<void(const std::string&)>& extra = {});

struct LoadedGpt {
  TokenGpt model{nullptr};  // CPU, eval mode
  text::CaptionReader captions;
  std::string tat_dir;      // the tokenizer checkpoint inside
  GptCheckpointInfo info;
};

// InputError naming the file for a missing or damaged checkpoint, one of
// another kind (e.g. a tokenizer given for a GPT) or version, with a hint.
LoadedGpt load_gpt_checkpoint(const std::string& dir);

}  // namespace nec::gpt
