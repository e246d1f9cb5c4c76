// Text to motion on any skeleton, through tokens: what `nec generate` runs.
//
//   GeneratorSession session = open_generator("runs/gpt", /*glove=*/"");
//   const PreparedClip dragon = tat::prepare_for_model("dragon.bvh", session.fps(), UpAxis::Auto);
//   std::vector<at::Tensor> codes = generate_codes(session, dragon, {{"a dragon walks forward", 30}}, 2, options);
//   tat::decode_onto(session.tokenizer, session.token_file(codes[0], "a dragon walks forward"), "dragon.bvh", ...);
//
// Several segments make one long motion: each segment is sampled with its
// own caption, continuing from the codes of the segments before it (the GPT
// reads the last of them as context), and the whole sequence is decoded at
// once, so the tokenizer's decoder and its cross-faded windows join the
// segments without a cut (docs/generation.md).
#pragma once

#include "nec/gpt/checkpoint.h"
#include "nec/gpt/sampling.h"
#include "nec/corpus/preprocess.h"
#include "nec/tat/session.h"

#include <ATen/core/Tensor.h>

#include <optional>
#include <string>
#include <vector>

namespace nec::gpt {

struct GeneratorSession {
  LoadedGpt gpt;
  tat::TokenizerSession tokenizer;
  std::optional<text::WordVectors> caption_vectors;  // the text encoder's word vectors when it reads any

  double fps() const { return tokenizer.model.info.fps; }
  int64_t downsampling() const { return tokenizer.model.tokenizer->config().downsampling(); }
  // A token file of codes (S, R) for decode_onto; `caption` names where it came from.
  tat::TokenFile token_file(const at::Tensor& codes, const std::string& caption) const;
};

// Loads the GPT checkpoint `dir`, its tokenizer and the word vectors both
// read (`glove`, or the default file). InputError naming the file otherwise.
GeneratorSession open_generator(const std::string& dir, const std::string& glove);

struct Segment {
  std::string caption;
  int64_t steps = 0;  // token steps; 0: until the GPT ends it (at most max_steps - 1)
};

// Codes (S, R) int64 of `samples` motions for the skeleton of `target` (a
// clip prepared for the model), each the segments in order. Sample i draws
// from seed + i of its own streams, so it is the same whatever `samples` is.
// InputError for an empty caption or one longer than the text encoder takes.
std::vector<at::Tensor> generate_codes(GeneratorSession& session, const PreparedClip& target,
                                       const std::vector<Segment>& segments, int samples,
                                       const SamplingOptions& options);

}  // namespace nec::gpt
