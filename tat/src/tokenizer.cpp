// TAT (NECromancer 4.3): the virtual-joint spatio-temporal tokenizer and the
// zero-padding RVQ-VAE baseline, sharing the temporal blocks and the quantizer.
#include "nec/tat/tokenizer.h"

#include "nec/layers/batched_matmul.h"
#include "nec/tat/model_space.h"
#include "nec/train/config_fields.h"

#include <torch/torch.h>

#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace nec::tat {
namespace {

constexpr int64_t kResidualDilation = 3;  // dilation of the ResNet1D unit's 3-tap conv
constexpr int64_t kFeedForwardMult = 2;   // attention FFN hidden width = 2 * dim
constexpr double kMaskedScore = -1e9;     // attention score of a padded key (finite: no NaN)

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("TatConfig: " + message);
}

bool is_nec(TokenizerKind kind) { return kind != TokenizerKind::ZeroPadRvq; }

torch::nn::Conv1d conv1d(int64_t in, int64_t out, int64_t kernel, int64_t stride = 1, int64_t padding = 0,
                         int64_t dilation = 1) {
  return torch::nn::Conv1d(
      torch::nn::Conv1dOptions(in, out, kernel).stride(stride).padding(padding).dilation(dilation));
}


// The root's rise per frame at the path's scale, kRootMotionScale (y_t − y_{t−1}), from model-space rows
// (B, T, N, kModelChannels) whose joint 0 is the root: (B, T, 1, 1), frame 0's 0.
at::Tensor root_rise(const at::Tensor& model) {
  const at::Tensor height = model.narrow(2, 0, 1).narrow(-1, 1, 1);  // (B, T, 1, 1)
  const int64_t later = height.size(1) - 1;
  return torch::constant_pad_nd(height.narrow(1, 1, later) - height.narrow(1, 0, later), {0, 0, 0, 0, 1, 0}) *
         kRootMotionScale;
}

// The model-space row of a joint at rest (identity rot6D), which the decoders
// predict offsets from: (kModelChannels).
at::Tensor rest_pose_features(const at::TensorOptions& options) {
  at::Tensor rest = torch::zeros({kModelChannels}, options);
  rest.narrow(0, 3, 1).fill_(1.0);
  rest.narrow(0, 7, 1).fill_(1.0);
  return rest;
}

// A skeleton's OwO joint embeddings share a large common part; what tells its joints apart is the rest.
// Centred over the skeleton's real joints and scaled to unit RMS: (B, J, E), mask (B, J) bool -> (B, J, E),
// zero at padded joints.
at::Tensor distinct_joint_embeddings(const at::Tensor& embeddings, const at::Tensor& joint_mask) {
  const at::Tensor real = joint_mask.to(embeddings.scalar_type()).unsqueeze(-1);  // (B, J, 1)
  const at::Tensor count = real.sum(1, true).clamp_min(1.0);                       // (B, 1, 1)
  const at::Tensor centred = (embeddings - (embeddings * real).sum(1, true) / count) * real;
  const at::Tensor mean_square = centred.pow(2).sum({1, 2}, true) / (count * static_cast<double>(embeddings.size(2)));
  return centred * mean_square.clamp_min(1e-12).rsqrt();
}

// ResNet1D unit (as T2M-GPT): x + conv1x1(ReLU(dilated conv3(ReLU(x)))). (N, D, T) -> (N, D, T).
class ResidualUnitImpl : public torch::nn::Module {
 public:
  explicit ResidualUnitImpl(int64_t dim) {
    dilated_ = register_module("dilated", conv1d(dim, dim, 3, 1, kResidualDilation, kResidualDilation));
    pointwise_ = register_module("pointwise", conv1d(dim, dim, 1));
  }
  at::Tensor forward(const at::Tensor& x) { return x + pointwise_(torch::relu(dilated_(torch::relu(x)))); }

 private:
  torch::nn::Conv1d dilated_{nullptr}, pointwise_{nullptr};
};
TORCH_MODULE(ResidualUnit);

// Temporal downsampling by 2: conv (kernel 4, stride 2) + ResNet1D. (N, D, T) -> (N, D, T / 2).
class DownBlockImpl : public torch::nn::Module {
 public:
  explicit DownBlockImpl(int64_t dim) {
    conv_ = register_module("conv", conv1d(dim, dim, 4, 2, 1));
    residual_ = register_module("residual", ResidualUnit(dim));
  }
  at::Tensor forward(const at::Tensor& x) { return residual_(conv_(x)); }

