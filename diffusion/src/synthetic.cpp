// Synthetic diffusion inputs and the bare training step shared with the Python peer.
#include "nec/diffusion/synthetic.h"

#include "nec/owo/training.h"
#include "nec/tat/model_space.h"
#include "nec/tat/synthetic.h"
#include "nec/train/optimizer.h"

#include <torch/torch.h>

#include <cmath>

namespace nec::diffusion {
namespace {

// (B) counts -> (B, width) bool, true for the first count positions.
at::Tensor first_positions(const at::Tensor& counts, int64_t width) {
  return torch::arange(width, torch::kLong).unsqueeze(0) < counts.unsqueeze(1);
}

}  // namespace

DiffusionTrainConfig synthetic_stage_config(const std::string& configs_dir, DiffusionStage stage) {
  const DiffusionTrainConfig pose = read_diffusion_train_config(configs_dir + "/diffusion_pose_cpu.json");
  DiffusionTrainConfig config = pose;
  if (stage == DiffusionStage::kMotion) {
    config = read_diffusion_train_config(configs_dir + "/diffusion_motion_cpu.json");
    config.model = pose.model;
  }
  config.model.skeleton_dim = owo::read_owo_training_config(configs_dir + "/owo_cpu.json").encoder.dim;
  config.validate();
  return config;
}

SyntheticDiffusionBatch synthetic_diffusion_batch(const DiffusionTrainConfig& config, DiffusionStage stage,
                                                  int64_t joints) {
  const int64_t b = config.batch_size, frames = config.data.window_frames, channels = tat::kModelChannels;
  at::Tensor features = tat::random_features(b, frames, joints);
  // parent(j) uniform in [0, j - 1]: a random tree with parents before children; -1 for the root.
  const at::Tensor index = torch::arange(joints, torch::kLong);
  at::Tensor parents =
      torch::minimum((torch::rand({b, joints}) * index.to(torch::kFloat)).floor().to(torch::kLong), index - 1);
  at::Tensor offsets = torch::randn({b, joints, 3}) * 0.1;
  offsets.select(1, 0).zero_();
  at::Tensor joint_counts = joints - (torch::rand({b}) * static_cast<double>(joints / 4 + 1)).floor().to(torch::kLong);
  at::Tensor frame_counts = frames - (torch::rand({b}) * static_cast<double>(frames / 2 + 1)).floor().to(torch::kLong);
  joint_counts[0] = joints;  // the batch is as wide as its widest skeleton and as long as its longest crop
  frame_counts[0] = frames;
  const at::Tensor joint_mask = first_positions(joint_counts, joints), frame_mask = first_positions(frame_counts, frames);
  const at::Tensor real = (frame_mask.view({b, frames, 1, 1}) & joint_mask.view({b, 1, joints, 1})).to(torch::kFloat);
  features = features * real;
  parents = torch::where(joint_mask, parents, torch::full_like(parents, -1));
  offsets = offsets * joint_mask.unsqueeze(-1).to(torch::kFloat);
  const at::Tensor embeddings =
      torch::randn({b, joints, config.model.skeleton_dim}) * joint_mask.unsqueeze(-1).to(torch::kFloat);

  SyntheticDiffusionBatch out;
  DenoisingBatch& x = out.batch;
  const at::Tensor piece_counts = 1 + (torch::rand({b}) * static_cast<double>(kSyntheticPieces)).floor().to(torch::kLong);
  x.text.mask = first_positions(piece_counts, piece_counts.max().item<int64_t>());
  // Pieces' features of about unit norm, like the unit sentence vectors.
  x.text.encoder_features = torch::randn({b, x.text.mask.size(1), text::kUseLiteWidth}) *
                            (1.0 / std::sqrt(static_cast<double>(text::kUseLiteWidth))) *
                            x.text.mask.unsqueeze(-1).to(torch::kFloat);
  const at::Tensor sentence = torch::randn({b, text::kUseLiteWidth});
  x.text.encoder_sentence = sentence / sentence.norm(2, -1, /*keepdim=*/true);

  const at::Tensor motion = tat::features_to_model_space(features);
  for (int64_t i = 0; i < b; ++i) {
    out.clips.push_back(motion[i].narrow(0, 0, frame_counts[i].item<int64_t>()).narrow(1, 0, joint_counts[i].item<int64_t>()));
  }
  x.motion = motion;
  x.frame_mask = frame_mask;
  if (stage == DiffusionStage::kPose) {  // as DiffusionTrainer::loss_of picks single frames
    const at::Tensor picks = (torch::rand({b, config.pose_frames}) * frame_counts.to(torch::kFloat).unsqueeze(1))
                                 .floor().to(torch::kInt64).clamp_max(frames - 1);
    x.motion = torch::gather(motion, 1, picks.view({b, -1, 1, 1}).expand({b, config.pose_frames, joints, channels}));
    x.frame_mask = torch::ones({b, config.pose_frames}, torch::kBool);
  }
  const int64_t steps = NoiseSchedule(config.model.noise_steps).steps();
  x.t = (torch::rand({b}) * static_cast<double>(steps)).floor().to(torch::kInt64).clamp_max(steps - 1);
  std::vector<at::Tensor> noises;
  for (int64_t i = 0; i < b; ++i) {
    const int64_t own = joint_counts[i].item<int64_t>();
    noises.push_back(torch::constant_pad_nd(torch::randn({x.motion.size(1), own, channels}), {0, 0, 0, joints - own}));
  }
  x.noise = torch::stack(noises);
  const at::Tensor draws = torch::rand({b});
  std::vector<int64_t> dropped;
  for (int64_t i = 0; i < b; ++i) dropped.push_back(draws[i].item<double>() < config.caption_dropout ? 1 : 0);
  x.drop_text = torch::tensor(dropped, torch::kInt64).to(torch::kBool);
  x.skeletons = make_skeleton_inputs(parents, offsets, joint_mask, embeddings);
  x.global_items = b;
  return out;
}

MotionDenoiser synthetic_denoiser(const DiffusionTrainConfig& config, DiffusionStage stage,
                                  const SyntheticDiffusionBatch& inputs) {
  MotionDenoiser model(config.model);
  model->fit_statistics(inputs.clips);
  if (stage == DiffusionStage::kMotion) {
    torch::NoGradGuard no_grad;
    for (at::Tensor& p : model->pose_parameters()) p.add_(torch::randn(p.sizes()) * kPoseStandInStd);
    if (!config.train_pose_model) freeze_pose_model(*model);
  }
  return model;
}

double synthetic_diffusion_train_step(MotionDenoiserImpl& model, torch::optim::Optimizer& optimizer,
                                      const SyntheticDiffusionBatch& inputs, const DiffusionTrainConfig& config,
                                      DiffusionStage stage, int64_t step) {
  const double lr = train::LearningRateSchedule(config.optimizer, config.steps).at(step);
  const NoiseSchedule schedule(model.config().noise_steps);
  set_training_mode(model, stage);
  optimizer.zero_grad();
  const at::Tensor loss = denoising_objective(model, schedule, inputs.batch, stage, config.velocity_weight);
  loss.backward();
  train::optimizer_step(optimizer, trained_parameters(model, stage, config.train_pose_model), config.optimizer.grad_clip, lr);
  return loss.item<double>();
}

}  // namespace nec::diffusion
