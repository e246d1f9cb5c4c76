// Residual vector quantizer with EMA codebooks, dead-code reset and quantize dropout.
#include "nec/tat/quantizer.h"

#include "nec/train/config_fields.h"
#include "nec/train/distributed.h"

#include <torch/torch.h>

#include <stdexcept>
#include <string>

namespace nec::tat {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("QuantizerConfig: " + message);
}

// Laplace smoothing of the EMA counts, so that a rarely used code is not divided by ~0.
constexpr double kLaplaceEpsilon = 1e-5;

// `count` rows of `rows` (N, C) drawn with replacement, row i with a chance
// proportional to weight_i (N) times |error_i|^2 (error (N, C)): k-means++ style,
// so a code is seeded or restarted where the codes so far explain the data worst,
// not at a residual they already explain (near zero: a duplicate that stays
// unused). The small floor keeps every kept row possible when all errors are 0.
at::Tensor sample_rows(const at::Tensor& rows, const at::Tensor& weight, const at::Tensor& error, int64_t count) {
  // Non-finite errors (a diverging run, stopped by the trainer's loss check) count as 0.
  const at::Tensor squared = torch::nan_to_num(weight * error.pow(2).sum(1), 0.0, 0.0, 0.0);  // (N), 0 where masked
  const at::Tensor chance = squared + weight * (1e-6 * squared.max()).clamp_min(1e-12);
  return rows.index_select(0, torch::multinomial(chance, count, /*replacement=*/true));
}

}  // namespace

void visit_fields(train::ConfigVisitor& v, QuantizerConfig& c) {
  v.field("layers", c.layers, "residual layers R");
  v.field("codebook_size", c.codebook_size, "codes per layer K");
  v.field("code_dim", c.code_dim, "width of a code = width of the latent");
  v.field("ema_decay", c.ema_decay, "decay of the codebooks' moving averages");
  v.field("commitment_weight", c.commitment_weight, "weight of the commitment loss");
  v.field("dead_code_threshold", c.dead_code_threshold, "average use per batch below which a code is reseeded");
  v.field("quantize_dropout", c.quantize_dropout, "chance per batch of training with only the first n layers");
}

void QuantizerConfig::validate() const {
  require(layers >= 1, "layers must be >= 1, got " + std::to_string(layers));
  require(codebook_size >= 1, "codebook_size must be >= 1, got " + std::to_string(codebook_size));
  require(code_dim >= 1, "code_dim must be >= 1, got " + std::to_string(code_dim));
  require(ema_decay >= 0.0 && ema_decay < 1.0, "ema_decay must be in [0, 1), got " + std::to_string(ema_decay));
  require(commitment_weight >= 0.0, "commitment_weight must be >= 0, got " + std::to_string(commitment_weight));
  require(dead_code_threshold >= 0.0, "dead_code_threshold must be >= 0, got " + std::to_string(dead_code_threshold));
  require(quantize_dropout >= 0.0 && quantize_dropout <= 1.0,
          "quantize_dropout must be in [0, 1], got " + std::to_string(quantize_dropout));
}

ResidualQuantizerImpl::ResidualQuantizerImpl(const QuantizerConfig& config) : config_(config) {
  config_.validate();
  const int64_t r = config_.layers, k = config_.codebook_size, c = config_.code_dim;
  codebooks_ = register_buffer("codebooks", torch::randn({r, k, c}));
  ema_counts_ = register_buffer("ema_counts", torch::ones({r, k}));
  ema_sums_ = register_buffer("ema_sums", codebooks_.clone());
  initialized_ = register_buffer("initialized", torch::zeros({}, torch::kBool));
}