 private:
  torch::nn::Conv1d conv_{nullptr};
  ResidualUnit residual_{nullptr};
};
TORCH_MODULE(DownBlock);

// Temporal upsampling by 2: nearest neighbour, conv (kernel 3) + ResNet1D. (N, D, T) -> (N, D, 2 T).
class UpBlockImpl : public torch::nn::Module {
 public:
  explicit UpBlockImpl(int64_t dim) {
    conv_ = register_module("conv", conv1d(dim, dim, 3, 1, 1));
    residual_ = register_module("residual", ResidualUnit(dim));
  }
  at::Tensor forward(const at::Tensor& x) {
    const at::Tensor repeated = x.unsqueeze(-1).expand({x.size(0), x.size(1), x.size(2), 2}).reshape(
        {x.size(0), x.size(1), 2 * x.size(2)});
    return residual_(conv_(repeated));
  }

 private:
  torch::nn::Conv1d conv_{nullptr};
  ResidualUnit residual_{nullptr};
};
TORCH_MODULE(UpBlock);

// Pre-norm transformer encoder layer over the tokens of each time step:
// x + MHA(LN(x)), then x + FFN(LN(x)). Keys are masked by an additive bias.
class SpatialAttentionImpl : public torch::nn::Module {
 public:
  SpatialAttentionImpl(int64_t dim, int64_t heads) : heads_(heads) {
    attention_norm_ = register_module("attention_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({dim})));
    qkv_ = register_module("qkv", torch::nn::Linear(dim, 3 * dim));
    out_ = register_module("out", torch::nn::Linear(dim, dim));
    ffn_norm_ = register_module("ffn_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({dim})));
    ffn_in_ = register_module("ffn_in", torch::nn::Linear(dim, kFeedForwardMult * dim));
    ffn_out_ = register_module("ffn_out", torch::nn::Linear(kFeedForwardMult * dim, dim));
  }

  // x (B, T, N, D); key_bias (B, 1, 1, 1, N) float, 0 for real keys and kMaskedScore for padding.
  // Returns (B, T, N, D), or (B, T, 1, D) for token 0 alone when first_token_only
  // (the encoder's last layer: only the virtual joint goes on).
  at::Tensor forward(const at::Tensor& x, const at::Tensor& key_bias, bool first_token_only = false) {
    const int64_t b = x.size(0), t = x.size(1), n = x.size(2), d = x.size(3), head_dim = d / heads_;
    const int64_t queries = first_token_only ? 1 : n;
    const at::Tensor normalized = attention_norm_(x);
    // (3, B, T, H, N, Dh) for the keys and values of every token.
    const at::Tensor qkv = qkv_(normalized).view({b, t, n, 3, heads_, head_dim}).permute({3, 0, 1, 4, 2, 5});
    const at::Tensor query = qkv[0].narrow(3, 0, queries) * (1.0 / std::sqrt(static_cast<double>(head_dim)));
    const int64_t groups = b * t * heads_;  // one small product per frame and head
    const at::Tensor scores =
        layers::batched_matmul(query.reshape({groups, queries, head_dim}),
                               qkv[1].transpose(-1, -2).reshape({groups, head_dim, n}))
            .view({b, t, heads_, queries, n}) +
        key_bias;  // (B, T, H, Q, N)
    const at::Tensor mixed = layers::batched_matmul(torch::softmax(scores, -1).view({groups, queries, n}),
                                                    qkv[2].reshape({groups, n, head_dim}))
                                 .view({b, t, heads_, queries, head_dim});  // (B, T, H, Q, Dh)
    const at::Tensor attended =
        x.narrow(2, 0, queries) + out_(mixed.permute({0, 1, 3, 2, 4}).reshape({b, t, queries, d}));
    return attended + ffn_out_(torch::gelu(ffn_in_(ffn_norm_(attended))));
  }

 private:
  int64_t heads_;
  torch::nn::LayerNorm attention_norm_{nullptr}, ffn_norm_{nullptr};
  torch::nn::Linear qkv_{nullptr}, out_{nullptr}, ffn_in_{nullptr}, ffn_out_{nullptr};
};
TORCH_MODULE(SpatialAttention);

// Applies a temporal block to every token sequence: (B, T, N, D) -> (B, T', N, D).
template <typename Block>
at::Tensor per_token(const std::shared_ptr<Block>& block, const at::Tensor& tokens) {
  const int64_t b = tokens.size(0), t = tokens.size(1), n = tokens.size(2), d = tokens.size(3);
  const at::Tensor sequences = tokens.permute({0, 2, 3, 1}).reshape({b * n, d, t});
  const at::Tensor out = block->forward(sequences);
  return out.view({b, n, d, out.size(2)}).permute({0, 3, 1, 2}).contiguous();
}

// (B, J) joint mask -> (B, 1, 1, 1, 1 + J) additive key bias; token 0 (the virtual joint) is never masked.
at::Tensor key_bias(const at::Tensor& joint_mask, const at::TensorOptions& options) {
  const at::Tensor keep = torch::cat({torch::ones({joint_mask.size(0), 1}, joint_mask.options()), joint_mask}, 1);
  const at::Tensor bias = torch::zeros(keep.sizes(), options).masked_fill_(keep.logical_not(), kMaskedScore);
  return bias.view({keep.size(0), 1, 1, 1, keep.size(1)});
}

// (B, J) joint mask -> (B, 1, 1, 1 + J, 1 + J) additive bias for the decoder's attention: the joints read
// every real token, the virtual joint (token 0) only itself. What the decoder reads from the virtual joint, the
// root's path, then comes from the tokens alone and is the same on every target skeleton.
at::Tensor decoder_attention_bias(const at::Tensor& joint_mask, const at::TensorOptions& options) {
  const int64_t b = joint_mask.size(0), n = joint_mask.size(1) + 1;
  at::Tensor bias = key_bias(joint_mask, options).expand({b, 1, 1, n, n}).clone();
  bias.narrow(3, 0, 1).narrow(4, 1, n - 1).fill_(kMaskedScore);
  return bias;
}

}  // namespace

namespace detail {

// One half of a tokenizer. joint_mask (B, J) bool; joint_embeddings (B, J, E) or undefined.
class EncoderImpl : public torch::nn::Module {
 public:
  // model-space features (B, T, J, kModelChannels) -> latent (B, T / r, C)
  virtual at::Tensor forward(const at::Tensor& features, const at::Tensor& joint_mask,
                             const at::Tensor& joint_embeddings) = 0;
};

class DecoderImpl : public torch::nn::Module {
 public:
  // quantized (B, S, C) -> model-space features (B, S * r, J, kModelChannels), zero at padded joints
  virtual at::Tensor forward(const at::Tensor& quantized, const at::Tensor& joint_mask,
                             const at::Tensor& joint_embeddings) = 0;
};

}  // namespace detail

namespace {

// NEC encoder: per joint MLP(Θ) + Proj(h), the virtual joint as token 0, then
// per block a temporal block per token and spatial attention over the tokens.
class NecEncoderImpl : public detail::EncoderImpl {
 public:
  explicit NecEncoderImpl(const TatConfig& config) {
    const int64_t d = config.dim;
    // Layers built in order (argument evaluation order is unspecified, and it
    // decides the random initial weights).
    torch::nn::Linear first(kModelChannels, d);
    torch::nn::Linear second(d, d);
    input_ = register_module("input", torch::nn::Sequential(first, torch::nn::ReLU(), second));
    embedding_ = register_module("embedding", torch::nn::Linear(config.joint_embedding_dim, d));
    rise_ = register_module("rise", torch::nn::Linear(1, d));
    virtual_joint_ = register_parameter("virtual_joint", torch::randn({d}) * 0.02);
    temporal_ = register_module("temporal", torch::nn::ModuleList());
    spatial_ = register_module("spatial", torch::nn::ModuleList());
    for (int64_t block = 0; block < config.blocks; ++block) {
      temporal_->push_back(DownBlock(d));
      for (int64_t layer = 0; layer < config.attention_layers; ++layer) {
        spatial_->push_back(SpatialAttention(d, config.heads));
      }
    }
    attention_layers_ = config.attention_layers;
    // Pre-norm layers leave the residual stream unnormalized: normalize it before the quantizer.
    final_norm_ = register_module("final_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
    to_latent_ = register_module("to_latent", torch::nn::Linear(d, config.quantizer.code_dim));
  }

  at::Tensor forward(const at::Tensor& features, const at::Tensor& joint_mask,
                     const at::Tensor& joint_embeddings) override {
    const at::Tensor joints = input_->forward(features) + embedding_(joint_embeddings).unsqueeze(1);  // (B, T, J, D)
    // The learnt vector plus the root's own input (through attention alone the root trajectory was lost) and
    // its rise per frame, scaled as the horizontal path is (beside its height, a jump's rise was lost).
    const at::Tensor virtual_joint =
        virtual_joint_.view({1, 1, 1, -1}) + joints.narrow(2, 0, 1) + rise_(root_rise(features));  // (B, T, 1, D)
    at::Tensor tokens = torch::cat({virtual_joint, joints}, 2);
    const at::Tensor bias = key_bias(joint_mask, tokens.options());
    const size_t blocks = temporal_->size();
    for (size_t block = 0; block < blocks; ++block) {
      tokens = per_token(temporal_->ptr<DownBlockImpl>(block), tokens);
      for (int64_t layer = 0; layer < attention_layers_; ++layer) {
        // The very last layer only needs the virtual joint's output.
        const bool last = block + 1 == blocks && layer + 1 == attention_layers_;
        tokens = spatial_->ptr<SpatialAttentionImpl>(block * attention_layers_ + layer)->forward(tokens, bias, last);
      }
    }
    return to_latent_(final_norm_(tokens.select(2, 0)));  // the virtual joint, (B, T / r, C)
  }

 private:
  int64_t attention_layers_ = 1;
  torch::nn::Sequential input_{nullptr};
  torch::nn::LayerNorm final_norm_{nullptr};
  torch::nn::Linear embedding_{nullptr}, rise_{nullptr}, to_latent_{nullptr};
  at::Tensor virtual_joint_;  // (D)
  torch::nn::ModuleList temporal_{nullptr}, spatial_{nullptr};
};

// NEC decoder: z_t as the virtual joint, MLP([z_t ‖ h_j]) per joint, then per
// block spatial attention and a temporal upsampling block per token, linear to kModelChannels per joint. The
// root's path in model space (Δx', Δz', yaw rate) is read from the virtual joint, which attends to itself
// only, so the same tokens give the same path, in body sizes, on every skeleton (docs/tokenizer.md).
class NecDecoderImpl : public detail::DecoderImpl {
 public:
  explicit NecDecoderImpl(const TatConfig& config) {
    const int64_t d = config.dim, c = config.quantizer.code_dim;
    virtual_from_latent_ = register_module("virtual_from_latent", torch::nn::Linear(c, d));
    // First layer of MLP([z ‖ h]) split in its z and h columns: no (B, S, J, C + E) concatenation.
    joint_from_latent_ = register_module("joint_from_latent", torch::nn::Linear(c, d));
    joint_from_embedding_ = register_module(
        "joint_from_embedding", torch::nn::Linear(torch::nn::LinearOptions(config.joint_embedding_dim, d).bias(false)));
    joint_hidden_ = register_module("joint_hidden", torch::nn::Linear(d, d));
    spatial_ = register_module("spatial", torch::nn::ModuleList());
    temporal_ = register_module("temporal", torch::nn::ModuleList());
    for (int64_t block = 0; block < config.blocks; ++block) {
      for (int64_t layer = 0; layer < config.attention_layers; ++layer) {
        spatial_->push_back(SpatialAttention(d, config.heads));
      }
      temporal_->push_back(UpBlock(d));
    }
    attention_layers_ = config.attention_layers;
    output_ = register_module("output", torch::nn::Linear(d, kModelChannels));
    path_ = register_module("path", torch::nn::Linear(d, 4));
  }

