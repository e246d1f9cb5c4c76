// Options and steps shared by the commands that run a trained tokenizer
// (encode, decode, transfer, eval recon): loading the checkpoint and the word
// vectors it needs, torch threads, and preparing a BVH file for the model.
#pragma once

#include "command_line.h"

#include "nec/motion/preprocess.h"
#include "nec/tat/checkpoint.h"
#include "nec/tat/inference.h"
#include "nec/text/word_vectors.h"

#include <optional>
#include <string>

namespace nec::app {

// Declares --model (unless with_model is false), --glove, --threads, --window-overlap.
void declare_model_options(CommandLine& cli, bool with_model = true);

struct TokenizerOptions {
  std::string model;          // checkpoint directory
  std::string glove;          // word vectors; empty = text::default_word_vectors_path()
  int threads = 0;            // torch threads; 0 = all cores
  int64_t overlap_frames = -1;  // -1: a quarter of the model's window, rounded down to a multiple of 2 r
};
// The options declared by declare_model_options (model empty without --model).
TokenizerOptions tokenizer_options(const CommandLine& cli);

// A loaded tokenizer with what it needs to embed skeletons.
struct TokenizerSession {
  tat::LoadedTatCheckpoint model;
  std::optional<text::WordVectors> vectors;  // loaded when the OwO encoder reads joint names
  tat::WindowOptions windows;

  // (J, D) joint embeddings of one normalized skeleton; undefined for the zero-padding baseline.
  at::Tensor embed(const Skeleton& skeleton, const std::vector<std::string>& canonical_names);
};

// Sets torch threads, loads the model (and the word vectors when needed), checks the overlap.
TokenizerSession open_tokenizer(const TokenizerOptions& options);

// read_bvh + preprocess at the model's fps; InputError naming the file when it is rejected.
PreparedClip prepare_for_model(const std::string& path, double fps, UpAxis up);

// The yaw (degrees, about the up axis) of a normalization's frame-0 heading,
// and a normalization that places normalized motion into `target`'s file
// (its scale, up axis and ground origin) with the heading `heading_degrees`.
double heading_degrees(const Normalization& normalization);
Normalization with_heading(const Normalization& target, double heading_degrees);

}  // namespace nec::app
