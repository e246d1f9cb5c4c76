// MPJPE, GeoDist and the joints' turning kept on masked batches.
#include "nec/tat/metrics.h"

#include "nec/motion/statistics.h"
#include "nec/tat/fk.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>

namespace nec::tat {

at::Tensor degrees_from_trace(const at::Tensor& traces) {
  return ((traces - 1.0) / 2.0).clamp(-1.0, 1.0).acos() * (180.0 / M_PI);
}

at::Tensor pose_turn_degrees(const at::Tensor& rotations) {
  return degrees_from_trace(rotations.slice(2, 1).diagonal(0, -2, -1).sum(-1));
}

at::Tensor frame_turn_degrees(const at::Tensor& rotations) {
  const at::Tensor joints = rotations.slice(2, 1);
  const int64_t frames = joints.size(1);
  // tr(R_tᵀ R_t+1): the angle of the turn between frames.
  return degrees_from_trace((joints.narrow(1, 0, frames - 1) * joints.narrow(1, 1, frames - 1)).sum({-1, -2}));
}

void ReconstructionMetrics::add(const at::Tensor& prediction, const at::Tensor& features, const at::Tensor& parents,
                                const at::Tensor& offsets, const at::Tensor& joint_mask, const at::Tensor& frame_mask,
                                double scale) {
  torch::NoGradGuard no_grad;
  const FkResult predicted = features_to_positions(prediction.to(torch::kFloat64), parents, offsets.to(torch::kFloat64));
  const FkResult truth = features_to_positions(features.to(torch::kFloat64), parents, offsets.to(torch::kFloat64));
  // (B, T, J) weight of real joints in real frames.
  const at::Tensor mask = (frame_mask.unsqueeze(2) & joint_mask.unsqueeze(1)).to(torch::kFloat64);
  const at::Tensor world = (predicted.positions - truth.positions).norm(2, -1);
  const at::Tensor local = ((predicted.positions - predicted.positions.slice(2, 0, 1)) -
                            (truth.positions - truth.positions.slice(2, 0, 1)))
                               .norm(2, -1);
  // Rotations as stored: local for joints, global for the root.
  const at::Tensor r_pred = rot6d_to_matrix(prediction.slice(-1, 3, 9).to(torch::kFloat64));
  const at::Tensor r_true = rot6d_to_matrix(features.slice(-1, 3, 9).to(torch::kFloat64));
  const at::Tensor trace = (r_pred * r_true).sum({-1, -2});  // tr(R̂ᵀ R)
  const at::Tensor angle = degrees_from_trace(trace);
  const at::Tensor joints = mask.slice(2, 1);
  predicted_turn_sum += (pose_turn_degrees(r_pred) * joints).sum().item<double>();
  true_turn_sum += (pose_turn_degrees(r_true) * joints).sum().item<double>();
  position_error_sum += scale * (world * mask).sum().item<double>();
  local_position_error_sum += scale * (local * mask).sum().item<double>();
  angle_error_sum += (angle * mask).sum().item<double>();
  count += static_cast<int64_t>(mask.sum().item<double>());
}

void ReconstructionMetrics::add(const ReconstructionMetrics& other) {
  position_error_sum += other.position_error_sum;
  local_position_error_sum += other.local_position_error_sum;
  angle_error_sum += other.angle_error_sum;
  count += other.count;
  predicted_turn_sum += other.predicted_turn_sum;
  true_turn_sum += other.true_turn_sum;
}

namespace {

double height_range(const std::vector<double>& heights) {
  if (heights.empty()) return 0.0;
  const auto [low, high] = std::minmax_element(heights.begin(), heights.end());
  return *high - *low;
}

}  // namespace

void HeightRangeKept::add(const Features& decoded, const Features& truth) {
  const int frames = std::min(decoded.frame_count, truth.frame_count);
  const double real = height_range(root_heights(truth, frames));
  if (real >= min_range) ratios.push_back(height_range(root_heights(decoded, frames)) / real);
}

double HeightRangeKept::median() const { return nec::median(ratios); }

}  // namespace nec::tat