  at::Tensor forward(const at::Tensor& quantized, const at::Tensor& joint_mask,
                     const at::Tensor& joint_embeddings) override {
    const int64_t joints = joint_mask.size(1);
    const at::Tensor virtual_joint = virtual_from_latent_(quantized).unsqueeze(2);  // (B, S, 1, D)
    const at::Tensor joint_features = joint_hidden_(torch::relu(
        joint_from_latent_(quantized).unsqueeze(2) + joint_from_embedding_(joint_embeddings).unsqueeze(1)));
    at::Tensor tokens = torch::cat({virtual_joint, joint_features}, 2);  // (B, S, 1 + J, D)
    const at::Tensor bias = decoder_attention_bias(joint_mask, tokens.options());
    const size_t blocks = temporal_->size();
    for (size_t block = 0; block < blocks; ++block) {
      for (int64_t layer = 0; layer < attention_layers_; ++layer) {
        tokens = spatial_->ptr<SpatialAttentionImpl>(block * attention_layers_ + layer)->forward(tokens, bias);
      }
      tokens = per_token(temporal_->ptr<UpBlockImpl>(block), tokens);
    }
    const at::Tensor out = output_(tokens.narrow(2, 1, joints)) + rest_pose_features(tokens.options());
    const at::Tensor path = path_(tokens.select(2, 0));  // (B, T, 4): Δx', Δz', yaw rate, rise
    const at::Tensor root = out.select(2, 0);           // (B, T, kModelChannels): the height's level and R̃ stay the root's
    // The height: the level the root joint reads (it knows the skeleton: a dog stands lower than a person)
    // averaged over the window, moved up and down by the rise the virtual joint reads from the tokens.
    const at::Tensor climb = (path.narrow(-1, 3, 1).narrow(1, 1, path.size(1) - 1) / kRootMotionScale).cumsum(1);
    const at::Tensor shape = torch::constant_pad_nd(climb, {0, 0, 1, 0});  // (B, T, 1), frame 0's 0
    const at::Tensor height = root.narrow(-1, 1, 1).mean(1, true) + shape - shape.mean(1, true);
    const at::Tensor root_with_path = torch::cat({path.narrow(-1, 0, 1), height, path.narrow(-1, 1, 1),
                                                  root.narrow(-1, 3, 6), path.narrow(-1, 2, 1)},
                                                 -1);
    const at::Tensor joined = torch::cat({root_with_path.unsqueeze(2), out.narrow(2, 1, joints - 1)}, 2);
    return joined * joint_mask.view({joint_mask.size(0), 1, joints, 1}).to(joined.scalar_type());
  }

