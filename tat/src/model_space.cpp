// Θ <-> the tokenizer's model space (body-frame root displacement, turning as a yaw rate).
#include "nec/tat/model_space.h"

#include "nec/tat/fk.h"

#include <torch/torch.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace nec::tat {
namespace {

void check_shape(const at::Tensor& x, int64_t channels, const char* name) {
  if (!x.defined() || x.dim() != 4 || x.size(1) == 0 || x.size(2) == 0 || x.size(3) != channels) {
    throw std::invalid_argument(std::string(name) + ": expected (B, T > 0, J > 0, " + std::to_string(channels) + ")");
  }
}

// (...) angles -> (..., 3, 3) rotations about +Y.
at::Tensor yaw_matrix(const at::Tensor& angle) {
  const at::Tensor c = torch::cos(angle), s = torch::sin(angle), zero = torch::zeros_like(angle),
                   one = torch::ones_like(angle);
  std::vector<int64_t> shape = angle.sizes().vec();
  shape.insert(shape.end(), {3, 3});
  return torch::stack({c, zero, s, zero, one, zero, -s, zero, c}, -1).view(shape);
}

// Angle about +Y of rotations about +Y (..., 3, 3).
at::Tensor yaw_angle(const at::Tensor& heading) {
  return torch::atan2(heading.select(-2, 0).select(-1, 2), heading.select(-2, 0).select(-1, 0));
}

// Δ of root rows (B, T, 9 or kModelChannels) turned by `turn` (B, 3, 3) about +Y, x and z times `scale`
// (which commutes with the turn).
at::Tensor turned_displacement(const at::Tensor& root, const at::Tensor& turn, double scale) {
  const at::Tensor delta = torch::matmul(root.narrow(-1, 0, 3), turn.transpose(-1, -2));  // rows (turn · Δ)ᵀ
  const at::Tensor factor = torch::tensor({scale, 1.0, scale}, root.options());
  return delta * factor;
}

// Root rows (B, T, C) with Θ's Δy (frame 0: the height) in channel 1 -> the same with the height of every frame.
at::Tensor with_heights(const at::Tensor& root) {
  return torch::cat({root.narrow(-1, 0, 1), root.narrow(-1, 1, 1).cumsum(1), root.narrow(-1, 2, root.size(-1) - 2)}, -1);
}

// The inverse: root rows with the height of every frame in channel 1 -> Θ's Δy (frame 0: the height).
at::Tensor with_height_steps(const at::Tensor& root) {
  const at::Tensor height = root.narrow(-1, 1, 1);
  const int64_t later = root.size(1) - 1;
  const at::Tensor step = torch::cat({height.narrow(1, 0, 1), height.narrow(1, 1, later) - height.narrow(1, 0, later)}, 1);
  return torch::cat({root.narrow(-1, 0, 1), step, root.narrow(-1, 2, root.size(-1) - 2)}, -1);
}

// Yaw rates (B, T - 1) of frames 1.. -> (B, T) with frame 0's, which never turns, 0.
at::Tensor after_a_still_first_frame(const at::Tensor& later_rates) {
  return torch::constant_pad_nd(later_rates, {1, 0});
}

}  // namespace

at::Tensor features_to_model_space(const at::Tensor& features) {
  check_shape(features, 9, "features_to_model_space");
  const at::Tensor root = features.select(2, 0);                        // (B, T, 9)
  const at::Tensor rotation = rot6d_to_matrix(root.narrow(-1, 3, 6));    // (B, T, 3, 3)
  const at::Tensor heading = heading_matrix(rotation);                   // H_t
  // R̃_t = H_tᵀ R_t; ω_t = angle of H_{t-1}ᵀ H_t.
  const at::Tensor untwisted = torch::matmul(heading.transpose(-1, -2), rotation);
  const int64_t later = features.size(1) - 1;
  const at::Tensor step = torch::matmul(heading.narrow(1, 0, later).transpose(-1, -2), heading.narrow(1, 1, later));
  const at::Tensor rate = after_a_still_first_frame(yaw_angle(step));  // (B, T)
  const at::Tensor model_root = torch::cat({with_heights(turned_displacement(root, heading.select(1, 0), kRootMotionScale)),
                                            matrix_to_rot6d(untwisted), (rate * kYawRateScale).unsqueeze(-1)},
                                           -1);  // (B, T, 10)
  const at::Tensor others = torch::constant_pad_nd(features.narrow(2, 1, features.size(2) - 1), {0, 1});
  return torch::cat({model_root.unsqueeze(2), others}, 2);
}

at::Tensor model_space_to_features(const at::Tensor& model, const at::Tensor& start_heading) {
  check_shape(model, kModelChannels, "model_space_to_features");
  const int64_t b = model.size(0);
  if (!start_heading.defined() || start_heading.dim() != 1 || start_heading.size(0) != b) {
    throw std::invalid_argument("model_space_to_features: start_heading must be (B) = (" + std::to_string(b) + ")");
  }
  const at::Tensor root = model.select(2, 0);                           // (B, T, 10)
  const at::Tensor untwisted = rot6d_to_matrix(root.narrow(-1, 3, 6));  // R̃_t
  // h_0 + ω_1 + … + ω_t: frame 0 does not turn (ω_0 is 0 by definition).
  const at::Tensor predicted = root.select(-1, 9) / kYawRateScale;  // (B, T)
  const at::Tensor rate = after_a_still_first_frame(predicted.narrow(1, 1, predicted.size(1) - 1));
  const at::Tensor start = start_heading.to(model.scalar_type()).view({b, 1});
  const at::Tensor rotation = torch::matmul(yaw_matrix(start + rate.cumsum(1)), untwisted);  // R_t
  const at::Tensor feature_root =
      torch::cat({turned_displacement(with_height_steps(root), yaw_matrix(start.select(1, 0)).transpose(-1, -2),
                                      1.0 / kRootMotionScale),
                  matrix_to_rot6d(rotation)},
                 -1);  // (B, T, 9)
  return torch::cat({feature_root.unsqueeze(2), model.narrow(2, 1, model.size(2) - 1).narrow(-1, 0, 9)}, 2);
}

at::Tensor start_heading(const at::Tensor& features) {
  check_shape(features, 9, "start_heading");
  return yaw_angle(heading_matrix(rot6d_to_matrix(features.select(1, 0).select(1, 0).narrow(-1, 3, 6))));
}

}  // namespace nec::tat
