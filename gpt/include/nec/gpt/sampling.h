// Sampling token sequences from a TokenGpt: temperature, top-k, top-p,
// classifier-free guidance, a seed per sample, batched, with a KV cache (the
// cost of each step does not grow with the length).
//
//   SamplingOptions options;  options.top_p = 0.9;  options.guidance = 2.5;  options.seed = 7;
//   GptCondition c = gpt->condition(captions, skeleton_features, {});
//   GptCondition u = gpt->unconditioned(skeleton_features);
//   std::vector<at::Tensor> codes = sample_codes(*gpt, c, &u, {}, {/*steps=*/30}, options);  // each (S, R) int64
//
// Length: with steps > 0 exactly that many steps (the end code is never drawn);
// with steps = 0 until the end code is drawn (at least min_steps), at most
// max_steps. A sequence longer than the model reads at once slides: the model
// restarts from the condition and the last half of its window.
// Guidance: layer logits are u + g (c - u), the conditioned and unconditioned
// halves run as one batch; g = 1 runs the conditioned half alone.
// Row i of a batch draws from its own stream, seed + i, so a sample does not
// depend on the batch it was drawn in.
#pragma once

#include "nec/gpt/model.h"

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace nec::gpt {

struct SamplingOptions {
  double temperature = 1.0;  // divides the logits, > 0
  int64_t top_k = 0;         // keep the k most likely codes; 0 = all
  double top_p = 0.95;       // keep the fewest codes whose probability reaches p, in (0, 1]; 1 = all
  double guidance = 2.5;     // classifier-free guidance scale g >= 1; 1 = none
  uint64_t seed = 0;         // row i draws from the stream of seed + i
  std::function<void(size_t segment, size_t segments)> on_segment;  // generate_codes: before each segment (progress)

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

struct SequenceLength {
  int64_t steps = 0;       // exactly this many steps; 0: until the end code
  int64_t min_steps = 4;   // with steps = 0: the end code is not drawn before this many
  int64_t max_steps = 64;  // with steps = 0: stop here without an end code
};

// Probabilities (B, V) float32 after temperature, top-k and top-p on logits (B, V); -inf logits stay 0.
at::Tensor sampling_probabilities(const at::Tensor& logits, const SamplingOptions& options);

// Draws one index per row of probabilities (B, V) (rows sum to 1) from u (B) uniforms in [0, 1): inverse CDF.
std::vector<int64_t> draw_codes(const at::Tensor& probabilities, const std::vector<double>& uniforms);

// One code sequence (S_i, R) int64 per row of `condition`, after `context`
// (B, C, R) int64 codes each continues (undefined: none; they are not
// returned). `unconditioned` may be null only when options.guidance is 1.
// Runs under InferenceMode; put the model in eval mode first.
std::vector<at::Tensor> sample_codes(TokenGptImpl& gpt, const GptCondition& condition,
                                     const GptCondition* unconditioned, const at::Tensor& context,
                                     const SequenceLength& length, const SamplingOptions& options);

}  // namespace nec::gpt