 private:
  int64_t attention_layers_ = 1;
  torch::nn::Linear virtual_from_latent_{nullptr}, joint_from_latent_{nullptr}, joint_from_embedding_{nullptr},
      joint_hidden_{nullptr}, output_{nullptr}, path_{nullptr};
  torch::nn::ModuleList spatial_{nullptr}, temporal_{nullptr};
};

// Zero-padding baseline encoder: (B, T, J, kModelChannels) -> channels (B, kModelChannels max_joints, T),
// conv 3, the same temporal blocks, conv 3 to the latent width.
class PaddedEncoderImpl : public detail::EncoderImpl {
 public:
  explicit PaddedEncoderImpl(const TatConfig& config) : max_joints_(config.max_joints) {
    const int64_t d = config.dim;
    input_ = register_module("input", conv1d(kModelChannels * max_joints_, d, 3, 1, 1));
    temporal_ = register_module("temporal", torch::nn::ModuleList());
    for (int64_t block = 0; block < config.blocks; ++block) temporal_->push_back(DownBlock(d));
    to_latent_ = register_module("to_latent", conv1d(d, config.quantizer.code_dim, 3, 1, 1));
  }

  at::Tensor forward(const at::Tensor& features, const at::Tensor& joint_mask, const at::Tensor&) override {
    const int64_t b = features.size(0), t = features.size(1), joints = features.size(2);
    const at::Tensor real = features * joint_mask.view({b, 1, joints, 1}).to(features.scalar_type());
    const at::Tensor padded = torch::constant_pad_nd(real, {0, 0, 0, max_joints_ - joints});  // (B, T, Jmax, ·)
    at::Tensor x = torch::relu(input_(padded.view({b, t, kModelChannels * max_joints_}).transpose(1, 2)));
    for (size_t block = 0; block < temporal_->size(); ++block) x = temporal_->ptr<DownBlockImpl>(block)->forward(x);
    return to_latent_(x).transpose(1, 2).contiguous();  // (B, T / r, C)
  }

