// Forward kinematics over all frames.
#include "nec/motion/kinematics.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace nec {
namespace {

void check_sizes(const Skeleton& skeleton, const Motion& motion) {
  if (motion.joint_count != skeleton.joint_count()) {
    throw std::invalid_argument("forward_kinematics: motion has " + std::to_string(motion.joint_count) +
                                " joints, skeleton has " + std::to_string(skeleton.joint_count()));
  }
}

// Global rotations and positions of one frame from its local rotations and translations.
inline void forward_kinematics_frame(const int* parents, int joints, const Quat* local, const Vec3* translation,
                                     Quat* global, Vec3* position) {
  global[0] = local[0];
  position[0] = translation[0];
  for (int j = 1; j < joints; ++j) {
    const int p = parents[j];
    global[j] = global[p] * local[j];
    position[j] = position[p] + global[p] * translation[j];
  }
}

}  // namespace

Pose forward_kinematics(const Skeleton& skeleton, const Motion& motion) {
  check_sizes(skeleton, motion);
  Pose pose;
  pose.frame_count = motion.frame_count;
  pose.joint_count = motion.joint_count;
  pose.rotations.resize(motion.rotations.size());
  pose.positions.resize(motion.rotations.size());
  const int joints = motion.joint_count;
  const int* parents = skeleton.parents.data();
  for (int t = 0; t < motion.frame_count; ++t) {
    const size_t base = static_cast<size_t>(t) * joints;
    forward_kinematics_frame(parents, joints, motion.rotations.data() + base, motion.translations.data() + base,
                             pose.rotations.data() + base, pose.positions.data() + base);
  }
  return pose;
}

void joint_positions(const Skeleton& skeleton, const Motion& motion, std::vector<Vec3>& positions) {
  check_sizes(skeleton, motion);
  const int joints = motion.joint_count;
  positions.resize(motion.rotations.size());
  std::vector<Quat> global(joints);
  const int* parents = skeleton.parents.data();
  for (int t = 0; t < motion.frame_count; ++t) {
    const size_t base = static_cast<size_t>(t) * joints;
    forward_kinematics_frame(parents, joints, motion.rotations.data() + base, motion.translations.data() + base,
                             global.data(), positions.data() + base);
  }
}

double horizontal_speed(const std::vector<Vec3>& positions, int joints, int joint, int frame, double fps) {
  const int frames = static_cast<int>(positions.size() / static_cast<size_t>(joints));
  const int a = std::max(0, frame - 1), b = std::min(frames - 1, frame + 1);
  if (a == b) return 0.0;
  Vec3 step = positions[static_cast<size_t>(b) * joints + joint] - positions[static_cast<size_t>(a) * joints + joint];
  step.y() = 0.0;
  return step.norm() * fps / (b - a);
}

std::vector<double> lowest_joint_heights(const std::vector<Vec3>& positions, int joints) {
  const size_t frames = positions.size() / static_cast<size_t>(joints);
  std::vector<double> lowest(frames);
  for (size_t t = 0; t < frames; ++t) {
    lowest[t] = positions[t * joints].y();
    for (int j = 1; j < joints; ++j) lowest[t] = std::min(lowest[t], positions[t * joints + j].y());
  }
  return lowest;
}

double lowest_height(const std::vector<Vec3>& positions) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const Vec3& p : positions) lowest = std::min(lowest, p.y());
  return lowest;
}

std::vector<Vec3> end_site_positions(const Skeleton& skeleton, const Pose& pose) {
  const size_t sites = skeleton.end_sites.size();
  std::vector<Vec3> out(static_cast<size_t>(pose.frame_count) * sites);
  for (int t = 0; t < pose.frame_count; ++t) {
    for (size_t e = 0; e < sites; ++e) {
      const EndSite& site = skeleton.end_sites[e];
      out[t * sites + e] = pose.position(t, site.parent) + pose.rotation(t, site.parent) * site.offset;
    }
  }
  return out;
}

}  // namespace nec
