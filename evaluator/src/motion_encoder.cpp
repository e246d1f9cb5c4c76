// The evaluator's motion encoder: model-space patches + OwO joint embeddings,
// spatial then temporal attention, pooled.
#include "nec/evaluator/motion_encoder.h"

#include "nec/layers/transformer.h"
#include "nec/tat/model_space.h"
#include "nec/train/config_fields.h"

#include <torch/torch.h>

#include <stdexcept>
#include <string>

namespace nec::evaluator {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("MotionEncoderConfig: " + message);
}


}  // namespace

void MotionEncoderConfig::validate() const {
  require(joint_embedding_dim >= 1, "joint_embedding_dim must be >= 1");
  require(dim >= 1 && heads >= 1 && dim % heads == 0, "heads must divide dim");
  require(patch_frames >= 1 && max_steps >= 1, "patch_frames and max_steps must be >= 1");
  require(spatial_layers >= 1 && temporal_layers >= 1, "spatial_layers and temporal_layers must be >= 1");
  require(feedforward >= 1 && output_dim >= 1, "feedforward and output_dim must be >= 1");
  require(dropout >= 0 && dropout < 1, "dropout must be in [0, 1)");
}

void visit_fields(train::ConfigVisitor& v, MotionEncoderConfig& c) {
  v.field("joint_embedding_dim", c.joint_embedding_dim, "width of the OwO joint embeddings (set from --owo)");
  v.field("dim", c.dim, "token width");
  v.field("patch_frames", c.patch_frames, "frames per temporal patch");
  v.field("spatial_layers", c.spatial_layers, "attention layers over the joints of a step");
  v.field("temporal_layers", c.temporal_layers, "attention layers over the steps");
  v.field("heads", c.heads, "attention heads; must divide dim");
  v.field("feedforward", c.feedforward, "FFN hidden width");
  v.field("max_steps", c.max_steps, "longest input in patches; longer clips are cropped to their middle");
  v.field("output_dim", c.output_dim, "width of the motion embedding (= the text encoder's output_dim)");
  v.field("dropout", c.dropout, "transformer dropout in training");
}

MotionEncoderImpl::MotionEncoderImpl(const MotionEncoderConfig& config) : config_(config) {
  config_.validate();
  const int64_t d = config_.dim;
  patch_in_ = register_module("patch_in", torch::nn::Linear(config_.patch_frames * tat::kModelChannels, d));
  joint_in_ = register_module("joint_in", torch::nn::Linear(config_.joint_embedding_dim, d));
  summary_ = register_parameter("summary", torch::randn({d}) * 0.02);
  step_positions_ = register_parameter("step_positions", torch::randn({config_.max_steps, d}) * 0.02);
  const layers::TransformerOptions layer{d, config_.heads, config_.feedforward, config_.dropout};
  spatial_ = register_module("spatial", std::make_shared<layers::TransformerStackImpl>(layer, config_.spatial_layers));
  temporal_ = register_module("temporal", std::make_shared<layers::TransformerStackImpl>(layer, config_.temporal_layers));
  out_ = register_module("out", torch::nn::Linear(d, config_.output_dim));
}

at::Tensor MotionEncoderImpl::forward(const at::Tensor& features, const at::Tensor& joint_mask,
                                      const at::Tensor& frame_mask, const at::Tensor& joint_embeddings) {
  const int64_t b = features.size(0), t = features.size(1), j = features.size(2), d = config_.dim;
  const int64_t p = config_.patch_frames, steps = (t + p - 1) / p;
  if (steps > config_.max_steps) {
    throw std::invalid_argument("MotionEncoder: " + std::to_string(t) + " frames, at most " +
                                std::to_string(config_.max_frames()));
  }
  const at::Tensor real = frame_mask.unsqueeze(2).logical_and(joint_mask.unsqueeze(1));  // (B, T, J)
  at::Tensor model = tat::features_to_model_space(features) * real.unsqueeze(-1).to(features.scalar_type());
  at::Tensor frames = frame_mask;
  if (steps * p != t) {
    model = torch::constant_pad_nd(model, {0, 0, 0, 0, 0, steps * p - t});
    frames = torch::constant_pad_nd(frame_mask, {0, steps * p - t});
  }
  // (B, S, J, p * C): the frames of a patch side by side for each joint.
  const at::Tensor patches =
      model.view({b, steps, p, j, tat::kModelChannels}).permute({0, 1, 3, 2, 4}).reshape({b, steps, j, p * tat::kModelChannels});
  const at::Tensor joints = patch_in_(patches) + joint_in_(joint_embeddings).unsqueeze(1);  // (B, S, J, D)
  const at::Tensor tokens =
      torch::cat({summary_.view({1, 1, 1, d}).expand({b, steps, 1, d}), joints}, 2).reshape({b * steps, j + 1, d});
  const at::Tensor keep = torch::cat({torch::ones({b, 1}, joint_mask.options()), joint_mask}, 1);  // (B, 1 + J)
  const at::Tensor joint_bias = layers::padding_bias(keep).repeat_interleave(steps, 0);          // (B S, 1, 1, 1 + J)
  const at::Tensor summaries = spatial_->forward(tokens, joint_bias).select(1, 0).view({b, steps, d});
  const at::Tensor step_mask = frames.view({b, steps, p}).select(2, 0);  // (B, S)
  const at::Tensor timeline = temporal_->forward(summaries + step_positions_.narrow(0, 0, steps).unsqueeze(0),
                                                 layers::padding_bias(step_mask));
  return out_(layers::masked_mean(timeline, step_mask));
}

}  // namespace nec::evaluator
