// Sampling token sequences: filtered probabilities, guided logits, cached steps, sliding windows.
#include "nec/gpt/sampling.h"

#include "nec/layers/transformer.h"
#include "nec/motion/random.h"

#include <torch/torch.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace nec::gpt {
namespace {

// Memory (B, P, D) and bias padded with masked pieces to P' >= P.
GptCondition pad_memory(const GptCondition& c, int64_t pieces) {
  const int64_t missing = pieces - c.memory.size(1);
  if (missing == 0) return c;
  GptCondition out = c;
  out.memory = torch::cat({c.memory, torch::zeros({c.memory.size(0), missing, c.memory.size(2)}, c.memory.options())}, 1);
  const at::Tensor masked =
      torch::full({c.memory_bias.size(0), 1, 1, missing}, layers::kMaskedScore, c.memory_bias.options());
  out.memory_bias = torch::cat({c.memory_bias, masked}, 3);
  return out;
}

// Rows of a then rows of b.
GptCondition concat(const GptCondition& a, const GptCondition& b) {
  const int64_t pieces = std::max(a.memory.size(1), b.memory.size(1));
  const GptCondition pa = pad_memory(a, pieces), pb = pad_memory(b, pieces);
  return {torch::cat({pa.prefix, pb.prefix}), torch::cat({pa.memory, pb.memory}),
          torch::cat({pa.memory_bias, pb.memory_bias})};
}

// The last `count` steps of sequence (B, S, R).
at::Tensor tail(const at::Tensor& sequence, int64_t count) {
  return sequence.narrow(1, sequence.size(1) - count, count);
}

}  // namespace

void SamplingOptions::validate() const {
  if (!(temperature > 0)) throw std::invalid_argument("temperature must be > 0, got " + std::to_string(temperature));
  if (top_k < 0) throw std::invalid_argument("top_k must be >= 0 (0: all codes), got " + std::to_string(top_k));
  if (!(top_p > 0 && top_p <= 1)) throw std::invalid_argument("top_p must be in (0, 1], got " + std::to_string(top_p));
  if (!(guidance >= 1)) throw std::invalid_argument("guidance must be >= 1 (1: none), got " + std::to_string(guidance));
}

at::Tensor sampling_probabilities(const at::Tensor& logits, const SamplingOptions& options) {
  const double minus_infinity = -std::numeric_limits<double>::infinity();
  at::Tensor scaled = logits.to(torch::kFloat32) / options.temperature;
  const int64_t v = scaled.size(1);
  if (options.top_k > 0 && options.top_k < v) {
    const at::Tensor kth = std::get<0>(scaled.topk(options.top_k, 1)).narrow(1, options.top_k - 1, 1);
    scaled = scaled.masked_fill(scaled < kth, minus_infinity);
  }
  if (options.top_p < 1) {
    const auto [sorted, order] = scaled.sort(1, /*descending=*/true);
    const at::Tensor mass = torch::softmax(sorted, 1);
    // A code stays while the codes above it hold less than top_p (the most likely one always stays).
    const at::Tensor above = mass.cumsum(1) - mass;
    const at::Tensor drop_sorted = above >= options.top_p;
    const at::Tensor drop = torch::zeros_like(drop_sorted).scatter(1, order, drop_sorted);
    scaled = scaled.masked_fill(drop, minus_infinity);
  }
  return torch::softmax(scaled, 1);
}

std::vector<int64_t> draw_codes(const at::Tensor& probabilities, const std::vector<double>& uniforms) {
  const at::Tensor p = probabilities.to(torch::kCPU, torch::kFloat64).contiguous();
  const int64_t rows = p.size(0), v = p.size(1);
  if (static_cast<int64_t>(uniforms.size()) != rows) throw std::invalid_argument("draw_codes: one uniform per row");
  const double* values = p.data_ptr<double>();
  std::vector<int64_t> out(static_cast<size_t>(rows));
  for (int64_t row = 0; row < rows; ++row) {
    const double* q = values + row * v;
    double total = 0;
    for (int64_t i = 0; i < v; ++i) total += q[i];
    const double target = uniforms[static_cast<size_t>(row)] * total;
    double running = 0;
    int64_t pick = -1;
    for (int64_t i = 0; i < v; ++i) {
      if (q[i] <= 0) continue;
      pick = i;  // the last code with mass, should rounding leave the target above the sum
      running += q[i];
      if (target < running) break;
    }
    out[static_cast<size_t>(row)] = pick;
  }
  return out;
}

