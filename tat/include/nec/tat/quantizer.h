// Residual vector quantization (NECromancer appendix C.5): R codebooks of K
// codes; stage r quantizes what the stages before it left over.
//
//   QuantizerConfig config;  config.layers = 4;  config.codebook_size = 256;  config.code_dim = 128;
//   ResidualQuantizer rvq(config);
//   QuantizerOutput q = rvq->forward(latent, mask);   // latent (N, C), mask (N) bool or undefined
//   // q.quantized (N, C) with straight-through gradients, q.codes (N, R), q.commitment_loss
//   at::Tensor same = rvq->codes_to_latent(q.codes);  // == q.quantized.detach() (all layers used)
//
// Codebooks are EMA-updated (no gradient) from the rows the mask keeps in
// training mode: forward collects the statistics, update_codebooks() moves the
// EMA once per optimizer step (a batch run in parts, or on several ranks,
// updates as one). They are seeded in the first training forward, and a code whose EMA
// usage falls below dead_code_threshold is restarted, both k-means++ style: at kept
// residuals drawn with a chance proportional to how badly the codes explain them.
// Quantize dropout (training only): with
// probability quantize_dropout a batch uses only the first n ~ U{1..R} layers,
// so early layers learn to carry the coarse motion on their own.
// A single-codebook VQ is this with layers = 1.
#pragma once

#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>

#include <cstdint>
#include <string>
#include <vector>

namespace nec::train {
class Communicator;
class ConfigVisitor;
}

namespace nec::tat {

struct QuantizerConfig {
  int64_t layers = 4;               // R residual layers, e.g. 4 (CPU) or 6 (paper)
  int64_t codebook_size = 256;      // K codes per layer, e.g. 256 (CPU) or 1024 (paper)
  int64_t code_dim = 128;           // C, width of a code = width of the latent
  double ema_decay = 0.99;          // EMA of code sums and counts
  double commitment_weight = 0.02;  // beta of |z - sg(q)|^2
  double dead_code_threshold = 1.0; // EMA usage (codes per batch) below which a code is reset
  double quantize_dropout = 0.2;    // chance per training batch of using only the first n layers

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, QuantizerConfig& c);  // train/config_fields.h

struct QuantizerOutput {
  at::Tensor quantized;        // (N, C) sum of the chosen codes; straight-through gradient to the latent
  at::Tensor codes;            // (N, R) int64 code indices (layers skipped by dropout: -1)
  at::Tensor commitment_loss;  // scalar, commitment_weight * mean |latent - sg(quantized)|^2 over kept rows
  at::Tensor perplexity;       // (R) float, exp(entropy of code usage) per layer over kept rows (0 if skipped)
};

class ResidualQuantizerImpl : public torch::nn::Module {
 public:
  explicit ResidualQuantizerImpl(const QuantizerConfig& config);

  // latent (N, C); mask (N) bool, true for rows that count (real frames), or undefined = all.
  QuantizerOutput forward(const at::Tensor& latent, const at::Tensor& mask = {});
  // Moves the EMA codebooks by the statistics the training forwards since the
  // last call collected (summed over the ranks of the communicator), restarts
  // dead codes, and clears the statistics. Returns whether a layer moved.
  // On several ranks every rank calls it once per step.
  bool update_codebooks();
  // The ranks of a data-parallel run (null: one process): seeding and updates
  // then use every rank's rows, and every rank keeps the same codebooks.
  void set_communicator(const train::Communicator* communicator) { communicator_ = communicator; }
  // codes (N, R') int64 with R' <= R (the first R' layers) -> (N, C), no gradient needed.
  at::Tensor codes_to_latent(const at::Tensor& codes);

  const QuantizerConfig& config() const { return config_; }

 private:
  QuantizerConfig config_;
  at::Tensor codebooks_;    // buffer (R, K, C)
  at::Tensor ema_counts_;   // buffer (R, K)
  at::Tensor ema_sums_;     // buffer (R, K, C)
  at::Tensor initialized_;  // buffer () bool: codebooks seeded from the first batch
  // Statistics of the training forwards since the last update_codebooks().
  at::Tensor pending_counts_;                         // (R, K) kept rows per code
  at::Tensor pending_sums_;                           // (R, K, C) their sum
  std::vector<std::vector<at::Tensor>> pending_rows_;  // per layer: (N, 2C + 1) residual, its error, weight
  const train::Communicator* communicator_ = nullptr;

  // `rows` of every rank, concatenated in rank order (this rank's alone without a communicator).
  at::Tensor all_ranks(const at::Tensor& rows) const;
};
TORCH_MODULE(ResidualQuantizer);

}  // namespace nec::tat
