// The diffusion training step's computation after its batch is drawn.
#include "nec/diffusion/objective.h"

#include "nec/diffusion/training.h"

#include <torch/torch.h>

namespace nec::diffusion {

at::Tensor denoising_objective(MotionDenoiserImpl& model, const NoiseSchedule& schedule, const DenoisingBatch& batch,
                               DiffusionStage stage, double velocity_weight) {
  const int64_t b = batch.motion.size(0);
  const at::Tensor used = channel_mask(batch.skeletons.joint_mask).unsqueeze(1) & batch.frame_mask.view({b, -1, 1, 1});
  // Padding is zero in Θ, which is no rotation: where(), not a product, keeps whatever it maps to out.
  const at::Tensor x0 = torch::where(used, model.standardize(batch.motion), torch::zeros_like(batch.motion));
  const at::Tensor x_t = schedule.add_noise(x0, batch.noise * used, batch.t);
  const at::Tensor condition = model.caption_condition(batch.text, batch.drop_text);
  const bool temporal = stage == DiffusionStage::kMotion;
  const at::Tensor predicted = model.forward(x_t, batch.t, condition, batch.skeletons, batch.frame_mask, temporal);
  at::Tensor loss = denoising_loss(predicted, x0, used, batch.global_items);
  if (temporal && velocity_weight > 0) loss = loss + velocity_weight * velocity_loss(predicted, x0, used, batch.global_items);
  return loss;
}

void set_training_mode(MotionDenoiserImpl& model, DiffusionStage stage) {
  model.train();
  if (stage == DiffusionStage::kMotion) model.text_encoder().eval();
}

std::vector<at::Tensor> trained_parameters(MotionDenoiserImpl& model, DiffusionStage stage, bool train_pose_model) {
  if (stage == DiffusionStage::kPose) return model.pose_parameters();
  // Trained together, the pose model learns what a frame is at high noise, where alone it can only give the
  // mean pose (it never sees which frame it is): docs/diffusion.md "Overfitting".
  return train_pose_model ? model.parameters() : model.temporal_parameters();
}

void freeze_pose_model(MotionDenoiserImpl& model) {
  for (at::Tensor& p : model.pose_parameters()) p.set_requires_grad(false);
}

}  // namespace nec::diffusion