std::vector<at::Tensor> sample_codes(TokenGptImpl& gpt, const GptCondition& condition,
                                     const GptCondition* unconditioned, const at::Tensor& context,
                                     const SequenceLength& length, const SamplingOptions& options) {
  options.validate();
  if (gpt.is_training()) throw std::logic_error("sample_codes: call gpt->eval() first");
  const bool guided = options.guidance != 1.0;
  if (guided && unconditioned == nullptr) throw std::invalid_argument("sample_codes: guidance needs the unconditioned condition");
  if (length.steps < 0 || length.max_steps < 1 || length.min_steps < 0) {
    throw std::invalid_argument("sample_codes: steps must be >= 0, max_steps >= 1 and min_steps >= 0");
  }
  c10::InferenceMode inference;
  const GptConfig& config = gpt.config();
  const int64_t b = condition.prefix.size(0), r = config.codebook_layers, k = config.codebook_size;
  const int64_t window = config.max_steps;
  const c10::Device device = condition.prefix.device();
  const GptCondition both = guided ? concat(condition, *unconditioned) : condition;
  const auto doubled = [&](const at::Tensor& codes) { return guided ? torch::cat({codes, codes}) : codes; };

  at::Tensor sequence = context.defined() ? context.to(device, torch::kInt64)
                                          : torch::zeros({b, 0, r}, torch::TensorOptions(device).dtype(torch::kInt64));
  const int64_t context_steps = sequence.size(1);
  KvCache cache;
  at::Tensor h = gpt.start(both, cache, doubled(tail(sequence, std::min(context_steps, window - 1))));
  int64_t cached_steps = std::min(context_steps, window - 1);

  std::vector<SplitMix64> streams;
  for (int64_t row = 0; row < b; ++row) streams.emplace_back(mix64(options.seed + static_cast<uint64_t>(row)));
  std::vector<int64_t> lengths(static_cast<size_t>(b), -1);  // -1: not ended
  const int64_t limit = length.steps > 0 ? length.steps : length.max_steps;
  for (int64_t generated = 0; generated < limit; ++generated) {
    at::Tensor codes = torch::zeros({b, r}, torch::TensorOptions(device).dtype(torch::kInt64));
    for (int64_t layer = 0; layer < r; ++layer) {
      const at::Tensor lower = doubled(codes.narrow(1, 0, layer));
      at::Tensor logits = gpt.layer_logits(h, layer, lower);
      if (guided) {
        const at::Tensor c = logits.narrow(0, 0, b), u = logits.narrow(0, b, b);
        logits = u + options.guidance * (c - u);
      }
      if (layer == 0 && (length.steps > 0 || generated < length.min_steps)) {
        logits = logits.index_fill(1, torch::tensor({k}, logits.options().dtype(torch::kInt64)),
                                   -std::numeric_limits<double>::infinity());
      }
      std::vector<double> uniforms;
      for (SplitMix64& stream : streams) uniforms.push_back(stream.uniform());
      std::vector<int64_t> drawn = draw_codes(sampling_probabilities(logits, options), uniforms);
      for (int64_t row = 0; row < b; ++row) {
        int64_t& code = drawn[static_cast<size_t>(row)];
        if (code == k) {  // the end code (layer 0 only)
          if (lengths[static_cast<size_t>(row)] < 0) lengths[static_cast<size_t>(row)] = generated;
          code = 0;
        }
      }
      codes.select(1, layer).copy_(torch::tensor(drawn, torch::kInt64));
    }
    sequence = torch::cat({sequence, codes.unsqueeze(1)}, 1);
    const bool all_ended = std::all_of(lengths.begin(), lengths.end(), [](int64_t n) { return n >= 0; });
    if (all_ended || generated + 1 == limit) break;
    if (cached_steps + 1 > window - 1) {  // the window is full: restart from its last half
      cached_steps = window / 2;
      h = gpt.start(both, cache, doubled(tail(sequence, cached_steps)));
    } else {
      h = gpt.advance(cache, doubled(codes));
      ++cached_steps;
    }
  }
  std::vector<at::Tensor> out;
  const int64_t total = sequence.size(1) - context_steps;
  for (int64_t row = 0; row < b; ++row) {
    const int64_t n = lengths[static_cast<size_t>(row)] >= 0 ? lengths[static_cast<size_t>(row)] : total;
    out.push_back(sequence[row].narrow(0, context_steps, n).to(torch::kCPU).clone());
  }
  return out;
}

}  // namespace nec::gpt
