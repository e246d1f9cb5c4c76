// Pre-norm transformer layers over token sequences with padding masks, the
// block every sequence model of nec is built from.
//
//   TransformerOptions options;  options.dim = 128;  options.heads = 4;
//   TransformerStack stack(options, /*layers=*/2);
//   at::Tensor bias = padding_bias(mask);                 // mask (B, N) bool, true for real tokens
//   at::Tensor y = stack->forward(x, bias);               // x (B, N, D) -> (B, N, D)
//   at::Tensor pooled = masked_mean(y, mask);             // (B, D)
//
// A layer is x + MHA(LN(x)), then x + FFN(LN(x)) (GELU, dropout after the
// attention and inside the FFN); the stack ends with a LayerNorm. Masked keys
// get an additive bias of kMaskedScore, so a token's output does not depend on
// what sits at padded positions.
#pragma once

#include <ATen/core/Tensor.h>
#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/dropout.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/modules/normalization.h>
#include <torch/nn/pimpl.h>

#include <cstdint>

namespace nec::layers {

// The attention score of a masked key: exp() of it is 0 in float32.
constexpr double kMaskedScore = -1e9;

struct TransformerOptions {
  int64_t dim = 128;          // token width D, e.g. 128
  int64_t heads = 4;          // attention heads; must divide dim
  int64_t feedforward = 256;  // FFN hidden width, e.g. 2 * dim
  double dropout = 0.1;       // after attention and in the FFN, training only

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

// (B, N) bool, true for real tokens -> (B, 1, 1, N) float additive bias over the keys.
at::Tensor padding_bias(const at::Tensor& mask);

// Mean over the real tokens: x (B, N, D), mask (B, N) bool -> (B, D); zero for an item without tokens.
at::Tensor masked_mean(const at::Tensor& x, const at::Tensor& mask);

// Scaled dot-product attention of `heads` heads: qkv (B, N, 3 D) the queries,
// keys and values side by side; bias broadcastable to (B, H, N, N), or
// undefined. -> (B, N, D), the heads' outputs side by side (before the output projection).
at::Tensor multi_head_attention(const at::Tensor& qkv, int64_t heads, const at::Tensor& bias);

class TransformerLayerImpl : public torch::nn::Module {
 public:
  explicit TransformerLayerImpl(const TransformerOptions& options);
  // x (B, N, D); bias broadcastable to (B, H, N, N) (e.g. padding_bias), or undefined. -> (B, N, D)
  at::Tensor forward(const at::Tensor& x, const at::Tensor& bias);

 private:
  int64_t heads_;
  torch::nn::LayerNorm attention_norm_{nullptr}, ffn_norm_{nullptr};
  torch::nn::Linear qkv_{nullptr}, out_{nullptr}, ffn_in_{nullptr}, ffn_out_{nullptr};
  torch::nn::Dropout dropout_{nullptr};
};
TORCH_MODULE(TransformerLayer);

class TransformerStackImpl : public torch::nn::Module {
 public:
  TransformerStackImpl(const TransformerOptions& options, int64_t layers);
  // x (B, N, D), bias as for a layer -> LN(layers(x)) (B, N, D)
  at::Tensor forward(const at::Tensor& x, const at::Tensor& bias);

 private:
  torch::nn::ModuleList layers_{nullptr};
  torch::nn::LayerNorm norm_{nullptr};
};
TORCH_MODULE(TransformerStack);

}  // namespace nec::layers
