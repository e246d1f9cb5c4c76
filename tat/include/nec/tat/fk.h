// Differentiable forward kinematics of the feature tensor Θ in torch, so that
// position losses reach every joint directly (errors are not left to
// accumulate down the chain) and metrics can be computed on batches.
//
//   FkResult fk = features_to_positions(x.features, x.parents, x.offsets);
//   // fk.positions (B, T, J, 3): world positions, root trajectory integrated from Δ
//
// Conventions match motion/features.h and motion/rotations.h exactly:
// rot6D = (r00, r10, r20, r01, r11, r21), Gram–Schmidt back to a matrix; the
// root displacement Δ_t is in the heading frame of the root's rotation at t
// (heading = the yaw part of the swing–twist split about +Y, nec::heading_rotation);
// frame 0 starts at ground position (0, 0), so its Δ = (0, height, 0) lands at
// (0, height, 0). Padded joints (parent -1 other than joint 0) get the root's
// position and are to be masked by the caller.
#pragma once

#include <ATen/core/Tensor.h>

#include <vector>

namespace nec::tat {

// (..., 6) -> (..., 3, 3) rotation matrices (columns x, y, x × y).
at::Tensor rot6d_to_matrix(const at::Tensor& rot6d);
// (..., 3, 3) -> (..., 6), the inverse on rotation matrices.
at::Tensor matrix_to_rot6d(const at::Tensor& matrix);
// (..., 3, 3) rotation -> (..., 3, 3) rotation about +Y: its heading. Identity
// where the heading is undefined (rotation by pi about a horizontal axis).
at::Tensor heading_matrix(const at::Tensor& rotation);

// Windows (N, L, J, 9) of one clip, each turned about +Y so that its frame 0
// has the heading of window 0's frame 0 (the clip's start), as
// nec::turn_to_heading turns training crops (the root orientations only).
// Window 0 stays. A copy.
at::Tensor align_window_headings(const at::Tensor& windows);
// The inverse across a clip cut into windows starting at `starts` (frames,
// increasing, overlapping or back to back): window 0 stays; every later
// window is turned about +Y so that its frame 0 has the heading that the
// window before it (already turned) has at that frame, or at its last frame
// when they do not overlap. Decoded windows that each start with the clip's
// start heading so continue one another's turning. A copy.
at::Tensor continue_window_headings(const at::Tensor& windows, const std::vector<int64_t>& starts);

struct FkResult {
  at::Tensor positions;         // (B, T, J, 3) world positions
  at::Tensor global_rotations;  // (B, T, J, 3, 3)
};

// features (B, T, J, 9) float; parents (B, J) int64 (parents before children,
// -1 for the root and padding); offsets (B, J, 3) float rest offsets.
FkResult features_to_positions(const at::Tensor& features, const at::Tensor& parents, const at::Tensor& offsets);

}  // namespace nec::tat
