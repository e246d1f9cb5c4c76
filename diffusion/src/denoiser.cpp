// The denoiser: joint tokens, factorized spatial / temporal DiT blocks with adaLN-Zero, x0 output.
#include "nec/diffusion/denoiser.h"

#include "nec/layers/transformer.h"
#include "nec/tat/model_space.h"
#include "nec/train/config_fields.h"

#include <torch/torch.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace nec::diffusion {
namespace {

constexpr int64_t kChannels = tat::kModelChannels;
constexpr int64_t kRotationBegin = 3, kRotationChannels = 6;  // rot6D in model space
constexpr double kNormEpsilon = 1e-6;
constexpr double kMinStd = 1e-3;  // a channel that hardly varies is not blown up

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("DenoiserConfig: " + message);
}

// Linear-SiLU-Linear, the paper's encoding layer.
torch::nn::Sequential encoding_mlp(int64_t in, int64_t dim) {
  return torch::nn::Sequential(torch::nn::Linear(in, dim), torch::nn::SiLU(), torch::nn::Linear(dim, dim));
}

at::Tensor layer_norm(const at::Tensor& x) {
  return torch::nn::functional::layer_norm(
      x, torch::nn::functional::LayerNormFuncOptions({x.size(-1)}).eps(kNormEpsilon));
}

// (B, D) shift and scale -> x (B, G, L, D) modulated.
at::Tensor modulate(const at::Tensor& x, const at::Tensor& shift, const at::Tensor& scale) {
  return x * (1 + scale.view({scale.size(0), 1, 1, -1})) + shift.view({shift.size(0), 1, 1, -1});
}

// (B, N) bool mask of the attended axis, repeated for each of `groups` groups -> (B * groups, 1, 1, N).
at::Tensor group_bias(const at::Tensor& mask, int64_t groups) {
  const at::Tensor bias = layers::padding_bias(mask);  // (B, 1, 1, N)
  return bias.unsqueeze(1).expand({mask.size(0), groups, 1, 1, mask.size(1)}).reshape({-1, 1, 1, mask.size(1)});
}

}  // namespace

namespace detail {

// A DiT block with adaLN-Zero: x + g1 · Attention(modulated LN(x) [+ positions]),
// then x + g2 · MLP(modulated LN(x)); shifts, scales and gates from c, all zero at the start.
class DitBlockImpl : public torch::nn::Module {
 public:
  DitBlockImpl(int64_t dim, int64_t heads, int64_t feedforward) : heads_(heads) {
    modulation_ = register_module("modulation", torch::nn::Linear(dim, 6 * dim));
    qkv_ = register_module("qkv", torch::nn::Linear(dim, 3 * dim));
    out_ = register_module("out", torch::nn::Linear(dim, dim));
    mlp_in_ = register_module("mlp_in", torch::nn::Linear(dim, feedforward));
    mlp_out_ = register_module("mlp_out", torch::nn::Linear(feedforward, dim));
    torch::NoGradGuard no_grad;
    modulation_->weight.zero_();
    modulation_->bias.zero_();
  }

  // x (B, G, L, D): attention along L within each of the G groups; c (B, D);
  // bias (B * G, 1, 1, L) or undefined; positions (L, D) added to the attention's input, or undefined.
  at::Tensor forward(const at::Tensor& x, const at::Tensor& c, const at::Tensor& bias, const at::Tensor& positions) {
    const int64_t b = x.size(0), g = x.size(1), l = x.size(2), d = x.size(3);
    const std::vector<at::Tensor> m = modulation_(torch::silu(c)).chunk(6, 1);  // each (B, D)
    at::Tensor h = modulate(layer_norm(x), m[0], m[1]);
    if (positions.defined()) h = h + positions;
    const at::Tensor attended = out_(layers::multi_head_attention(qkv_(h.reshape({b * g, l, d})), heads_, bias));
    const at::Tensor y = x + m[2].view({b, 1, 1, d}) * attended.view({b, g, l, d});
    const at::Tensor mlp = mlp_out_(torch::gelu(mlp_in_(modulate(layer_norm(y), m[3], m[4]))));
    return y + m[5].view({b, 1, 1, d}) * mlp;
  }

