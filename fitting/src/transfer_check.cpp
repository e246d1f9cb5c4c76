// Transfer checks: speed, heading, direction, foot plants and bone lengths of a clip.
#include "nec/fitting/transfer_check.h"

#include "nec/motion/kinematics.h"
#include "nec/motion/kinematic_signals.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace nec {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Angle a - b wrapped into (-180, 180].
double wrapped_difference(double a, double b) {
  double d = std::fmod(a - b, 360.0);
  if (d <= -180.0) d += 360.0;
  if (d > 180.0) d -= 360.0;
  return d;
}

}  // namespace

std::vector<bool> contact_frames(const std::vector<Vec3>& positions, int joints, int leaf, double floor, double size,
                                 double fps) {
  const int frames = static_cast<int>(positions.size()) / joints;
  std::vector<bool> contact(frames);
  for (int t = 0; t < frames; ++t) {
    const bool low = (positions[static_cast<size_t>(t) * joints + leaf].y() - floor) / size < kContactHeight;
    contact[t] = low && horizontal_speed(positions, joints, leaf, t, fps) / size < kContactSpeed;
  }
  return contact;
}

std::vector<int> touchdown_frames(const std::vector<bool>& contact) {
  std::vector<int> out;
  for (int t = 1; t + 1 < static_cast<int>(contact.size()); ++t) {
    if (contact[t] && contact[t + 1] && !contact[t - 1]) out.push_back(t);
  }
  return out;
}

namespace {

GaitMeasurements measure_gait(const Clip& clip, double size) {
  const Motion& m = clip.motion;
  const int frames = m.frame_count, joints = m.joint_count;
  std::vector<Vec3> positions;
  joint_positions(clip.skeleton, m, positions);
  auto at = [&](int t, int j) -> const Vec3& { return positions[static_cast<size_t>(t) * joints + j]; };
  const double floor = lowest_height(positions);

  GaitMeasurements gait;
  gait.skate = kNaN;
  if (frames < 3) return gait;
  long planted = 0, touchdowns = 0, low_frames = 0;
  double low_speed_sum = 0.0;
  for (const int leaf : clip.skeleton.leaves()) {
    for (int t = 0; t < frames; ++t) {
      if ((at(t, leaf).y() - floor) / size >= kContactHeight) continue;
      low_speed_sum += horizontal_speed(positions, joints, leaf, t, m.fps) / size;
      ++low_frames;
    }
    const std::vector<bool> contact = contact_frames(positions, joints, leaf, floor, size, m.fps);
    const long frames_planted = std::count(contact.begin(), contact.end(), true);
    if (frames_planted == 0) continue;
    ++gait.feet;
    planted += frames_planted;
    touchdowns += static_cast<long>(touchdown_frames(contact).size());
  }
  if (gait.feet > 0) gait.contact_fraction = static_cast<double>(planted) / (static_cast<double>(gait.feet) * frames);
  gait.touchdowns_per_second = touchdowns / m.duration_seconds();
  if (gait.feet > 0) gait.touchdowns_per_foot_second = gait.touchdowns_per_second / gait.feet;
  if (low_frames > 0) gait.skate = low_speed_sum / static_cast<double>(low_frames);
  return gait;
}

std::vector<double> lowest_heights(const Clip& clip, double size) {
  const Motion& m = clip.motion;
  std::vector<Vec3> positions;
  joint_positions(clip.skeleton, m, positions);
  const std::vector<double> lowest = lowest_joint_heights(positions, m.joint_count);
  const int window = std::max(1, static_cast<int>(std::lround(kFloorWindowSeconds * m.fps)));
  std::vector<double> out;
  for (int start = 0; start < m.frame_count; start += window) {
    const auto end = lowest.begin() + std::min(start + window, m.frame_count);
    out.push_back(*std::min_element(lowest.begin() + start, end) / size);
  }
  return out;
}

double floor_difference(const MotionMeasurements& source, const MotionMeasurements& output) {
  const size_t windows = std::min(source.lowest_heights.size(), output.lowest_heights.size());
  if (windows == 0) return kNaN;
  double largest = 0.0;
  for (size_t w = 0; w < windows; ++w) {
    largest = std::max(largest, std::abs(output.lowest_heights[w] - source.lowest_heights[w]));
  }
  return largest;
}

// TransferCheck::joint_distance.
double joint_distance(const Clip& source, const Clip& output) {
  if (source.skeleton.names != output.skeleton.names ||
      source.motion.frame_count != output.motion.frame_count) {
    return kNaN;
  }
  std::vector<Vec3> a, b;
  joint_positions(source.skeleton, source.motion, a);
  joint_positions(output.skeleton, output.motion, b);
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]).norm();
  return sum / static_cast<double>(a.size()) / source.skeleton.diameter();
}

}  // namespace

MotionMeasurements measure_motion(const Clip& clip) {
  const Motion& m = clip.motion;
  if (m.frame_count < 1) throw std::invalid_argument("measure_motion: the clip has no frames");
  if (!(m.fps > 0.0)) throw std::invalid_argument("measure_motion: fps must be positive");
  const double size = clip.skeleton.diameter();
  MotionMeasurements out;
  out.seconds = m.duration_seconds();

  const KinematicSignals signals = measure_kinematics(clip);
  double facing_x = 0.0, facing_z = 0.0;  // mean facing direction
  for (int t = 0; t < signals.frame_count(); ++t) {
    out.speed += signals.speed[t] / signals.frame_count();
    facing_x += std::sin(signals.heading[t] / kDegreesPerRadian);
    facing_z += std::cos(signals.heading[t] / kDegreesPerRadian);
  }
  out.heading_change = signals.heading.back() - signals.heading.front();
  const Vec3 first = m.translation(0, 0), last = m.translation(m.frame_count - 1, 0);
  const double dx = last.x() - first.x(), dz = last.z() - first.z();
  out.distance = std::hypot(dx, dz) / size;
  // The net displacement against the mean facing: a swaying body or a turn (whose
  // chord points along its mean facing) does not count.
  out.travel_direction = out.distance < kMinTravel ? kNaN
                                                   : wrapped_difference(kDegreesPerRadian * std::atan2(dx, dz),
                                                                        kDegreesPerRadian * std::atan2(facing_x, facing_z));

  out.gait = measure_gait(clip, size);
  out.lowest_heights = lowest_heights(clip, size);

  const std::vector<double> rest = clip.skeleton.bone_lengths();
  for (int t = 0; t < m.frame_count; ++t) {
    for (int j = 1; j < m.joint_count; ++j) {
      out.bone_length_change = std::max(out.bone_length_change, std::abs(m.translation(t, j).norm() - rest[j]) / size);
    }
  }
  return out;
}

TransferCheck check_transfer(const Clip& source, const Clip& output) {
  TransferCheck check;
  check.source = measure_motion(source);
  check.output = measure_motion(output);
  check.speed_ratio = check.source.speed > 1e-9 ? check.output.speed / check.source.speed : kNaN;
  check.heading_difference = check.output.heading_change - check.source.heading_change;
  check.direction_difference = std::isnan(check.source.travel_direction) || std::isnan(check.output.travel_direction)
                                   ? kNaN
                                   : wrapped_difference(check.output.travel_direction, check.source.travel_direction);
  check.joint_distance = joint_distance(source, output);
  check.floor_difference = floor_difference(check.source, check.output);
  return check;
}

}  // namespace nec