 private:
  int64_t max_joints_;
  torch::nn::Conv1d input_{nullptr}, to_latent_{nullptr};
  torch::nn::ModuleList temporal_{nullptr};
};

// Zero-padding baseline decoder, the encoder mirrored; output cropped to the batch's J.
class PaddedDecoderImpl : public detail::DecoderImpl {
 public:
  explicit PaddedDecoderImpl(const TatConfig& config) : max_joints_(config.max_joints) {
    const int64_t d = config.dim;
    from_latent_ = register_module("from_latent", conv1d(config.quantizer.code_dim, d, 3, 1, 1));
    temporal_ = register_module("temporal", torch::nn::ModuleList());
    for (int64_t block = 0; block < config.blocks; ++block) temporal_->push_back(UpBlock(d));
    output_ = register_module("output", conv1d(d, kModelChannels * max_joints_, 3, 1, 1));
  }

  at::Tensor forward(const at::Tensor& quantized, const at::Tensor& joint_mask, const at::Tensor&) override {
    const int64_t b = quantized.size(0), joints = joint_mask.size(1);
    at::Tensor x = torch::relu(from_latent_(quantized.transpose(1, 2)));
    for (size_t block = 0; block < temporal_->size(); ++block) x = temporal_->ptr<UpBlockImpl>(block)->forward(x);
    const at::Tensor channels = output_(x).transpose(1, 2);  // (B, T, kModelChannels Jmax)
    const int64_t t = channels.size(1);
    const at::Tensor out = channels.reshape({b, t, max_joints_, kModelChannels}).narrow(2, 0, joints) +
                           rest_pose_features(channels.options());
    return out * joint_mask.view({b, 1, joints, 1}).to(out.scalar_type());
  }