 private:
  int64_t heads_;
  torch::nn::Linear modulation_{nullptr}, qkv_{nullptr}, out_{nullptr}, mlp_in_{nullptr}, mlp_out_{nullptr};
};
TORCH_MODULE(DitBlock);

}  // namespace detail

const char* to_string(JointIdentity identity) {
  switch (identity) {
    case JointIdentity::kOwo: return "owo";
    case JointIdentity::kTree: return "tree";
    case JointIdentity::kBoth: return "both";
  }
  return "owo";
}

void DenoiserConfig::validate() const {
  require(dim >= 1 && heads >= 1 && dim % heads == 0, "heads must be >= 1 and divide dim");
  require(layers >= 1 && feedforward >= 1, "layers and feedforward must be >= 1");
  require(max_frames >= 2, "max_frames must be >= 2");
  require(joint_identity == JointIdentity::kTree || skeleton_dim >= 1, "skeleton_dim must be >= 1");
  require(noise_steps >= 2, "noise_steps must be >= 2");
  try {
    text.validate();
  } catch (const std::invalid_argument& e) {
    require(false, std::string("text.") + e.what());
  }
}

void visit_fields(train::ConfigVisitor& v, DenoiserConfig& c) {
  v.field("dim", c.dim, "token width");
  v.field("heads", c.heads, "attention heads; must divide dim");
  v.field("layers", c.layers, "spatial blocks (each followed by a temporal block in the motion model)");
  v.field("feedforward", c.feedforward, "MLP hidden width of every block");
  v.field("max_frames", c.max_frames, "longest window read at once; longer motions are overlapping windows");
  v.field("skeleton_dim", c.skeleton_dim, "width of the OwO joint embeddings (set from the encoder)");
  v.choice("joint_identity", c.joint_identity, {JointIdentity::kOwo, JointIdentity::kTree, JointIdentity::kBoth},
           to_string, "joint identity: OwO embeddings, TreePE + RestPE (the paper's), or both");
  v.field("noise_steps", c.noise_steps, "timesteps of the cosine noise schedule");
  v.object("text", c.text, "the caption encoder");
}

at::Tensor channel_mask(const at::Tensor& joint_mask) {
  at::Tensor used = torch::zeros({joint_mask.size(1), kChannels}, joint_mask.options().dtype(torch::kBool));
  used.narrow(1, kRotationBegin, kRotationChannels).fill_(true);
  used[0].fill_(true);
  return used.unsqueeze(0) & joint_mask.unsqueeze(-1);
}

at::Tensor sinusoidal_encoding(const at::Tensor& positions, int64_t dim) {
  const int64_t half = dim / 2;
  const at::Tensor frequencies =
      torch::exp(torch::arange(half, positions.options().dtype(torch::kFloat32)) * (-std::log(10000.0) / std::max<int64_t>(1, half)));
  const at::Tensor angles = positions.to(torch::kFloat32).unsqueeze(-1) * frequencies;
  at::Tensor out = torch::cat({torch::sin(angles), torch::cos(angles)}, -1);
  if (out.size(-1) < dim) out = torch::constant_pad_nd(out, {0, dim - out.size(-1)});
  return out;
}

