// Forward kinematics: global rotations and positions of every joint in every frame.
//
//   Pose pose = forward_kinematics(clip.skeleton, clip.motion);
//   Vec3 hand = pose.position(t, clip.skeleton.find("LeftHand"));
#pragma once

#include "nec/motion/motion.h"

#include <vector>

namespace nec {

struct Pose {
  int frame_count = 0;
  int joint_count = 0;
  std::vector<Quat> rotations;  // (T, J) global rotations
  std::vector<Vec3> positions;  // (T, J) global positions

  const Quat& rotation(int frame, int joint) const { return rotations[static_cast<size_t>(frame) * joint_count + joint]; }
  const Vec3& position(int frame, int joint) const { return positions[static_cast<size_t>(frame) * joint_count + joint]; }
};

Pose forward_kinematics(const Skeleton& skeleton, const Motion& motion);
// Positions only, written into `positions` (resized to T * J); reuses its storage.
void joint_positions(const Skeleton& skeleton, const Motion& motion, std::vector<Vec3>& positions);
// Horizontal (x, z) speed of `joint` at `frame`, units per second, from positions (T, J) as joint_positions
// writes them: a centred difference, one-sided at the clip's ends; 0 for a single frame.
double horizontal_speed(const std::vector<Vec3>& positions, int joints, int joint, int frame, double fps);
// Height (y) of the lowest joint in each frame, from positions (T, J) as joint_positions writes them.
std::vector<double> lowest_joint_heights(const std::vector<Vec3>& positions, int joints);
// The lowest height (y) any joint reaches in any frame: the clip's floor; +infinity for no positions.
double lowest_height(const std::vector<Vec3>& positions);
// Global positions of the end sites, (T, E) in skeleton.end_sites order.
std::vector<Vec3> end_site_positions(const Skeleton& skeleton, const Pose& pose);

}  // namespace nec
