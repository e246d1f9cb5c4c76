// What one training step of the diffusion model computes once its batch is
// drawn, shared by DiffusionTrainer and the synthetic step of the benchmark
// and the golden test (diffusion/synthetic.h), so that those measure and pin
// the trainer's own computation.
//
//   DenoisingBatch x;  // motion, masks, skeletons, timesteps, noise, captions: the trainer's loss_of makes it
//   set_training_mode(*model, stage);
//   const at::Tensor loss = denoising_objective(*model, schedule, x, stage, config.velocity_weight);
//   loss.backward();
//   train::optimizer_step(*optimizer, trained_parameters(*model, stage, config.train_pose_model), config.optimizer.grad_clip, lr);
#pragma once

#include "nec/diffusion/checkpoint.h"
#include "nec/diffusion/denoiser.h"
#include "nec/diffusion/noise_schedule.h"
#include "nec/diffusion/skeleton_inputs.h"
#include "nec/text/text_encoder.h"

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <vector>

namespace nec::diffusion {

// A batch with its diffusion draws, before standardizing and noising.
struct DenoisingBatch {
  at::Tensor motion;        // (B, T, J, C) model space; the pose stage: the frames drawn from each crop
  at::Tensor frame_mask;    // (B, T) bool
  SkeletonInputs skeletons; // joint mask (B, J) among them
  at::Tensor t;             // (B) int64 timesteps
  at::Tensor noise;         // (B, T, J, C) unit Gaussian; only where the item uses a channel is read
  text::TextBatch text;     // every item's caption (a dropped one too: it is read, then replaced)
  at::Tensor drop_text;     // (B) bool: the item reads the null caption
  int64_t global_items = 0; // items of the whole batch over all ranks (the loss's divisor)
};

// x0 = the standardized motion where used, x_t = add_noise(x0, noise, t), the
// predicted x0, and denoising_loss (+ velocity_weight x velocity_loss in the
// motion stage) over the channels each real joint of each real frame uses. -> ()
at::Tensor denoising_objective(MotionDenoiserImpl& model, const NoiseSchedule& schedule, const DenoisingBatch& batch,
                               DiffusionStage stage, double velocity_weight);

// Train mode as the stage trains: the motion stage's frozen caption encoder
// reads captions as it will in generation (no dropout).
void set_training_mode(MotionDenoiserImpl& model, DiffusionStage stage);
// The parameters the stage trains: the pose model's; or the temporal blocks' and the frame encoding's, and with
// train_pose_model (DiffusionTrainConfig) every parameter.
std::vector<at::Tensor> trained_parameters(MotionDenoiserImpl& model, DiffusionStage stage, bool train_pose_model);
// Freezes the pose model for a motion stage that does not train it (train_pose_model false).
void freeze_pose_model(MotionDenoiserImpl& model);

}  // namespace nec::diffusion
