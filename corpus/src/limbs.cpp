// How a person's limbs hang and swing (stance.h): upper arms against straight down, thighs' forward swing.
#include "nec/corpus/stance.h"

#include "nec/motion/kinematics.h"
#include "nec/motion/rotations.h"
#include "nec/motion/statistics.h"

#include <algorithm>
#include <cmath>

namespace nec {
namespace {

// The first joint called "<side> <part>" for one of `parts`; -1 when none has a child to make a bone.
int limb_joint(const Skeleton& skeleton, const std::vector<std::string>& names, const std::string& side,
               const std::vector<std::string>& parts) {
  for (const std::string& part : parts) {
    const std::string wanted = side + " " + part;
    const auto found = std::find(names.begin(), names.end(), wanted);
    if (found == names.end()) continue;
    const int joint = static_cast<int>(found - names.begin());
    return skeleton.children(joint).empty() ? -1 : joint;
  }
  return -1;
}

}  // namespace

LimbAngles measure_limbs(const Clip& normalized, const std::vector<std::string>& canonical_names) {
  const Skeleton& s = normalized.skeleton;
  LimbAngles out;
  // "shldr": the upper arm of Poser / MotionBuilder exports (CMU's lShldr).
  const std::vector<std::string> arm_names{"upper arm", "arm", "shldr"}, thigh_names{"upper leg", "leg"};
  const int arms[2] = {limb_joint(s, canonical_names, "left", arm_names),
                       limb_joint(s, canonical_names, "right", arm_names)};
  const int thighs[2] = {limb_joint(s, canonical_names, "left", thigh_names),
                         limb_joint(s, canonical_names, "right", thigh_names)};
  if (arms[0] < 0 || arms[1] < 0 || thighs[0] < 0 || thighs[1] < 0 || normalized.motion.frame_count == 0) return out;
  const Pose pose = forward_kinematics(s, normalized.motion);
  const Vec3 up = Vec3::UnitY();
  auto bone = [&](int t, int joint) {
    const Vec3 d = pose.position(t, s.children(joint).front()) - pose.position(t, joint);
    return Vec3(d.norm() > 1e-12 ? Vec3(d.normalized()) : Vec3(-up));
  };
  std::vector<double> hanging, pitch[2];
  for (int t = 0; t < normalized.motion.frame_count; ++t) {
    for (const int arm : arms) hanging.push_back(std::acos(std::clamp(-bone(t, arm).dot(up), -1.0, 1.0)));
    Vec3 across = pose.position(t, thighs[0]) - pose.position(t, thighs[1]);
    across.y() = 0.0;
    if (across.norm() < 1e-12) continue;
    const Vec3 forward = across.normalized().cross(up);
    for (int side = 0; side < 2; ++side) {
      const Vec3 d = bone(t, thighs[side]);
      pitch[side].push_back(std::atan2(d.dot(forward), -d.dot(up)));
    }
  }
  out.found = true;
  out.arms_from_hanging = upper_median(hanging) * kDegreesPerRadian;
  double swing = 0.0;
  for (const std::vector<double>& p : pitch) {
    if (!p.empty()) swing += 0.5 * (lower_quantile(p, 0.95) - lower_quantile(p, 0.05)) * kDegreesPerRadian;
  }
  out.thigh_swing = swing;
  return out;
}

}  // namespace nec
