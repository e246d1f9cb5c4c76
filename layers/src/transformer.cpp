// Pre-norm transformer layers with padding masks.
#include "nec/layers/transformer.h"

#include "nec/layers/batched_matmul.h"

#include <torch/torch.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace nec::layers {

void TransformerOptions::validate() const {
  if (dim < 1 || heads < 1 || dim % heads != 0) {
    throw std::invalid_argument("heads (" + std::to_string(heads) + ") must be >= 1 and divide dim (" +
                                std::to_string(dim) + ")");
  }
  if (feedforward < 1) throw std::invalid_argument("feedforward must be >= 1");
  if (!(dropout >= 0 && dropout < 1)) throw std::invalid_argument("dropout must be in [0, 1)");
}

at::Tensor padding_bias(const at::Tensor& mask) {
  const at::Tensor bias = torch::zeros(mask.sizes(), mask.options().dtype(torch::kFloat32))
                              .masked_fill_(mask.logical_not(), kMaskedScore);
  return bias.view({mask.size(0), 1, 1, mask.size(1)});
}

at::Tensor masked_mean(const at::Tensor& x, const at::Tensor& mask) {
  const at::Tensor weights = mask.to(x.scalar_type()).unsqueeze(-1);  // (B, N, 1)
  return (x * weights).sum(1) / weights.sum(1).clamp_min(1.0);
}

at::Tensor multi_head_attention(const at::Tensor& qkv, int64_t heads, const at::Tensor& bias) {
  const int64_t b = qkv.size(0), n = qkv.size(1), d = qkv.size(2) / 3, head_dim = d / heads;
  // One copy into (3, B * H, N, Dh) and the keys transposed in memory: bmm on strided operands runs one small
  // BLAS call per matrix through a slow path (twice the time for 24-token sequences).
  const at::Tensor split = qkv.view({b, n, 3, heads, head_dim}).permute({2, 0, 3, 1, 4}).reshape({3, b * heads, n, head_dim});
  const at::Tensor keys = split[1].transpose(1, 2).contiguous();
  at::Tensor scores = batched_matmul(split[0] * (1.0 / std::sqrt(static_cast<double>(head_dim))), keys).view({b, heads, n, n});
  if (bias.defined()) scores = scores + bias;
  const at::Tensor mixed = batched_matmul(torch::softmax(scores, -1).view({b * heads, n, n}), split[2]);  // (B * H, N, Dh)
  return mixed.view({b, heads, n, head_dim}).permute({0, 2, 1, 3}).reshape({b, n, d});
}

TransformerLayerImpl::TransformerLayerImpl(const TransformerOptions& options) : heads_(options.heads) {
  options.validate();
  const int64_t dim = options.dim;
  attention_norm_ = register_module("attention_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({dim})));
  qkv_ = register_module("qkv", torch::nn::Linear(dim, 3 * dim));
  out_ = register_module("out", torch::nn::Linear(dim, dim));
  ffn_norm_ = register_module("ffn_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({dim})));
  ffn_in_ = register_module("ffn_in", torch::nn::Linear(dim, options.feedforward));
  ffn_out_ = register_module("ffn_out", torch::nn::Linear(options.feedforward, dim));
  dropout_ = register_module("dropout", torch::nn::Dropout(options.dropout));
}

at::Tensor TransformerLayerImpl::forward(const at::Tensor& x, const at::Tensor& bias) {
  const at::Tensor mixed = multi_head_attention(qkv_(attention_norm_(x)), heads_, bias);
  const at::Tensor attended = x + dropout_(out_(mixed));
  return attended + ffn_out_(dropout_(torch::gelu(ffn_in_(ffn_norm_(attended)))));
}

TransformerStackImpl::TransformerStackImpl(const TransformerOptions& options, int64_t layers) {
  if (layers < 1) throw std::invalid_argument("layers must be >= 1, got " + std::to_string(layers));
  layers_ = register_module("layers", torch::nn::ModuleList());
  for (int64_t i = 0; i < layers; ++i) layers_->push_back(TransformerLayer(options));
  norm_ = register_module("norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({options.dim})));
}

at::Tensor TransformerStackImpl::forward(const at::Tensor& x, const at::Tensor& bias) {
  at::Tensor y = x;
  for (const auto& layer : *layers_) y = layer->as<TransformerLayerImpl>()->forward(y, bias);
  return norm_(y);
}

}  // namespace nec::layers