QuantizerOutput ResidualQuantizerImpl::forward(const at::Tensor& latent, const at::Tensor& mask) {
  const int64_t layers = config_.layers, size = config_.codebook_size, dim = config_.code_dim;
  if (latent.dim() != 2 || latent.size(1) != dim) {
    throw std::invalid_argument("ResidualQuantizer: latent must be (N, " + std::to_string(dim) + "), got " +
                                std::to_string(latent.dim()) + "-D");
  }
  const int64_t rows = latent.size(0);
  if (mask.defined() && (mask.dim() != 1 || mask.size(0) != rows)) {
    throw std::invalid_argument("ResidualQuantizer: mask must be (N) = (" + std::to_string(rows) + ")");
  }
  const auto float_options = latent.options().dtype(codebooks_.scalar_type());
  const at::Tensor weight = mask.defined() ? mask.to(float_options) : torch::ones({rows}, float_options);  // (N)

  // Training: how many layers this batch uses (drawn on the CPU generator),
  // whether any row is kept (else nothing is learned), whether to seed the codebooks.
  int64_t used_layers = layers;
  bool update = false, seed = false;
  if (is_training()) {
    if (config_.quantize_dropout > 0.0 && layers > 1 &&
        torch::rand({1}, torch::kDouble).item<double>() < config_.quantize_dropout) {
      used_layers = torch::randint(1, layers + 1, {1}, torch::kLong).item<int64_t>();
    }
    bool initialized = true;
    if (rows > 0) {
      const at::Tensor flags = torch::stack({weight.sum() > 0, initialized_}).to(torch::kCPU);  // one sync
      update = flags[0].item<bool>();
      initialized = flags[1].item<bool>();
    } else {
      initialized = initialized_.item<bool>();
    }
    // Every rank seeds alike, from the rows of all of them (even one whose rows are all masked).
    seed = !initialized && (communicator_ != nullptr ? communicator_->any(update) : update);
  }

  at::Tensor codes = torch::full({rows, layers}, -1, latent.options().dtype(torch::kLong));
  at::Tensor perplexity = torch::zeros({layers}, float_options);
  at::Tensor quantized;
  {
    torch::NoGradGuard no_grad;
    const at::Tensor input = latent.detach().to(codebooks_.scalar_type());
    at::Tensor residual = input.clone();
    at::Tensor total = torch::zeros_like(input);
    const at::Tensor kept = weight.sum().clamp_min(1.0);
    for (int64_t r = 0; r < used_layers; ++r) {
      at::Tensor codebook = codebooks_[r];  // (K, C) view into the buffer
      if (seed) {
        const at::Tensor candidates = all_ranks(torch::cat({residual, weight.unsqueeze(1)}, 1));  // (N', C + 1)
        const at::Tensor candidate_rows = candidates.narrow(1, 0, dim);
        codebook.copy_(sample_rows(candidate_rows, candidates.select(1, dim), candidate_rows, size));
        ema_sums_[r].copy_(codebook);
        ema_counts_[r].fill_(1.0);
      }
      // Nearest code: argmin |x|² - 2 x·c + |c|² (|x|² is the same for every code).
      const at::Tensor distance =
          torch::addmm((codebook * codebook).sum(1).unsqueeze(0), residual, codebook.t(), /*beta=*/1, /*alpha=*/-2);
      const at::Tensor index = distance.argmin(1);  // (N)
      const at::Tensor chosen = codebook.index_select(0, index);
      codes.select(1, r).copy_(index);

      const at::Tensor counts = torch::zeros({size}, float_options).index_add_(0, index, weight);  // (K)
      const at::Tensor usage = counts / kept;
      perplexity.select(0, r).copy_(torch::exp(-(usage * torch::log(usage.clamp_min(1e-10))).sum()));

      if (update) {
        // Kept for update_codebooks(): the EMA moves once per optimizer step, from every part and rank.
        const at::Tensor sums = torch::zeros({size, dim}, float_options).index_add_(0, index, residual * weight.unsqueeze(1));
        if (!pending_counts_.defined()) {
          pending_counts_ = torch::zeros_like(ema_counts_);
          pending_sums_ = torch::zeros_like(ema_sums_);
          pending_rows_.assign(static_cast<size_t>(layers), {});
        }
        pending_counts_[r].add_(counts);
        pending_sums_[r].add_(sums);
        if (config_.dead_code_threshold > 0.0) {
          pending_rows_[static_cast<size_t>(r)].push_back(torch::cat({residual, residual - chosen, weight.unsqueeze(1)}, 1));
        }
      }
      total += chosen;
      residual -= chosen;
    }
    if (seed) initialized_.fill_(true);
    quantized = total.to(latent.scalar_type());
  }

  QuantizerOutput out;
  const at::Tensor squared_error = (latent - quantized).pow(2).mean(1);  // (N), gradient to the latent only
  out.commitment_loss = config_.commitment_weight * (squared_error * weight.to(latent.scalar_type())).sum() /
                        weight.sum().clamp_min(1.0).to(latent.scalar_type());
  out.quantized = latent + (quantized - latent).detach();  // straight-through
  out.codes = codes;
  out.perplexity = perplexity;
  return out;
}

at::Tensor ResidualQuantizerImpl::all_ranks(const at::Tensor& rows) const {
  return communicator_ != nullptr ? communicator_->gather_rows(rows) : rows;
}

