// The diffusion process: a cosine noise schedule (Nichol & Dhariwal 2021)
// over `steps` timesteps, noising for training and DDIM steps (η = 0) that
// skip timesteps for sampling.
//
//   NoiseSchedule schedule(1000);
//   at::Tensor x_t = schedule.add_noise(x0, noise, t);          // t (B) int64 in [0, 1000)
//   const std::vector<int64_t> ts = schedule.sampling_timesteps(50, TimestepSpacing::kUniform);  // 50 of the 1000
//   for (size_t i = 0; i < ts.size(); ++i) {
//     const int64_t previous = i + 1 < ts.size() ? ts[i + 1] : -1;
//     x = schedule.ddim_step(x, predicted_x0, ts[i], previous);  // previous = -1: the last step gives x0
//   }
//   // or DPM-Solver++(2M): the same steps, each also reading the x0 predicted at the step before
//   x = schedule.dpm_solver_step(x, predicted_x0, earlier_x0, earlier_t, t, previous);
//
// ᾱ(t) = f(t + 1) / f(0), f(u) = cos²((u / steps + s) / (1 + s) · π / 2), s = 0.008, with every
// β = 1 − ᾱ(t) / ᾱ(t − 1) clipped to at most 0.999 (so the last timestep is almost pure noise).
#pragma once

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <vector>

namespace nec::diffusion {

// How a sampler's timesteps are spread from steps − 1 down to 0.
enum class TimestepSpacing {
  kUniform,    // evenly
  kQuadratic,  // t = (steps − 1) u², u evenly from 1 to 0: more steps at low noise, where each step's x0
               // estimate is cleaned of the noise the earlier, noisier ones left (the jitter of few steps)
};
const char* to_string(TimestepSpacing spacing);  // "uniform", "quadratic"

class NoiseSchedule {
 public:
  // Throws std::invalid_argument for steps < 2.
  explicit NoiseSchedule(int64_t steps);

  int64_t steps() const { return static_cast<int64_t>(alpha_bar_.size()); }
  // ᾱ at timestep t in [0, steps): the share of the signal's variance left.
  double alpha_bar(int64_t t) const { return alpha_bar_.at(static_cast<size_t>(t)); }

  // x_t = √ᾱ_t x0 + √(1 − ᾱ_t) noise for t (B) int64; x0 and noise (B, ...).
  at::Tensor add_noise(const at::Tensor& x0, const at::Tensor& noise, const at::Tensor& t) const;

  // The `count` timesteps a sampler visits, from steps − 1 down to 0, each below the one before; throws
  // std::invalid_argument unless 1 <= count <= steps.
  std::vector<int64_t> sampling_timesteps(int64_t count, TimestepSpacing spacing) const;

  // DDIM (η = 0): from x_t and the predicted x0 to timestep `previous`
  // (< t; −1: x0 itself).
  at::Tensor ddim_step(const at::Tensor& x_t, const at::Tensor& predicted_x0, int64_t t, int64_t previous) const;

  // DPM-Solver++(2M) (Lu et al. 2022, the multistep second-order solver in its data-prediction form): the
  // DDIM step with the x0 estimate extrapolated in log signal-to-noise ratio λ from the one made at
  // timestep `earlier` (> t) to the middle of the step. `earlier_x0` undefined (the first step) or `previous` <= 0
  // (the last, longest step in λ, where extrapolating overshoots): the DDIM step.
  at::Tensor dpm_solver_step(const at::Tensor& x_t, const at::Tensor& predicted_x0, const at::Tensor& earlier_x0,
                             int64_t earlier, int64_t t, int64_t previous) const;

  // λ(t) = log(√ᾱ_t / √(1 − ᾱ_t)), falling with t.
  double log_snr(int64_t t) const;

 private:
  std::vector<double> alpha_bar_;
};

}  // namespace nec::diffusion