 private:
  int64_t max_joints_;
  torch::nn::Conv1d from_latent_{nullptr}, output_{nullptr};
  torch::nn::ModuleList temporal_{nullptr};
};

void check_input(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("Tokenizer: " + message);
}

std::string shape_of(const at::Tensor& x) {
  if (!x.defined()) return "undefined";
  std::ostringstream out;
  out << x.sizes();
  return out.str();
}

}  // namespace

std::string to_string(TokenizerKind kind) {
  switch (kind) {
    case TokenizerKind::NecRvq: return "nec-rvq";
    case TokenizerKind::NecVq: return "nec-vq";
    case TokenizerKind::ZeroPadRvq: return "zero-pad-rvq";
  }
  throw std::invalid_argument("to_string: unknown TokenizerKind");
}

TokenizerKind tokenizer_kind_from_string(const std::string& name) {
  for (TokenizerKind kind : {TokenizerKind::NecRvq, TokenizerKind::NecVq, TokenizerKind::ZeroPadRvq}) {
    if (to_string(kind) == name) return kind;
  }
  throw std::invalid_argument("unknown tokenizer kind '" + name + "' (expected nec-rvq, nec-vq or zero-pad-rvq)");
}

void visit_fields(train::ConfigVisitor& v, TatConfig& c) {
  v.choice("kind", c.kind, {TokenizerKind::NecRvq, TokenizerKind::NecVq, TokenizerKind::ZeroPadRvq},
           [](TokenizerKind kind) { return to_string(kind); }, "the tokenizer or a baseline");
  v.field("joint_embedding_dim", c.joint_embedding_dim, "width of the OwO joint embeddings (set from the OwO checkpoint)");
  v.field("dim", c.dim, "width of the per-joint features");
  v.field("blocks", c.blocks, "spatio-temporal blocks; time is downsampled by 2^blocks");
  v.field("attention_layers", c.attention_layers, "spatial transformer layers per block");
  v.field("heads", c.heads, "attention heads; must divide dim");
  v.field("max_joints", c.max_joints, "zero-pad-rvq only: joints of the padded input; 0 = the cache's largest");
  v.object("quantizer", c.quantizer, "the residual vector quantizer");
}

void TatConfig::validate() const {
  require(dim >= 1, "dim must be >= 1, got " + std::to_string(dim));
  require(blocks >= 1 && blocks <= 16, "blocks must be in [1, 16], got " + std::to_string(blocks));
  quantizer.validate();
  if (is_nec(kind)) {
    require(joint_embedding_dim >= 1, "joint_embedding_dim must be >= 1, got " + std::to_string(joint_embedding_dim));
    require(attention_layers >= 1, "attention_layers must be >= 1 (the virtual joint sees the joints only "
                                   "through attention), got " + std::to_string(attention_layers));
    require(heads >= 1 && dim % heads == 0,
            "heads must divide dim, got heads = " + std::to_string(heads) + ", dim = " + std::to_string(dim));
  }
  if (kind == TokenizerKind::NecVq) {
    require(quantizer.layers == 1,
            "nec-vq uses a single codebook: quantizer.layers must be 1, got " + std::to_string(quantizer.layers));
  }
  if (kind == TokenizerKind::ZeroPadRvq) {
    require(max_joints >= 1, "zero-pad-rvq needs max_joints >= 1 (the padded joint count), got " +
                                 std::to_string(max_joints));
  }
}

std::string TatConfig::to_string() const {
  std::ostringstream out;
  out << "TatConfig(kind=" << nec::tat::to_string(kind) << ", joint_embedding_dim=" << joint_embedding_dim
      << ", dim=" << dim << ", blocks=" << blocks << ", attention_layers=" << attention_layers << ", heads=" << heads
      << ", max_joints=" << max_joints << ", quantizer.layers=" << quantizer.layers
      << ", quantizer.codebook_size=" << quantizer.codebook_size << ", quantizer.code_dim=" << quantizer.code_dim
      << ", quantizer.ema_decay=" << quantizer.ema_decay
      << ", quantizer.commitment_weight=" << quantizer.commitment_weight
      << ", quantizer.dead_code_threshold=" << quantizer.dead_code_threshold
      << ", quantizer.quantize_dropout=" << quantizer.quantize_dropout << ")";
  return out.str();
}

TokenizerImpl::TokenizerImpl(const TatConfig& config) : config_(config) {
  config_.validate();
  if (is_nec(config_.kind)) {
    encoder_ = register_module("encoder", std::make_shared<NecEncoderImpl>(config_));
    decoder_ = register_module("decoder", std::make_shared<NecDecoderImpl>(config_));
  } else {
    encoder_ = register_module("encoder", std::make_shared<PaddedEncoderImpl>(config_));
    decoder_ = register_module("decoder", std::make_shared<PaddedDecoderImpl>(config_));
  }
  quantizer_ = register_module("quantizer", ResidualQuantizer(config_.quantizer));
}

at::Tensor TokenizerImpl::encode(const at::Tensor& features, const at::Tensor& joint_mask,
                                 const at::Tensor& joint_embeddings) {
  check_input(features.defined() && features.dim() == 4 && features.size(3) == 9,
              "features must be (B, T, J, 9), got " + shape_of(features));
  const int64_t b = features.size(0), t = features.size(1), joints = features.size(2), r = config_.downsampling();
  check_input(t % r == 0, "the frame count T = " + std::to_string(t) + " is not a multiple of the downsampling r = " +
                              std::to_string(r) + " (2^blocks); crop or pad the clip to a multiple of " +
                              std::to_string(r));
  check_input(joint_mask.defined() && joint_mask.dim() == 2 && joint_mask.size(0) == b && joint_mask.size(1) == joints,
              "joint_mask must be (B, J) = (" + std::to_string(b) + ", " + std::to_string(joints) + "), got " +
                  shape_of(joint_mask));
  if (is_nec(config_.kind)) {
    check_input(joint_embeddings.defined() && joint_embeddings.dim() == 3 && joint_embeddings.size(0) == b &&
                    joint_embeddings.size(1) == joints && joint_embeddings.size(2) == config_.joint_embedding_dim,
                "joint_embeddings must be (B, J, E) = (" + std::to_string(b) + ", " + std::to_string(joints) + ", " +
                    std::to_string(config_.joint_embedding_dim) + "), got " + shape_of(joint_embeddings));
  } else {
    check_input(joints <= config_.max_joints, "the batch has " + std::to_string(joints) +
                                                  " joints, more than this zero-pad-rvq model's max_joints = " +
                                                  std::to_string(config_.max_joints));
  }
  const at::Tensor mask = joint_mask.to(torch::kBool);
  return encoder_->forward(features_to_model_space(features), mask,
                           is_nec(config_.kind) ? distinct_joint_embeddings(joint_embeddings, mask) : at::Tensor());
}

QuantizerOutput TokenizerImpl::quantize(const at::Tensor& latent, const at::Tensor& step_mask) {
  check_input(latent.defined() && latent.dim() == 3 && latent.size(2) == config_.quantizer.code_dim,
              "latent must be (B, S, " + std::to_string(config_.quantizer.code_dim) + "), got " + shape_of(latent));
  const int64_t b = latent.size(0), s = latent.size(1);
  if (step_mask.defined()) {
    check_input(step_mask.dim() == 2 && step_mask.size(0) == b && step_mask.size(1) == s,
                "step_mask must be (B, S) = (" + std::to_string(b) + ", " + std::to_string(s) + "), got " +
                    shape_of(step_mask));
  }
  QuantizerOutput q = quantizer_->forward(latent.reshape({b * s, latent.size(2)}),
                                          step_mask.defined() ? step_mask.reshape({b * s}).to(torch::kBool) : at::Tensor());
  q.quantized = q.quantized.view({b, s, latent.size(2)});
  q.codes = q.codes.view({b, s, config_.quantizer.layers});
  return q;
}

at::Tensor TokenizerImpl::decode(const at::Tensor& quantized, const at::Tensor& joint_mask,
                                 const at::Tensor& joint_embeddings, const at::Tensor& start_heading) {
  check_input(quantized.defined() && quantized.dim() == 3 && quantized.size(2) == config_.quantizer.code_dim,
              "quantized must be (B, S, " + std::to_string(config_.quantizer.code_dim) + "), got " +
                  shape_of(quantized));
  const int64_t b = quantized.size(0);
  check_input(joint_mask.defined() && joint_mask.dim() == 2 && joint_mask.size(0) == b,
              "joint_mask must be (B, J) with B = " + std::to_string(b) + ", got " + shape_of(joint_mask));
  const int64_t joints = joint_mask.size(1);
  if (is_nec(config_.kind)) {
    check_input(joint_embeddings.defined() && joint_embeddings.dim() == 3 && joint_embeddings.size(0) == b &&
                    joint_embeddings.size(1) == joints && joint_embeddings.size(2) == config_.joint_embedding_dim,
                "joint_embeddings must be (B, J, E) = (" + std::to_string(b) + ", " + std::to_string(joints) + ", " +
                    std::to_string(config_.joint_embedding_dim) + "), got " + shape_of(joint_embeddings));
  } else {
    check_input(joints <= config_.max_joints, "the target has " + std::to_string(joints) +
                                                  " joints, more than this zero-pad-rvq model's max_joints = " +
                                                  std::to_string(config_.max_joints));
  }
  if (start_heading.defined()) {
    check_input(start_heading.dim() == 1 && start_heading.size(0) == b,
                "start_heading must be (B) = (" + std::to_string(b) + "), got " + shape_of(start_heading));
  }
  const at::Tensor mask = joint_mask.to(torch::kBool);
  const at::Tensor model = decoder_->forward(
      quantized, mask, is_nec(config_.kind) ? distinct_joint_embeddings(joint_embeddings, mask) : at::Tensor());
  return model_space_to_features(
      model, start_heading.defined() ? start_heading.to(model.device()) : torch::zeros({b}, model.options()));
}

at::Tensor TokenizerImpl::codes_to_latent(const at::Tensor& codes) {
  check_input(codes.defined() && codes.dim() == 3, "codes must be (B, S, R), got " + shape_of(codes));
  return quantizer_->codes_to_latent(codes);
}

TokenizerOutput TokenizerImpl::forward(const at::Tensor& features, const at::Tensor& joint_mask,
                                       const at::Tensor& frame_mask, const at::Tensor& joint_embeddings) {
  const at::Tensor latent = encode(features, joint_mask, joint_embeddings);  // (B, S, C)
  const int64_t b = latent.size(0), s = latent.size(1);
  at::Tensor step_mask;  // a step is real when any of its r frames is
  if (frame_mask.defined()) {
    check_input(frame_mask.dim() == 2 && frame_mask.size(0) == b && frame_mask.size(1) == features.size(1),
                "frame_mask must be (B, T) = (" + std::to_string(b) + ", " + std::to_string(features.size(1)) +
                    "), got " + shape_of(frame_mask));
    step_mask = frame_mask.to(torch::kBool).reshape({b, s, config_.downsampling()}).any(-1);
  }
  QuantizerOutput q = quantize(latent, step_mask);
  TokenizerOutput out;
  out.reconstruction = decode(q.quantized, joint_mask, joint_embeddings, start_heading(features));
  out.codes = q.codes;
  out.commitment_loss = q.commitment_loss;
  out.perplexity = q.perplexity;
  return out;
}

}  // namespace nec::tat