bool ResidualQuantizerImpl::update_codebooks() {
  torch::NoGradGuard no_grad;
  if (communicator_ == nullptr && !pending_counts_.defined()) return false;
  if (!pending_counts_.defined()) {  // this rank kept no row: it still takes part in the sums
    pending_counts_ = torch::zeros_like(ema_counts_);
    pending_sums_ = torch::zeros_like(ema_sums_);
    pending_rows_.assign(static_cast<size_t>(config_.layers), {});
  }
  if (communicator_ != nullptr) {
    std::vector<at::Tensor> statistics{pending_counts_, pending_sums_};
    communicator_->sum(statistics);
  }
  const int64_t size = config_.codebook_size, dim = config_.code_dim;
  const at::Tensor layer_used = (pending_counts_.sum(1) > 0).to(torch::kCPU);  // (R), the same on every rank
  bool updated = false;
  for (int64_t r = 0; r < config_.layers; ++r) {
    if (!layer_used[r].item<bool>()) continue;
    updated = true;
    at::Tensor codebook = codebooks_[r];
    const double decay = config_.ema_decay;
    ema_counts_[r].mul_(decay).add_(pending_counts_[r], 1.0 - decay);
    ema_sums_[r].mul_(decay).add_(pending_sums_[r], 1.0 - decay);
    const at::Tensor total_count = ema_counts_[r].sum();
    const at::Tensor smoothed = (ema_counts_[r] + kLaplaceEpsilon) / (total_count + size * kLaplaceEpsilon) * total_count;
    codebook.copy_(ema_sums_[r] / smoothed.unsqueeze(1));
    if (config_.dead_code_threshold <= 0.0) continue;
    // Codes used less than the threshold restart at kept residuals of this layer,
    // preferring the rows its codes serve worst.
    const at::Tensor dead = (ema_counts_[r] < config_.dead_code_threshold).unsqueeze(1);  // (K, 1)
    if (!dead.any().item<bool>()) continue;
    std::vector<at::Tensor>& kept_rows = pending_rows_[static_cast<size_t>(r)];
    const at::Tensor local = kept_rows.empty() ? torch::zeros({0, 2 * dim + 1}, ema_sums_.options()) : torch::cat(kept_rows);
    const at::Tensor candidates = all_ranks(local);  // (N, 2C + 1): residual, its error, weight
    const at::Tensor fresh =
        sample_rows(candidates.narrow(1, 0, dim), candidates.select(1, 2 * dim), candidates.narrow(1, dim, dim), size);
    codebook.copy_(torch::where(dead, fresh, codebook));
    ema_sums_[r].copy_(torch::where(dead, fresh * config_.dead_code_threshold, ema_sums_[r]));
    ema_counts_[r].masked_fill_(dead.squeeze(1), config_.dead_code_threshold);
  }
  if (communicator_ != nullptr) {
    // Rank 0's draws win: ranks whose generators drifted apart (unequal parts) keep one codebook.
    std::vector<at::Tensor> state{codebooks_, ema_counts_, ema_sums_};
    communicator_->broadcast(state, 0);
  }
  pending_counts_ = at::Tensor();
  pending_sums_ = at::Tensor();
  pending_rows_.clear();
  return updated;
}

at::Tensor ResidualQuantizerImpl::codes_to_latent(const at::Tensor& codes) {
  const int64_t size = config_.codebook_size, dim = config_.code_dim;
  if (codes.dim() < 1 || codes.size(-1) > config_.layers) {
    throw std::invalid_argument("ResidualQuantizer::codes_to_latent: codes must be (..., R') with R' <= " +
                                std::to_string(config_.layers));
  }
  torch::NoGradGuard no_grad;
  const int64_t used = codes.size(-1);
  const int64_t rows = used == 0 ? 0 : codes.numel() / used;
  const at::Tensor flat = codes.reshape({rows, used}).to(torch::kLong);  // (N, R')
  if (((flat >= size) | (flat < -1)).any().item<bool>()) {
    throw std::invalid_argument("ResidualQuantizer::codes_to_latent: codes must be in [-1, " +
                                std::to_string(size - 1) + "]");
  }
  const at::Tensor layer_start = torch::arange(used, flat.options()).mul_(size);  // (R') offset of each codebook
  const at::Tensor index = (flat.clamp_min(0) + layer_start).reshape({-1});
  const at::Tensor vectors =
      codebooks_.narrow(0, 0, used).reshape({used * size, dim}).index_select(0, index).view({rows, used, dim});
  const at::Tensor used_mask = (flat >= 0).unsqueeze(-1).to(vectors.scalar_type());  // -1: layer skipped
  std::vector<int64_t> shape = codes.sizes().vec();
  shape.back() = dim;
  return (vectors * used_mask).sum(1).view(shape);
}

}  // namespace nec::tat
