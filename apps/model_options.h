// Options shared by the commands that run a trained tokenizer (encode,
// decode, transfer, eval recon): the checkpoint, the word vectors it needs,
// torch threads and the window overlap.
#pragma once

#include "command_line.h"

#include "nec/tat/session.h"
#include "warm_cache.h"

#include <memory>
#include <string>

namespace nec::app {

// The default models of the repository (models/default/, made by scripts/train_default_models.sh):
// the directory of `name` ("gpt", "gpt/tat", "evaluator"), or "" when it is not there.
std::string default_model_dir(const std::string& name);
// `given` when not empty, else the default model `name`; UsageError naming `option` when there is none.
std::string model_or_default(const std::string& given, const std::string& name, const std::string& option);

// The "format" of the checkpoint directory `dir` (its config.json), e.g. "nec-gpt"; "" when it has none.
std::string checkpoint_format(const std::string& dir);

// Declares --model (unless with_model is false; default: the default models' tokenizer), --glove, --threads,
// --window-overlap.
void declare_model_options(CommandLine& cli, bool with_model = true);

struct TokenizerOptions {
  std::string model;          // checkpoint directory
  std::string glove;          // word vectors; empty = text::default_word_vectors_path()
  int threads = 0;            // torch threads; 0 = all cores
  int64_t overlap_frames = -1;  // -1: a quarter of the model's window, rounded down to a multiple of 2 r
};
// The options declared by declare_model_options (model empty without --model).
TokenizerOptions tokenizer_options(const CommandLine& cli);

// Sets torch threads and opens the tokenizer (tat::open_tokenizer_session; kept by a worker, warm_cache.h); a
// bad --window-overlap is a UsageError.
std::shared_ptr<tat::TokenizerSession> open_tokenizer(const TokenizerOptions& options);

// The key part of the word vectors `glove` ("" = the default ones) for warm_cache.h: path, size and time.
std::string glove_stamp(const std::string& glove);

// Declares --stance and --rest-from-motion: how a skeleton that receives motion gets the rest its motion turns
// around (tat::prepare_target).
void declare_stance_options(CommandLine& cli);
// The stance network those options ask for (--stance, else the default models' models/default/stance), or null
// with --rest-from-motion, or when the default one is missing or cannot be used (no word vectors: a note on
// stderr says the mean pose is used). `glove`: the word vectors, for a network that reads joint names.
// InputError for a --stance checkpoint that cannot be used.
// A worker keeps the network (warm_cache.h).
struct Stance {
  std::shared_ptr<const StancePredictor> network;  // null: the mean pose of the file's motion
  std::string key;                                 // its files (warm_cache.h), "" without one
};
Stance open_stance(const CommandLine& cli, const std::string& glove);
// tat::prepare_target, with the target's warnings (a skeleton without limbs, joints on their parents) on stderr.
// A worker keeps the prepared rig for the same file (unchanged), rate, up axis and stance network.
PreparedClip prepare_target(const std::string& path, double fps, UpAxis up, const Stance& stance);

}  // namespace nec::app
