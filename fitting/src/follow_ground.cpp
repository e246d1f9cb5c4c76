// Ground following: lift or lower a decoded motion onto its floor.
#include "nec/fitting/follow_ground.h"

#include "nec/motion/kinematics.h"
#include "nec/fitting/smoothing.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace nec {
namespace {

void check_fits(const Skeleton& skeleton, const Motion& motion, const char* function) {
  if (motion.joint_count != skeleton.joint_count()) {
    throw std::invalid_argument(std::string(function) + ": the motion has " + std::to_string(motion.joint_count) +
                                " joints, the skeleton " + std::to_string(skeleton.joint_count()));
  }
}

// Per frame, the lowest joint's height at its lowest over a centred window of `width` frames, body sizes.
std::vector<double> standing_levels(const Skeleton& skeleton, const Motion& motion, int width) {
  std::vector<Vec3> positions;
  joint_positions(skeleton, motion, positions);
  const std::vector<double> lowest = lowest_joint_heights(positions, motion.joint_count);
  const double size = skeleton.diameter();
  const int frames = motion.frame_count, half = width / 2;
  std::vector<double> levels(frames);
  for (int t = 0; t < frames; ++t) {
    const auto begin = lowest.begin() + std::max(0, t - half), end = lowest.begin() + std::min(frames, t + half + 1);
    levels[t] = *std::min_element(begin, end) / size;
  }
  return levels;
}

// Adds the smoothed per-frame shift (body sizes) to the root's height.
GroundReport apply_shift(const Skeleton& skeleton, Motion& motion, const std::vector<double>& shift, int width) {
  const int frames = motion.frame_count;
  const std::vector<double> smooth = smooth_twice(shift, std::vector<double>(frames, 1.0), width);
  const double size = skeleton.diameter();
  GroundReport report;
  for (int t = 0; t < frames; ++t) {
    motion.translation(t, 0).y() += smooth[t] * size;
    report.mean_shift += std::abs(smooth[t]) / frames;
    report.max_shift = std::max(report.max_shift, std::abs(smooth[t]));
  }
  return report;
}

}  // namespace

void GroundOptions::validate() const {
  if (!(window_seconds > 0.0)) {
    throw std::invalid_argument("GroundOptions: window_seconds must be > 0, got " + std::to_string(window_seconds));
  }
  if (!(settle_height >= 0.0)) {
    throw std::invalid_argument("GroundOptions: settle_height must be >= 0, got " + std::to_string(settle_height));
  }
}

GroundReport follow_ground(const Clip& source, const Skeleton& skeleton, Motion& motion,
                           const GroundOptions& options) {
  options.validate();
  check_fits(skeleton, motion, "follow_ground");
  if (motion.frame_count != source.motion.frame_count || motion.frame_count < 1) {
    throw std::invalid_argument("follow_ground: the source has " + std::to_string(source.motion.frame_count) +
                                " frames, the motion " + std::to_string(motion.frame_count) +
                                " (they must be equal and at least 1)");
  }
  if (std::abs(motion.fps - source.motion.fps) > 1e-6 * source.motion.fps) {
    throw std::invalid_argument("follow_ground: the source runs at " + std::to_string(source.motion.fps) +
                                " fps, the motion at " + std::to_string(motion.fps));
  }
  const int width = odd_window_frames(options.window_seconds, motion.fps);
  const std::vector<double> wanted = standing_levels(source.skeleton, source.motion, width);
  std::vector<double> shift = standing_levels(skeleton, motion, width);
  for (size_t t = 0; t < shift.size(); ++t) shift[t] = wanted[t] - shift[t];
  return apply_shift(skeleton, motion, shift, width);
}

GroundReport settle_on_ground(const Skeleton& skeleton, Motion& motion, const GroundOptions& options) {
  options.validate();
  check_fits(skeleton, motion, "settle_on_ground");
  if (motion.frame_count < 1) return {};
  const int width = odd_window_frames(options.window_seconds, motion.fps);
  std::vector<double> shift = standing_levels(skeleton, motion, width);
  for (double& s : shift) s = s < options.settle_height ? -s : 0.0;
  return apply_shift(skeleton, motion, shift, width);
}

}  // namespace nec
