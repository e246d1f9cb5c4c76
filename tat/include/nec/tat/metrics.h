// Reconstruction metrics (NECromancer appendix D): MPJPE with and without the
// root trajectory, and GeoDist, on batches of Θ with masks; how much of the joints' turning and of a clip's
// vertical motion comes back.
//
//   ReconstructionMetrics m;
//   m.add(prediction, target.features, target.parents, target.offsets, target.joint_mask, target.frame_mask);
//   double mpjpe = m.mpjpe();   // mean over every real joint of every real frame, normalized units
//   HeightRangeKept kept;
//   kept.add(decoded, truth);   // Features of one clip
//   double median = kept.median();
#pragma once

#include "nec/motion/features.h"

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <vector>

namespace nec::tat {

// The angle (degrees) of rotations from their traces: acos((tr R - 1) / 2), any shape.
at::Tensor degrees_from_trace(const at::Tensor& traces);
// rotations (B, T, J, 3, 3), local for joints (the rest pose is the identity), the root first. The degrees each
// joint other than the root is turned away from the rest pose, (B, T, J-1), and turns from frame to frame, (B, T-1, J-1).
at::Tensor pose_turn_degrees(const at::Tensor& rotations);
at::Tensor frame_turn_degrees(const at::Tensor& rotations);

struct ReconstructionMetrics {
  double position_error_sum = 0;       // Σ |p̂ - p| over joints × frames (world positions, root trajectory included)
  double local_position_error_sum = 0; // Σ |(p̂ - p̂_root) - (p - p_root)| (no root translation)
  double angle_error_sum = 0;          // Σ geodesic angle (degrees) between predicted and true rotations
  int64_t count = 0;                   // joints × frames summed
  // Σ angle (degrees) of the joints' local rotations away from the rest pose, root excluded: a decoder that
  // answers with the rest pose (a body standing still while its root travels) keeps 0 of the real turning
  // and still scores a GeoDist no worse than the clips' own spread.
  double predicted_turn_sum = 0, true_turn_sum = 0;

  // prediction, features (B, T, J, 9); parents (B, J); offsets (B, J, 3);
  // joint_mask (B, J) and frame_mask (B, T) bool. `scale` multiplies the
  // position errors (e.g. a clip's diameter to get the file's units).
  void add(const at::Tensor& prediction, const at::Tensor& features, const at::Tensor& parents,
           const at::Tensor& offsets, const at::Tensor& joint_mask, const at::Tensor& frame_mask, double scale = 1.0);
  void add(const ReconstructionMetrics& other);

  double mpjpe() const { return count ? position_error_sum / count : 0.0; }
  double mpjpe_no_translation() const { return count ? local_position_error_sum / count : 0.0; }
  double geodesic_degrees() const { return count ? angle_error_sum / count : 0.0; }
  // How much the joints turn away from the rest pose, decoded / real (1: as much as the real motion; 0: still).
  double pose_turn_kept() const { return true_turn_sum > 0 ? predicted_turn_sum / true_turn_sum : 0.0; }
};

// The range of the root's height (highest minus lowest, over the clip) of decoded clips divided by their
// real clips', for the clips whose root goes up or down by at least min_range (a jump, a sit, a lie-down; a
// walk's bob is noise here). MPJPE hardly sees a body that stays at one height; this does.
struct HeightRangeKept {
  double min_range = 0.05;     // normalized units (skeleton diameters)
  std::vector<double> ratios;  // one per clip that moves vertically

  // decoded and truth: Θ of one clip (frame counts may differ: the shorter one's frames are compared).
  void add(const Features& decoded, const Features& truth);
  void add(const HeightRangeKept& other) { ratios.insert(ratios.end(), other.ratios.begin(), other.ratios.end()); }
  // Median of the ratios; 0 when no clip moved vertically.
  double median() const;
};

}  // namespace nec::tat
