// The tokenizer's view of Θ ("model space"): what its networks read and
// predict, converted exactly to and from Θ at its boundary.
//
//   at::Tensor m = features_to_model_space(x.features);           // (B, T, J, 9) -> (B, T, J, kModelChannels)
//   at::Tensor back = model_space_to_features(m, start_heading(x.features));  // Θ again (float rounding)
//
// Why: Θ's absolute root orientation and root-frame Δ hide turning, forward and height (docs/tokenizer.md).
// Model space, per root frame t (h_t = heading of the root, nec::heading_rotation):
//   [kRootMotionScale · Δx', y_t, kRootMotionScale · Δz', rot6D(R̃_t), kYawRateScale · ω_t]
// with y_t the root's height (Θ's Δy summed over frames 0..t), Δ' = Y(h_0) Δ (the body's heading frame: every window starts with its
// clip's start heading, where preprocessing made the body face +Z), R̃_t =
// Y(−h_t) R_t (the root orientation without its heading: lean and roll) and
// the yaw rate ω_t = h_t − h_{t−1} (radians per frame, wrapped; ω_0 = 0).
// Other joints: [0, 0, 0, rot6D, 0]. The start heading h_0 is not in model
// space: back to Θ takes it as an argument, R_t = Y(h_0 + ω_1 + … + ω_t) R̃_t
// and Δ = Y(−h_0) Δ'. Changing h_0 turns the body, not its path.
// Differentiable.
#pragma once

#include <ATen/core/Tensor.h>

#include <cstdint>

namespace nec::tat {

constexpr int64_t kModelChannels = 10;
// The root's motion is tiny beside the other features, and the yaw rate's errors add up (docs/tokenizer.md).
constexpr double kRootMotionScale = 20.0;  // Δx, Δz
constexpr double kYawRateScale = 60.0;     // ω

// features (B, T > 0, J > 0, 9) -> (B, T, J, kModelChannels); std::invalid_argument on other shapes.
at::Tensor features_to_model_space(const at::Tensor& features);
// (B, T > 0, J > 0, kModelChannels) and start_heading (B) radians -> Θ (B, T, J, 9).
at::Tensor model_space_to_features(const at::Tensor& model, const at::Tensor& start_heading);
// The root's heading at frame 0 of features (B, T > 0, J > 0, 9): (B) radians about +Y.
at::Tensor start_heading(const at::Tensor& features);

}  // namespace nec::tat