MotionDenoiserImpl::MotionDenoiserImpl(const DenoiserConfig& config) : config_(config) {
  config_.validate();
  const int64_t d = config_.dim;
  text_ = register_module("text", text::TextEncoder(config_.text));
  caption_in_ = register_module("caption_in", encoding_mlp(config_.text.output_dim, d));
  null_caption_ = register_parameter("null_caption", torch::randn({d}) * 0.02);
  time_in_ = register_module("time_in", encoding_mlp(d, d));
  motion_in_ = register_module("motion_in", torch::nn::Linear(kChannels, d));
  if (config_.joint_identity != JointIdentity::kTree) {
    owo_in_ = register_module("owo_in", encoding_mlp(config_.skeleton_dim, d));
  }
  if (config_.joint_identity != JointIdentity::kOwo) {
    tree_in_ = register_module("tree_in", encoding_mlp(kTreeFeatures, d));
    rest_in_ = register_module("rest_in", encoding_mlp(kRestFeatures, d));
  }
  spatial_ = register_module("spatial", torch::nn::ModuleList());
  temporal_ = register_module("temporal", torch::nn::ModuleList());
  for (int64_t i = 0; i < config_.layers; ++i) {
    spatial_->push_back(detail::DitBlock(d, config_.heads, config_.feedforward));
    temporal_->push_back(detail::DitBlock(d, config_.heads, config_.feedforward));
  }
  frame_in_ = register_module("frame_in", encoding_mlp(d, d));
  final_modulation_ = register_module("final_modulation", torch::nn::Linear(d, 2 * d));
  out_ = register_module("out", torch::nn::Linear(d, kChannels));
  {
    torch::NoGradGuard no_grad;
    for (const torch::nn::Linear& zero : {final_modulation_, out_}) {
      zero->weight.zero_();
      zero->bias.zero_();
    }
  }
  mean_ = register_buffer("data_mean", torch::zeros({2, kChannels}));
  std_ = register_buffer("data_std", torch::ones({2, kChannels}));
}

at::Tensor MotionDenoiserImpl::caption_condition(const text::TextBatch& captions, const at::Tensor& drop_text) {
  const at::Tensor caption = caption_in_->forward(text_->forward(captions).sentence);
  if (!drop_text.defined()) return caption;
  return torch::where(drop_text.unsqueeze(-1), null_caption_.expand_as(caption), caption);
}

at::Tensor MotionDenoiserImpl::null_condition(int64_t batch) { return null_caption_.unsqueeze(0).expand({batch, -1}); }

at::Tensor MotionDenoiserImpl::joint_identity(const SkeletonInputs& skeletons) {
  at::Tensor identity;
  const auto add = [&identity](const at::Tensor& part) { identity = identity.defined() ? identity + part : part; };
  if (owo_in_) add(owo_in_->forward(skeletons.joint_embeddings));
  if (tree_in_) add(tree_in_->forward(skeletons.tree) + rest_in_->forward(skeletons.rest));
  return identity * skeletons.joint_mask.unsqueeze(-1).to(identity.scalar_type());
}

at::Tensor MotionDenoiserImpl::forward(const at::Tensor& x_t, const at::Tensor& t, const at::Tensor& caption,
                                       const SkeletonInputs& skeletons, const at::Tensor& frame_mask, bool temporal) {
  if (x_t.dim() != 4 || x_t.size(3) != kChannels || skeletons.joint_mask.size(1) != x_t.size(2)) {
    throw std::invalid_argument("MotionDenoiser: expected x_t (B, T, J, " + std::to_string(kChannels) +
                                ") with the skeletons' J joints");
  }
  const int64_t frames = x_t.size(1), joints = x_t.size(2);
  if (temporal && frames > config_.max_frames) {
    throw std::invalid_argument("MotionDenoiser: " + std::to_string(frames) + " frames, more than max_frames " +
                                std::to_string(config_.max_frames));
  }
  const at::Tensor c = time_in_->forward(sinusoidal_encoding(t, config_.dim)) + caption;  // (B, D)
  at::Tensor h = motion_in_(x_t) + joint_identity(skeletons).unsqueeze(1);               // (B, T, J, D)
  const at::Tensor spatial_bias = group_bias(skeletons.joint_mask, frames);
  at::Tensor temporal_bias, positions;
  if (temporal) {
    if (frame_mask.defined()) temporal_bias = group_bias(frame_mask, joints);
    positions = frame_in_->forward(sinusoidal_encoding(torch::arange(frames, x_t.options().dtype(torch::kInt64)), config_.dim));
  }
  for (int64_t i = 0; i < config_.layers; ++i) {
    h = spatial_[static_cast<size_t>(i)]->as<detail::DitBlockImpl>()->forward(h, c, spatial_bias, {});
    if (temporal) {
      h = temporal_[static_cast<size_t>(i)]->as<detail::DitBlockImpl>()
              ->forward(h.transpose(1, 2), c, temporal_bias, positions)
              .transpose(1, 2);
    }
  }
  const std::vector<at::Tensor> m = final_modulation_(torch::silu(c)).chunk(2, 1);
  return out_(modulate(layer_norm(h), m[0], m[1]));
}

