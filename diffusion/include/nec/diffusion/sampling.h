// Sampling motion from a trained denoiser: DPM-Solver++ or DDIM over a few of
// the 1000 timesteps, classifier-free guidance, a seed per sample, long
// motions as overlapping windows with a caption each (windows.h).
//
//   DiffusionSamplingOptions options;  options.steps = 10;  options.guidance = 2.5;  options.seed = 7;
//   std::vector<at::Tensor> motions = sample_motions(*model, schedule, skeleton, captions, {120}, 4, options);
//   // each (T, J, kModelChannels) model space on the skeleton, heading 0 at frame 0
//
// Guidance: x0 = u + g (c − u) of the unconditioned and conditioned
// predictions, the two halves run as one batch (g = 1: the conditioned half
// alone). Sample i starts from the noise of the stream seed + i, so it does
// not depend on how many samples are drawn with it. Both solvers are
// deterministic after the starting noise.
#pragma once

#include "nec/diffusion/denoiser.h"
#include "nec/diffusion/noise_schedule.h"

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace nec::tat {
struct BatchTensors;
}

namespace nec::diffusion {

// How each denoising step moves to the next timestep.
enum class DiffusionSolver {
  kDdim,       // DDIM, η = 0: first order
  kDpmSolver,  // DPM-Solver++(2M): second order from the x0 estimates of this step and the one before
};

// The defaults: 10 steps of DPM-Solver++, more of them at low noise, as good as 50 uniform DDIM steps
// (docs/diffusion.md, "Fewer steps").
struct DiffusionSamplingOptions {
  int64_t steps = 10;          // denoising steps, 1..noise_steps
  DiffusionSolver solver = DiffusionSolver::kDpmSolver;
  TimestepSpacing spacing = TimestepSpacing::kQuadratic;
  double guidance = 2.5;       // classifier-free guidance scale g >= 1; 1 = none
  uint64_t seed = 0;           // sample i starts from the noise of seed + i
  int64_t overlap_frames = 0;  // frames neighbouring windows share; 0 = a quarter of a window
  std::function<void(int64_t step, int64_t steps)> on_step;  // called before each denoising step (progress)

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

// `samples` motions (T, J, C) raw model space for one skeleton (B = 1), T the
// sum of segment_frames, segment s read with caption row s of `captions`
// (S, D) (MotionDenoiserImpl::caption_condition). Runs under InferenceMode;
// put the model in eval mode first.
std::vector<at::Tensor> sample_motions(MotionDenoiserImpl& model, const NoiseSchedule& schedule,
                                       const SkeletonInputs& skeleton, const at::Tensor& captions,
                                       const std::vector<int64_t>& segment_frames, int samples,
                                       const DiffusionSamplingOptions& options);

// How the joints of motions sampled on real clips' skeletons from their captions turn, beside the real
// clips' own: away from the rest pose (the pose) and from one frame to the next (the speed), in degrees
// summed over the non-root joints of the real frames. The x0 loss hardly tells: at most noise levels its
// best answer is near the mean pose, and a model whose samples stand still scores almost as well as one
// whose samples move. A body held still in some pose keeps its pose's turning but none of the speed.
struct SampledTurning {
  double sampled_pose = 0, real_pose = 0;
  double sampled_speed = 0, real_speed = 0;

  void add(const SampledTurning& other);
  // Sampled / real (0: bodies at rest, or standing still; 1: as much as the real ones; jitter adds speed).
  double pose_kept() const { return real_pose > 0 ? sampled_pose / real_pose : 0.0; }
  double speed_kept() const { return real_speed > 0 ? sampled_speed / real_speed : 0.0; }
};

// `truth`: the clips' Θ and masks (B items); `skeletons`: their B rows; `captions` (B, D) conditions
// (caption_condition). One sample per clip, as long as its real frames. Put the model in eval mode.
SampledTurning sampled_turning(MotionDenoiserImpl& model, const NoiseSchedule& schedule, const tat::BatchTensors& truth,
                               const SkeletonInputs& skeletons, const at::Tensor& captions,
                               const DiffusionSamplingOptions& options);

// (T, J, C) standard normal noise of the stream `seed`.
at::Tensor seeded_noise(uint64_t seed, int64_t frames, int64_t joints, const c10::Device& device);

}  // namespace nec::diffusion
