// Θ encoding and its exact inverse.
#include "nec/motion/features.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace nec {

Features encode_features(const Skeleton& skeleton, const Motion& motion) {
  if (motion.joint_count != skeleton.joint_count()) {
    throw std::invalid_argument("encode_features: motion and skeleton joint counts differ");
  }
  Features f;
  f.frame_count = motion.frame_count;
  f.joint_count = motion.joint_count;
  f.fps = motion.fps;
  f.data.assign(static_cast<size_t>(f.frame_count) * f.joint_count * kFeatureSize, 0.0f);
  if (f.frame_count == 0) return f;
  const Vec3 start = motion.translation(0, 0);
  f.start_xz = {start.x(), start.z()};
  for (int t = 0; t < f.frame_count; ++t) {
    const Vec3 position = motion.translation(t, 0);
    const Vec3 previous = t == 0 ? Vec3(start.x(), 0.0, start.z()) : motion.translation(t - 1, 0);
    const Vec3 delta = heading_rotation(motion.rotation(t, 0)).conjugate() * (position - previous);
    for (int k = 0; k < 3; ++k) f.at(t, 0, k) = static_cast<float>(delta[k]);
    for (int j = 0; j < f.joint_count; ++j) {
      const Rot6 r6 = matrix_to_rot6d(motion.rotation(t, j).toRotationMatrix());
      for (int k = 0; k < 6; ++k) f.at(t, j, 3 + k) = static_cast<float>(r6[k]);
    }
  }
  return f;
}

Motion decode_features(const Skeleton& skeleton, const Features& f) {
  if (f.joint_count != skeleton.joint_count()) {
    throw std::invalid_argument("decode_features: features have " + std::to_string(f.joint_count) +
                                " joints, skeleton has " + std::to_string(skeleton.joint_count()));
  }
  Motion m = Motion::rest(skeleton, f.frame_count, f.fps);
  Vec3 position(f.start_xz[0], 0.0, f.start_xz[1]);
  for (int t = 0; t < f.frame_count; ++t) {
    for (int j = 0; j < f.joint_count; ++j) {
      Rot6 r6;
      for (int k = 0; k < 6; ++k) r6[k] = f.at(t, j, 3 + k);
      m.rotation(t, j) = Quat(rot6d_to_matrix(r6)).normalized();
    }
    const Vec3 delta(f.at(t, 0, 0), f.at(t, 0, 1), f.at(t, 0, 2));
    position += heading_rotation(m.rotation(t, 0)) * delta;
    m.translation(t, 0) = position;
  }
  return m;
}

namespace {

Mat3 root_rotation(const Features& f, int frame) {
  Rot6 r6;
  for (int k = 0; k < 6; ++k) r6[k] = f.at(frame, 0, 3 + k);
  return rot6d_to_matrix(r6);
}

}  // namespace

double root_heading(const Features& f, int frame) {
  if (frame < 0 || frame >= f.frame_count || f.joint_count == 0) {
    throw std::out_of_range("root_heading: frame " + std::to_string(frame) + " of a clip of " +
                            std::to_string(f.frame_count) + " frames and " + std::to_string(f.joint_count) +
                            " joints");
  }
  return std::remainder(heading_angle(Quat(root_rotation(f, frame))), 2.0 * M_PI);
}

std::vector<double> root_heights(const Features& f, int frame_count) {
  if (frame_count < 0 || frame_count > f.frame_count || (frame_count > 0 && f.joint_count == 0)) {
    throw std::out_of_range("root_heights: " + std::to_string(frame_count) + " frames of a clip of " +
                            std::to_string(f.frame_count) + " frames and " + std::to_string(f.joint_count) + " joints");
  }
  std::vector<double> heights(frame_count);
  double height = 0.0;
  for (int t = 0; t < frame_count; ++t) heights[t] = height += f.at(t, 0, 1);
  return heights;
}

namespace {

// Premultiplies every root orientation by `turn`; with keep_path, turns every displacement back by it.
void turn_root(Features& f, const Mat3& turn, bool keep_path) {
  for (int t = 0; t < f.frame_count && f.joint_count > 0; ++t) {
    const Rot6 r6 = matrix_to_rot6d(turn * root_rotation(f, t));
    for (int k = 0; k < 6; ++k) f.at(t, 0, 3 + k) = static_cast<float>(r6[k]);
    if (!keep_path) continue;
    const Vec3 delta = turn.transpose() * Vec3(f.at(t, 0, 0), f.at(t, 0, 1), f.at(t, 0, 2));
    for (int k = 0; k < 3; ++k) f.at(t, 0, k) = static_cast<float>(delta[k]);
  }
}

}  // namespace

double turn_to_heading(Features& f, double heading) {
  if (f.frame_count == 0 || f.joint_count == 0) return 0.0;
  const double angle = std::remainder(heading - root_heading(f, 0), 2.0 * M_PI);
  turn_root(f, Eigen::AngleAxisd(angle, Vec3::UnitY()).toRotationMatrix(), /*keep_path=*/false);
  return angle;
}

void turn_body(Features& f, double angle) {
  turn_root(f, Eigen::AngleAxisd(angle, Vec3::UnitY()).toRotationMatrix(), /*keep_path=*/true);
}

}  // namespace nec
