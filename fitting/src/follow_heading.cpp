// Heading following: steer a transferred motion to face and go where its source does.
#include "nec/fitting/follow_heading.h"

#include "nec/motion/rotations.h"
#include "nec/motion/kinematic_signals.h"
#include "nec/fitting/smoothing.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace nec {
namespace {

// Root step from the frame before, horizontal, in body sizes; zero at frame 0.
Vec3 root_step(const Motion& motion, int t, double size) {
  if (t == 0) return Vec3::Zero();
  const Vec3 step = (motion.translation(t, 0) - motion.translation(t - 1, 0)) / size;
  return Vec3(step.x(), 0.0, step.z());
}

// Heading (degrees about +Y, + = left, 0 = +Z) of a horizontal vector.
double heading_of(const Vec3& v) { return std::atan2(v.x(), v.z()) * kDegreesPerRadian; }

}  // namespace

void HeadingOptions::validate() const {
  if (!(smoothing_seconds > 0.0)) {
    throw std::invalid_argument("HeadingOptions: smoothing_seconds must be > 0, got " +
                                std::to_string(smoothing_seconds));
  }
  if (!(still_speed > 0.0)) {
    throw std::invalid_argument("HeadingOptions: still_speed must be > 0, got " + std::to_string(still_speed));
  }
}

HeadingReport follow_heading(const Clip& source, const Skeleton& skeleton, Motion& motion,
                             const HeadingOptions& options) {
  options.validate();
  if (motion.joint_count != skeleton.joint_count()) {
    throw std::invalid_argument("follow_heading: the motion has " + std::to_string(motion.joint_count) +
                                " joints, the skeleton " + std::to_string(skeleton.joint_count()));
  }
  if (motion.frame_count != source.motion.frame_count || motion.frame_count < 1) {
    throw std::invalid_argument("follow_heading: the source has " + std::to_string(source.motion.frame_count) +
                                " frames, the motion " + std::to_string(motion.frame_count) +
                                " (they must be equal and at least 1)");
  }
  if (std::abs(motion.fps - source.motion.fps) > 1e-6 * source.motion.fps) {
    throw std::invalid_argument("follow_heading: the source runs at " + std::to_string(source.motion.fps) +
                                " fps, the motion at " + std::to_string(motion.fps));
  }
  const std::vector<double> wanted = measure_kinematics(source).heading;
  const std::vector<double> facing = measure_kinematics(Clip{skeleton, motion, {}}).heading;
  const int frames = motion.frame_count;
  std::vector<double> difference(frames);
  for (int t = 0; t < frames; ++t) difference[t] = wanted[t] - facing[t];
  // Both headings are unwrapped from their own first frame: take whole turns out of the difference there.
  const double whole_turns = 360.0 * std::round(difference[0] / 360.0);
  for (double& d : difference) d -= whole_turns;
  const int width = odd_window_frames(options.smoothing_seconds, motion.fps);
  const std::vector<double> body_turn = smooth_twice(difference, std::vector<double>(frames, 1.0), width);

  // The path's turn: per frame, the angle from the output's step to the source's (the representative nearest
  // the body's turn), weighted by the product of their lengths; where either stands still the body's turn
  // takes over (it weighs as much as a pair of steps at still_speed).
  const double still_step = options.still_speed / motion.fps;
  const double prior = still_step * still_step;
  std::vector<double> path_difference(frames), path_weight(frames);
  for (int t = 0; t < frames; ++t) {
    const Vec3 wanted_step = root_step(source.motion, t, source.skeleton.diameter());
    const Vec3 step = root_step(motion, t, skeleton.diameter());
    const double weight = wanted_step.norm() * step.norm();
    double angle = body_turn[t];
    if (weight > 0.0) {
      angle = heading_of(wanted_step) - heading_of(step);
      angle -= 360.0 * std::round((angle - body_turn[t]) / 360.0);
    }
    path_weight[t] = weight + prior;
    path_difference[t] = (weight * angle + prior * body_turn[t]) / path_weight[t];
  }
  const std::vector<double> path_turn = smooth_twice(path_difference, path_weight, width);

  HeadingReport report;
  Vec3 previous = motion.translation(0, 0);
  for (int t = 0; t < frames; ++t) {
    Vec3& position = motion.translation(t, 0);
    const Vec3 step = position - previous;
    previous = position;
    if (t > 0) position = motion.translation(t - 1, 0) + axis_rotation(1, path_turn[t]) * step;
    motion.rotation(t, 0) = (axis_rotation(1, body_turn[t]) * motion.rotation(t, 0)).normalized();
    report.mean_turn += std::abs(body_turn[t]) / frames;
    report.max_turn = std::max(report.max_turn, std::abs(body_turn[t]));
    report.max_path_turn = std::max(report.max_path_turn, std::abs(path_turn[t]));
  }
  return report;
}

}  // namespace nec
