// The diffusion process: a cosine noise schedule (Nichol & Dhariwal 2021)
// over `steps` timesteps, noising for training and DDIM steps (η = 0) that
// skip timesteps for sampling.
//
//   NoiseSchedule schedule(1000);
//   at::Tensor x_t = schedule.add_noise(x0, noise, t);          // t (B) int64 in [0, 1000)
//   for (int64_t i = 0; i < 50; ++i) {                          // 50 of the 1000 steps
//     const auto [t, previous] = schedule.sampling_step(i, 50);
//     x = schedule.ddim_step(x, predicted_x0, t, previous);      // previous = -1: the last step gives x0
//   }
//
// ᾱ(t) = f(t + 1) / f(0), f(u) = cos²((u / steps + s) / (1 + s) · π / 2), s = 0.008, with every
// β = 1 − ᾱ(t) / ᾱ(t − 1) clipped to at most 0.999 (so the last timestep is almost pure noise).
#pragma once

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace nec::diffusion {

class NoiseSchedule {
 public:
  // Throws std::invalid_argument for steps < 2.
  explicit NoiseSchedule(int64_t steps);

  int64_t steps() const { return static_cast<int64_t>(alpha_bar_.size()); }
  // ᾱ at timestep t in [0, steps): the share of the signal's variance left.
  double alpha_bar(int64_t t) const { return alpha_bar_.at(static_cast<size_t>(t)); }

  // x_t = √ᾱ_t x0 + √(1 − ᾱ_t) noise for t (B) int64; x0 and noise (B, ...).
  at::Tensor add_noise(const at::Tensor& x0, const at::Tensor& noise, const at::Tensor& t) const;

  // Step i of a sampler that visits `count` timesteps, evenly spaced from
  // steps − 1 down to 0: {its timestep, the next one (−1 after the last)}.
  std::pair<int64_t, int64_t> sampling_step(int64_t i, int64_t count) const;

  // DDIM (η = 0): from x_t and the predicted x0 to timestep `previous`
  // (< t; −1: x0 itself).
  at::Tensor ddim_step(const at::Tensor& x_t, const at::Tensor& predicted_x0, int64_t t, int64_t previous) const;

 private:
  std::vector<double> alpha_bar_;
};

}  // namespace nec::diffusion
