// Reconstruction metrics (NECromancer appendix D): MPJPE with and without the
// root trajectory, and GeoDist, on batches of Θ with masks.
//
//   ReconstructionMetrics m;
//   m.add(prediction, target.features, target.parents, target.offsets, target.joint_mask, target.frame_mask);
//   double mpjpe = m.mpjpe();   // mean over every real joint of every real frame, normalized units
#pragma once

#include <ATen/core/Tensor.h>

#include <cstdint>

namespace nec::tat {

struct ReconstructionMetrics {
  double position_error_sum = 0;       // Σ |p̂ - p| over joints × frames (world positions, root trajectory included)
  double local_position_error_sum = 0; // Σ |(p̂ - p̂_root) - (p - p_root)| (no root translation)
  double angle_error_sum = 0;          // Σ geodesic angle (degrees) between predicted and true rotations
  int64_t count = 0;                   // joints × frames summed

  // prediction, features (B, T, J, 9); parents (B, J); offsets (B, J, 3);
  // joint_mask (B, J) and frame_mask (B, T) bool. `scale` multiplies the
  // position errors (e.g. a clip's diameter to get the file's units).
  void add(const at::Tensor& prediction, const at::Tensor& features, const at::Tensor& parents,
           const at::Tensor& offsets, const at::Tensor& joint_mask, const at::Tensor& frame_mask, double scale = 1.0);
  void add(const ReconstructionMetrics& other);

  double mpjpe() const { return count ? position_error_sum / count : 0.0; }
  double mpjpe_no_translation() const { return count ? local_position_error_sum / count : 0.0; }
  double geodesic_degrees() const { return count ? angle_error_sum / count : 0.0; }
};

}  // namespace nec::tat
