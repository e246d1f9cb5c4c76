// The generalized motion diffusion model's denoiser (How to Move Your Dragon,
// section 5 and appendix B.1) on the skeleton embeddings nec already has.
//
//   DenoiserConfig config;  config.skeleton_dim = 64;  config.text.vocab_size = pieces.vocab_size();
//   MotionDenoiser model(config);
//   at::Tensor c = model->caption_condition(text_batch, drop_text);      // (B, D); drop_text may be undefined
//   at::Tensor x0 = model->forward(x_t, t, c, skeletons, frame_mask, /*temporal=*/true);
//   // x_t, x0 (B, T, J, kModelChannels) normalized model space; t (B) int64 timesteps
//
// One token per joint and frame: a linear projection of the joint's
// model-space channels (tat/model_space.h, standardized) plus its joint
// identity, chosen by `joint_identity`: the frozen OwO embedding h_j through
// an MLP (default), TreePE + RestPE through MLPs (the paper's), or both.
// Each layer is a spatial block (the joints of one frame attend to each
// other, padded joints masked) followed, in the motion model, by a temporal
// block (each joint attends to itself across frames, padded frames masked,
// with a frame position encoding). Blocks are DiT blocks with adaLN-Zero
// modulation from c = MLP(timestep) + MLP(caption sentence vector), so a new
// temporal block starts as the identity. The output is the predicted clean
// x0 (standardized). Stage one (the pose model) runs the spatial blocks
// alone on single frames; stage two adds the temporal blocks and trains only
// them (temporal_parameters()).
//
// Standardization: model space has channels of very different scales, so the
// model reads (x − mean) / std with statistics of the training data (buffers,
// saved with the weights): for the root joint per channel, except the
// horizontal displacement (Δx, Δz), which shares one std and has mean 0 so
// that turning it (motion windows) commutes with standardizing; for the other
// joints per rot6D channel. Channels a joint does not use (the others' root
// channels) are 0 in model space and excluded from the loss (channel_mask).
#pragma once

#include "nec/diffusion/skeleton_inputs.h"
#include "nec/text/text_encoder.h"

#include <ATen/core/Tensor.h>
#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/container/sequential.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/pimpl.h>

#include <cstdint>
#include <string>
#include <vector>

namespace nec::train {
class ConfigVisitor;
}

namespace nec::diffusion {

// Where a joint's identity comes from.
enum class JointIdentity { kOwo, kTree, kBoth };
const char* to_string(JointIdentity identity);  // "owo", "tree", "both"

// Hyper-parameters; saved with a model.
struct DenoiserConfig {
  int64_t dim = 128;             // token width D, e.g. 128 (CPU) or 384 (the paper)
  int64_t heads = 4;             // attention heads; must divide dim
  int64_t layers = 4;            // spatial (+ temporal) blocks, e.g. 4 (CPU) or 12 (the paper)
  int64_t feedforward = 512;     // MLP hidden width, e.g. 4 * dim
  int64_t max_frames = 120;      // longest window read at once (longer motions: overlapping windows)
  int64_t skeleton_dim = 64;     // width of the OwO embeddings (set from the OwO encoder)
  JointIdentity joint_identity = JointIdentity::kOwo;
  int64_t noise_steps = 1000;    // timesteps of the cosine schedule
  text::TextEncoderConfig text;  // the caption encoder, trained with the pose model

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, DenoiserConfig& c);  // train/config_fields.h

// (B, J, kModelChannels) bool: the channels a joint uses (the root all, others their rot6D), false at padding.
at::Tensor channel_mask(const at::Tensor& joint_mask);

namespace detail {
class DitBlockImpl;
}

class MotionDenoiserImpl : public torch::nn::Module {
 public:
  explicit MotionDenoiserImpl(const DenoiserConfig& config);
  const DenoiserConfig& config() const { return config_; }
  text::TextEncoderImpl& text_encoder() { return *text_; }

  // (B, D) caption part of the condition; rows with drop_text (B) bool (undefined: none) read the learnt null caption.
  at::Tensor caption_condition(const text::TextBatch& captions, const at::Tensor& drop_text);
  // (B, D) the null caption for B items (classifier-free guidance's unconditioned half).
  at::Tensor null_condition(int64_t batch);

  // x_t (B, T, J, C) standardized noisy motion, t (B) int64 timesteps, caption (B, D),
  // frame_mask (B, T) bool (undefined: all real). temporal = false: the pose model (frames independent).
  // -> predicted x0 (B, T, J, C), standardized.
  at::Tensor forward(const at::Tensor& x_t, const at::Tensor& t, const at::Tensor& caption,
                     const SkeletonInputs& skeletons, const at::Tensor& frame_mask, bool temporal);

  // Model space (…, J, C) <-> standardized, for joints (…, J) laid out with the root at index 0.
  at::Tensor standardize(const at::Tensor& model_space) const;
  at::Tensor unstandardize(const at::Tensor& standardized) const;
  // Sets the statistics from training data: the model space (T, J, C) of clips (any J, root first).
  void fit_statistics(const std::vector<at::Tensor>& clips);

  // The pose model's parameters (everything but the temporal blocks) and the temporal blocks'.
  std::vector<at::Tensor> pose_parameters();
  std::vector<at::Tensor> temporal_parameters();

 private:
  at::Tensor joint_identity(const SkeletonInputs& skeletons);

  DenoiserConfig config_;
  text::TextEncoder text_{nullptr};
  torch::nn::Sequential caption_in_{nullptr};   // sentence vector -> D
  at::Tensor null_caption_;                     // (D) a dropped caption
  torch::nn::Sequential time_in_{nullptr};      // sinusoidal timestep -> D
  torch::nn::Linear motion_in_{nullptr};        // C -> D per joint
  torch::nn::Sequential owo_in_{nullptr};       // E -> D (kOwo, kBoth)
  torch::nn::Sequential tree_in_{nullptr};      // TreePE -> D (kTree, kBoth)
  torch::nn::Sequential rest_in_{nullptr};      // RestPE -> D (kTree, kBoth)
  torch::nn::ModuleList spatial_{nullptr};
  torch::nn::ModuleList temporal_{nullptr};
  torch::nn::Sequential frame_in_{nullptr};     // sinusoidal frame index -> D (temporal part)
  torch::nn::Linear final_modulation_{nullptr}; // c -> shift, scale of the output norm (zero-initialised)
  torch::nn::Linear out_{nullptr};              // D -> C (zero-initialised)
  at::Tensor mean_, std_;                       // (2, C) buffers: row 0 the root, row 1 the other joints
};
TORCH_MODULE(MotionDenoiser);

// (N) positions -> (N, dim) sinusoidal encodings (Vaswani et al.; timesteps and frame indices).
at::Tensor sinusoidal_encoding(const at::Tensor& positions, int64_t dim);

}  // namespace nec::diffusion
