// Heading following: turn a transferred motion to face where its source faced.
#include "nec/motion/follow_heading.h"

#include "nec/motion/rotations.h"
#include "nec/motion/segment.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace nec {
namespace {

// Least-squares line through the values of a centred window of `width` frames (odd), read at its centre:
// the centred moving average inside the clip; near the ends, where the window is cut short, a trend is
// followed to the last frame instead of flattened.
std::vector<double> moving_line(const std::vector<double>& values, int width) {
  const int n = static_cast<int>(values.size()), half = width / 2;
  std::vector<double> sum_v(n + 1, 0.0), sum_tv(n + 1, 0.0);
  for (int t = 0; t < n; ++t) {
    sum_v[t + 1] = sum_v[t] + values[t];
    sum_tv[t + 1] = sum_tv[t] + t * values[t];
  }
  std::vector<double> out(values.size());
  for (int t = 0; t < n; ++t) {
    const int begin = std::max(0, t - half), end = std::min(n, t + half + 1);
    const double count = end - begin, mean_t = 0.5 * (begin + end - 1);
    const double mean_v = (sum_v[end] - sum_v[begin]) / count;
    // Σ (t' - mean_t)² over the window's frames: count (count² - 1) / 12.
    const double spread = count * (count * count - 1.0) / 12.0;
    const double slope =
        spread > 0.0 ? (sum_tv[end] - sum_tv[begin] - mean_t * (sum_v[end] - sum_v[begin])) / spread : 0.0;
    out[t] = mean_v + slope * (t - mean_t);
  }
  return out;
}

}  // namespace

void HeadingOptions::validate() const {
  if (!(smoothing_seconds > 0.0)) {
    throw std::invalid_argument("HeadingOptions: smoothing_seconds must be > 0, got " +
                                std::to_string(smoothing_seconds));
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
  const int width = 2 * static_cast<int>(std::lround(0.5 * options.smoothing_seconds * motion.fps)) + 1;
  const std::vector<double> turn = moving_line(moving_line(difference, width), width);

  HeadingReport report;
  Vec3 previous_source = motion.translation(0, 0);
  for (int t = 0; t < frames; ++t) {
    const Quat yaw = axis_rotation(1, turn[t]);
    Vec3& position = motion.translation(t, 0);
    const Vec3 step = position - previous_source;
    previous_source = position;
    if (t > 0) position = motion.translation(t - 1, 0) + yaw * step;
    motion.rotation(t, 0) = (yaw * motion.rotation(t, 0)).normalized();
    report.mean_turn += std::abs(turn[t]) / frames;
    report.max_turn = std::max(report.max_turn, std::abs(turn[t]));
  }
  return report;
}

}  // namespace nec
