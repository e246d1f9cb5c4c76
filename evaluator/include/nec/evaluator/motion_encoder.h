// The evaluator's motion encoder for any skeleton: per-joint features in the
// tokenizer's model space (tat/model_space.h) cut into patches of a few
// frames, plus the frozen OwO embedding of each joint; attention over the
// joints of each patch step with a summary token (padded joints masked), a
// temporal transformer over the summary tokens (padded steps masked), pooled
// to one vector. A window of frames is embedded the same way (Coverage and
// Novelty read windows).
//
//   MotionEncoderConfig config;  config.joint_embedding_dim = 128;  // the OwO encoder's width
//   MotionEncoder encoder(config);
//   at::Tensor e = encoder->forward(x.features, x.joint_mask, x.frame_mask, joint_embeddings);  // (B, output_dim)
//
// Frames are grouped from frame 0 in patches of patch_frames (the last patch
// padded); a patch step is real when its first frame is. A clip longer than
// max_steps patches is refused (callers crop: evaluator.h's embed_clip).
#pragma once

#include <ATen/core/Tensor.h>
#include <torch/nn/module.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/pimpl.h>

#include <cstdint>
#include <memory>

namespace nec::train {
class ConfigVisitor;
}
namespace nec::layers {
class TransformerStackImpl;
}

namespace nec::evaluator {

// Hyper-parameters; saved with a model.
struct MotionEncoderConfig {
  int64_t joint_embedding_dim = 128;  // width E of the OwO joint embeddings (set from the encoder)
  int64_t dim = 128;                  // token width D, e.g. 128
  int64_t patch_frames = 4;           // frames per temporal patch, e.g. 4 (133 ms at 30 fps)
  int64_t spatial_layers = 1;         // attention layers over the joints of a step
  int64_t temporal_layers = 2;        // attention layers over the steps
  int64_t heads = 4;                  // attention heads; must divide dim
  int64_t feedforward = 256;          // FFN hidden width, e.g. 2 * dim
  int64_t max_steps = 64;             // longest input in patches (64 x 4 frames = 8.5 s at 30 fps)
  int64_t output_dim = 128;           // width of the motion embedding
  double dropout = 0.1;               // in the transformers, training only

  int64_t max_frames() const { return max_steps * patch_frames; }
  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, MotionEncoderConfig& c);  // train/config_fields.h

class MotionEncoderImpl : public torch::nn::Module {
 public:
  explicit MotionEncoderImpl(const MotionEncoderConfig& config);
  const MotionEncoderConfig& config() const { return config_; }

  // features (B, T, J, 9) Θ as batches hold it; joint_mask (B, J) bool;
  // frame_mask (B, T) bool; joint_embeddings (B, J, E). -> (B, output_dim)
  // A skeleton's output does not depend on what it is batched with (eval mode).
  at::Tensor forward(const at::Tensor& features, const at::Tensor& joint_mask, const at::Tensor& frame_mask,
                     const at::Tensor& joint_embeddings);

 private:
  MotionEncoderConfig config_;
  torch::nn::Linear patch_in_{nullptr};  // patch_frames x model channels -> D
  torch::nn::Linear joint_in_{nullptr};  // E -> D
  at::Tensor summary_;                   // (D) the token that reads every joint of a step
  at::Tensor step_positions_;            // (max_steps, D)
  std::shared_ptr<layers::TransformerStackImpl> spatial_, temporal_;
  torch::nn::Linear out_{nullptr};       // D -> output_dim
};
TORCH_MODULE(MotionEncoder);

}  // namespace nec::evaluator
