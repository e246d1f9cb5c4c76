// Cosine noise schedule and DDIM steps.
#include "nec/diffusion/noise_schedule.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nec::diffusion {
namespace {

constexpr double kOffset = 0.008;   // s of the cosine schedule: keeps β small near t = 0
constexpr double kMaxBeta = 0.999;  // no timestep removes all of the signal at once

}  // namespace

NoiseSchedule::NoiseSchedule(int64_t steps) {
  if (steps < 2) throw std::invalid_argument("noise steps must be >= 2, got " + std::to_string(steps));
  const auto f = [steps](double u) {
    const double angle = (u / static_cast<double>(steps) + kOffset) / (1.0 + kOffset) * M_PI / 2.0;
    return std::cos(angle) * std::cos(angle);
  };
  double alpha_bar = 1.0;
  for (int64_t t = 0; t < steps; ++t) {
    const double beta = std::min(kMaxBeta, 1.0 - f(static_cast<double>(t + 1)) / f(static_cast<double>(t)));
    alpha_bar *= 1.0 - beta;
    alpha_bar_.push_back(alpha_bar);
  }
}

at::Tensor NoiseSchedule::add_noise(const at::Tensor& x0, const at::Tensor& noise, const at::Tensor& t) const {
  const at::Tensor table = torch::tensor(alpha_bar_, torch::kDouble).to(x0.device());
  std::vector<int64_t> shape(static_cast<size_t>(x0.dim()), 1);
  shape[0] = x0.size(0);
  const at::Tensor a = table.index_select(0, t.to(x0.device())).to(x0.scalar_type()).view(shape);
  return a.sqrt() * x0 + (1.0 - a).sqrt() * noise;
}

const char* to_string(TimestepSpacing spacing) { return spacing == TimestepSpacing::kUniform ? "uniform" : "quadratic"; }

std::vector<int64_t> NoiseSchedule::sampling_timesteps(int64_t count, TimestepSpacing spacing) const {
  if (count < 1 || count > steps()) {
    throw std::invalid_argument("sampling " + std::to_string(count) + " timesteps: the count must be in [1, " +
                                std::to_string(steps()) + "]");
  }
  std::vector<int64_t> timesteps(static_cast<size_t>(count));
  const double last = static_cast<double>(steps() - 1);
  // From the end: each at least one above the next, so that rounding never repeats a timestep.
  for (int64_t k = count - 1; k >= 0; --k) {
    const double u = count == 1 ? 1.0 : static_cast<double>(count - 1 - k) / static_cast<double>(count - 1);
    int64_t t = std::llround(last * (spacing == TimestepSpacing::kUniform ? u : u * u));
    if (k + 1 < count) t = std::max(t, timesteps[static_cast<size_t>(k + 1)] + 1);
    timesteps[static_cast<size_t>(k)] = t;
  }
  return timesteps;
}

at::Tensor NoiseSchedule::ddim_step(const at::Tensor& x_t, const at::Tensor& predicted_x0, int64_t t,
                                    int64_t previous) const {
  if (previous < 0) return predicted_x0;
  const double a = alpha_bar(t), a_previous = alpha_bar(previous);
  const at::Tensor noise = (x_t - std::sqrt(a) * predicted_x0) / std::sqrt(1.0 - a);
  return std::sqrt(a_previous) * predicted_x0 + std::sqrt(1.0 - a_previous) * noise;
}

double NoiseSchedule::log_snr(int64_t t) const {
  const double a = alpha_bar(t);
  return 0.5 * std::log(a / (1.0 - a));
}

at::Tensor NoiseSchedule::dpm_solver_step(const at::Tensor& x_t, const at::Tensor& predicted_x0,
                                          const at::Tensor& earlier_x0, int64_t earlier, int64_t t,
                                          int64_t previous) const {
  // The step onto timestep 0 is the schedule's longest in λ: extrapolating over it overshoots (DPM-Solver's
  // lower order at the end).
  if (previous <= 0 || !earlier_x0.defined()) return ddim_step(x_t, predicted_x0, t, previous);
  const double h = log_snr(previous) - log_snr(t), h_earlier = log_snr(t) - log_snr(earlier);
  const double r = h_earlier / h;
  const at::Tensor x0 = (1.0 + 0.5 / r) * predicted_x0 - (0.5 / r) * earlier_x0;
  return ddim_step(x_t, x0, t, previous);
}

}  // namespace nec::diffusion