namespace {

// (J, C) per-joint rows of a (2, C) statistic: row 0 for the root, row 1 for every other joint.
at::Tensor per_joint(const at::Tensor& statistic, int64_t joints) {
  return torch::cat({statistic.narrow(0, 0, 1), statistic.narrow(0, 1, 1).expand({joints - 1, -1})});
}

}  // namespace

at::Tensor MotionDenoiserImpl::standardize(const at::Tensor& model_space) const {
  const int64_t j = model_space.size(-2);
  return (model_space - per_joint(mean_, j)) / per_joint(std_, j);
}

at::Tensor MotionDenoiserImpl::unstandardize(const at::Tensor& standardized) const {
  const int64_t j = standardized.size(-2);
  return standardized * per_joint(std_, j) + per_joint(mean_, j);
}

void MotionDenoiserImpl::fit_statistics(const std::vector<at::Tensor>& clips) {
  torch::NoGradGuard no_grad;
  std::vector<at::Tensor> roots, others;
  for (const at::Tensor& clip : clips) {
    const at::Tensor x = clip.to(torch::kCPU, torch::kDouble);
    roots.push_back(x.select(1, 0));
    if (x.size(1) > 1) others.push_back(x.narrow(1, 1, x.size(1) - 1).narrow(2, kRotationBegin, kRotationChannels).reshape({-1, kRotationChannels}));
  }
  if (roots.empty()) throw std::invalid_argument("fit_statistics: no clip");
  at::Tensor mean = torch::zeros({2, kChannels}, torch::kDouble), std = torch::ones({2, kChannels}, torch::kDouble);
  const at::Tensor root = torch::cat(roots);  // (N, C)
  mean[0] = root.mean(0);
  std[0] = root.std(0, /*unbiased=*/false);
  // The horizontal displacement: mean 0 and one std for x and z, so that turning it commutes with standardizing.
  const at::Tensor horizontal = torch::sqrt((root.select(1, 0).square().mean() + root.select(1, 2).square().mean()) / 2);
  for (const int64_t k : {int64_t{0}, int64_t{2}}) {
    mean[0][k] = 0.0;
    std[0][k] = horizontal;
  }
  if (!others.empty()) {
    const at::Tensor rows = torch::cat(others);  // (M, 6)
    mean[1].narrow(0, kRotationBegin, kRotationChannels).copy_(rows.mean(0));
    std[1].narrow(0, kRotationBegin, kRotationChannels).copy_(rows.std(0, /*unbiased=*/false));
  }
  mean_.copy_(mean.to(torch::kFloat32));
  std_.copy_(std.clamp_min(kMinStd).to(torch::kFloat32));
}

std::vector<at::Tensor> MotionDenoiserImpl::pose_parameters() {
  std::vector<at::Tensor> out;
  for (const auto& item : named_parameters()) {
    if (item.key().rfind("temporal.", 0) != 0 && item.key().rfind("frame_in.", 0) != 0) out.push_back(item.value());
  }
  return out;
}

std::vector<at::Tensor> MotionDenoiserImpl::temporal_parameters() {
  std::vector<at::Tensor> out = temporal_->parameters();
  for (const at::Tensor& p : frame_in_->parameters()) out.push_back(p);
  return out;
}

}  // namespace nec::diffusion
