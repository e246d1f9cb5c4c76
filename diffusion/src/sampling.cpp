// Sampling with DPM-Solver++ or DDIM, guidance and overlapping windows.
#include "nec/diffusion/sampling.h"

#include "nec/diffusion/windows.h"
#include "nec/tat/batch_tensors.h"
#include "nec/tat/fk.h"
#include "nec/tat/metrics.h"
#include "nec/tat/model_space.h"

#include <ATen/CPUGeneratorImpl.h>
#include <torch/torch.h>

#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

namespace nec::diffusion {
namespace {

constexpr int64_t kYawRateChannel = 9;

// Σ degrees the non-root joints of Θ (1, T, J, 9) turn away from the rest pose, and from frame to frame.
std::pair<double, double> joint_turning(const at::Tensor& theta, const at::Tensor& joint_mask) {
  const at::Tensor r = tat::rot6d_to_matrix(theta.slice(-1, 3, 9).to(torch::kFloat64));  // (1, T, J, 3, 3)
  const at::Tensor joints = joint_mask.slice(1, 1).to(torch::kFloat64).unsqueeze(1);    // (1, 1, J-1)
  return {(tat::pose_turn_degrees(r) * joints).sum().item<double>(), (tat::frame_turn_degrees(r) * joints).sum().item<double>()};
}

}  // namespace

void DiffusionSamplingOptions::validate() const {
  if (steps < 1) throw std::invalid_argument("steps must be >= 1, got " + std::to_string(steps));
  if (!(guidance >= 1)) throw std::invalid_argument("guidance must be >= 1, got " + std::to_string(guidance));
  if (overlap_frames < 0) throw std::invalid_argument("overlap_frames must be >= 0");
}

at::Tensor seeded_noise(uint64_t seed, int64_t frames, int64_t joints, const c10::Device& device) {
  at::Generator generator = at::make_generator<at::CPUGeneratorImpl>(seed);
  return torch::randn({frames, joints, tat::kModelChannels}, generator, torch::kFloat32).to(device);
}

std::vector<at::Tensor> sample_motions(MotionDenoiserImpl& model, const NoiseSchedule& schedule,
                                       const SkeletonInputs& skeleton, const at::Tensor& captions,
                                       const std::vector<int64_t>& segment_frames, int samples,
                                       const DiffusionSamplingOptions& options) {
  options.validate();
  if (options.steps > schedule.steps()) {
    throw std::invalid_argument("steps " + std::to_string(options.steps) + " is more than the model's " +
                                std::to_string(schedule.steps()) + " noise steps");
  }
  if (samples < 1) throw std::invalid_argument("samples must be >= 1");
  if (captions.size(0) != static_cast<int64_t>(segment_frames.size())) {
    throw std::invalid_argument("sample_motions: one caption row per segment");
  }
  c10::InferenceMode inference;
  const c10::Device device = captions.device();
  const int64_t total = std::accumulate(segment_frames.begin(), segment_frames.end(), int64_t{0});
  const int64_t joints = skeleton.joint_mask.size(1);
  const std::vector<MotionWindow> windows = layout_windows(segment_frames, model.config().max_frames, options.overlap_frames);
  const int64_t count = static_cast<int64_t>(windows.size()), frames = windows.front().frames;
  const int64_t overlap = window_overlap(frames, options.overlap_frames);
  const int64_t rows = samples * count;  // row = sample * count + window
  const bool guided = options.guidance != 1.0;

  std::vector<int64_t> segment_rows;
  for (int64_t s = 0; s < samples; ++s) {
    for (const MotionWindow& w : windows) segment_rows.push_back(w.segment);
  }
  at::Tensor condition = captions.index_select(0, torch::tensor(segment_rows, torch::kInt64).to(device));
  if (guided) condition = torch::cat({condition, model.null_condition(rows)});
  const int64_t batch = guided ? 2 * rows : rows;
  const SkeletonInputs skeletons = skeleton.select(torch::zeros({batch}, torch::kInt64));
  const at::Tensor used = channel_mask(skeleton.joint_mask).to(torch::kFloat32);  // (1, J, C)

  // Blend weights per window and frame; a later window's frame 0 holds no displacement or yaw rate of its own.
  at::Tensor weights = torch::zeros({count, frames, 1, tat::kModelChannels});
  for (int64_t k = 0; k < count; ++k) {
    weights[k].copy_(window_weights(frames, overlap, k == 0, k + 1 == count).view({frames, 1, 1}).expand({frames, 1, tat::kModelChannels}));
    if (windows[static_cast<size_t>(k)].start > 0) {
      for (const int64_t channel : {int64_t{0}, int64_t{2}, kYawRateChannel}) weights[k][0][0][channel] = 0.0f;
    }
  }
  weights = weights.to(device);
  at::Tensor weight_sum = torch::zeros({total, 1, tat::kModelChannels}, device);
  for (int64_t k = 0; k < count; ++k) weight_sum.narrow(0, windows[static_cast<size_t>(k)].start, frames) += weights[k];

  std::vector<at::Tensor> noise;
  for (int s = 0; s < samples; ++s) noise.push_back(seeded_noise(options.seed + static_cast<uint64_t>(s), total, joints, device));
  at::Tensor x = torch::stack(noise) * used;        // (S, T, J, C) standardized
  at::Tensor x0 = torch::zeros_like(x), earlier_x0;
  int64_t earlier_t = -1;
  at::Tensor yaw = torch::zeros({samples, total}, x.options());  // heading of each frame from the x0 estimate
  const std::vector<int64_t> timesteps = schedule.sampling_timesteps(options.steps, options.spacing);
  for (int64_t i = 0; i < options.steps; ++i) {
    if (options.on_step) options.on_step(i, options.steps);
    const int64_t t = timesteps[static_cast<size_t>(i)], previous = i + 1 < options.steps ? timesteps[static_cast<size_t>(i + 1)] : -1;
    // Each window in its own frame: turned by the heading at its start.
    std::vector<at::Tensor> local, turns;
    for (const MotionWindow& w : windows) turns.push_back(yaw.select(1, w.start));
    const at::Tensor turn = torch::stack(turns, 1).reshape({rows});  // (S * count)
    for (const MotionWindow& w : windows) local.push_back(x.narrow(1, w.start, frames));
    at::Tensor inputs = turn_horizontal(torch::stack(local, 1).reshape({rows, frames, joints, tat::kModelChannels}), turn);
    if (guided) inputs = torch::cat({inputs, inputs});
    const at::Tensor timesteps = torch::full({batch}, t, torch::TensorOptions(torch::kInt64).device(device));
    at::Tensor predicted = model.forward(inputs, timesteps, condition, skeletons, {}, true);
    if (guided) {
      const at::Tensor c = predicted.narrow(0, 0, rows), u = predicted.narrow(0, rows, rows);
      predicted = u + options.guidance * (c - u);
    }
    predicted = turn_horizontal(predicted, -turn).view({samples, count, frames, joints, tat::kModelChannels});
    at::Tensor blended = torch::zeros_like(x);
    for (int64_t k = 0; k < count; ++k) {
      blended.narrow(1, windows[static_cast<size_t>(k)].start, frames) += predicted.select(1, k) * weights[k];
    }
    x0 = blended / weight_sum * used;
    const at::Tensor rate = model.unstandardize(x0).select(2, 0).select(2, kYawRateChannel) / tat::kYawRateScale;
    yaw = rate.cumsum(1);
    x = options.solver == DiffusionSolver::kDdim ? schedule.ddim_step(x, x0, t, previous)
                                                 : schedule.dpm_solver_step(x, x0, earlier_x0, earlier_t, t, previous);
    earlier_x0 = x0;
    earlier_t = t;
  }
  const at::Tensor motion = model.unstandardize(x0) * used;
  std::vector<at::Tensor> out;
  for (int s = 0; s < samples; ++s) out.push_back(motion[s].clone());
  return out;
}

void SampledTurning::add(const SampledTurning& other) {
  sampled_pose += other.sampled_pose;
  real_pose += other.real_pose;
  sampled_speed += other.sampled_speed;
  real_speed += other.real_speed;
}

SampledTurning sampled_turning(MotionDenoiserImpl& model, const NoiseSchedule& schedule, const tat::BatchTensors& truth,
                               const SkeletonInputs& skeletons, const at::Tensor& captions,
                               const DiffusionSamplingOptions& options) {
  SampledTurning turning;
  for (int64_t i = 0; i < truth.features.size(0); ++i) {
    const tat::BatchTensors clip = truth.items(i, 1);
    const int64_t frames = clip.frame_mask.sum().item<int64_t>();
    if (frames < 2) continue;
    const at::Tensor row = torch::full({1}, i, torch::kInt64);
    const at::Tensor motion =
        sample_motions(model, schedule, skeletons.select(row), captions.narrow(0, i, 1), {frames}, 1, options).front();
    const at::Tensor theta = tat::model_space_to_features(motion.unsqueeze(0), torch::zeros({1}, motion.options()));
    const auto [sampled_pose, sampled_speed] = joint_turning(theta, clip.joint_mask);
    const auto [real_pose, real_speed] = joint_turning(clip.features.narrow(1, 0, frames), clip.joint_mask);
    turning.add({sampled_pose, real_pose, sampled_speed, real_speed});
  }
  return turning;
}

}  // namespace nec::diffusion
