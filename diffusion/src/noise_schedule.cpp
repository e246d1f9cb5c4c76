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

std::pair<int64_t, int64_t> NoiseSchedule::sampling_step(int64_t i, int64_t count) const {
  if (count < 1 || count > steps() || i < 0 || i >= count) {
    throw std::invalid_argument("sampling step " + std::to_string(i) + " of " + std::to_string(count) +
                                ": the count must be in [1, " + std::to_string(steps()) + "]");
  }
  const auto at = [&](int64_t k) {
    return count == 1 ? steps() - 1
                      : static_cast<int64_t>(std::llround(static_cast<double>(steps() - 1) *
                                                          static_cast<double>(count - 1 - k) / static_cast<double>(count - 1)));
  };
  return {at(i), i + 1 < count ? at(i + 1) : -1};
}

at::Tensor NoiseSchedule::ddim_step(const at::Tensor& x_t, const at::Tensor& predicted_x0, int64_t t,
                                    int64_t previous) const {
  if (previous < 0) return predicted_x0;
  const double a = alpha_bar(t), a_previous = alpha_bar(previous);
  const at::Tensor noise = (x_t - std::sqrt(a) * predicted_x0) / std::sqrt(1.0 - a);
  return std::sqrt(a_previous) * predicted_x0 + std::sqrt(1.0 - a_previous) * noise;
}

}  // namespace nec::diffusion
