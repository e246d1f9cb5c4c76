// Legs and two-bone reaching, shared by foot locking (fitting/foot_lock.h) and stepping
// (fitting/step_feet.h): internal to fitting/.
#pragma once

#include "nec/motion/kinematics.h"
#include "nec/motion/motion.h"

#include <utility>
#include <vector>

namespace nec::detail {

// A foot and the two joints that move it: the hip swings, the knee bends (-1: a one-joint leg only swings).
struct Leg {
  int foot = -1;
  int hip = -1;
  int knee = -1;
};

// The leg above `foot`: its parent and up to the first joint of the limb (the child of a joint with several
// children), at most four joints, never the root. An empty leg (hip -1) when the foot hangs from the root.
Leg leg_above(const Skeleton& skeleton, const std::vector<std::vector<int>>& children, int foot);

// Joint positions of every frame, (T, J).
struct Positions {
  std::vector<Vec3> data;
  int joints = 0;
  const Vec3& at(int t, int j) const { return data[static_cast<size_t>(t) * joints + j]; }
};

// A foot's own ground: the 10th percentile of its height over the clip (decoded feet do not all come down
// to the same height).
double foot_ground(const Positions& positions, int frames, int foot);

// Two-bone IK at frame t: bend the knee so that hip-to-foot is as long as hip-to-target (within reach), then
// swing the hip to put the foot on the target. `pose` must be the motion's FK; it is stale afterwards. Only
// the knee's and the hip's local rotations change, so bones keep their lengths.
void reach(const Skeleton& skeleton, const Pose& pose, Motion& motion, int t, const Leg& leg, const Vec3& target);

// Per leg and frame: the foot's target and how much it holds (0: leave the frame as it is).
using LegTargets = std::vector<std::vector<std::pair<double, Vec3>>>;

// Every leg reaches its targets of weight > 0 (reach, frame by frame); `positions` is refreshed to the new
// motion. Returns the largest distance left between a foot and a target of weight 1, in `size` units.
double reach_targets(const Skeleton& skeleton, Motion& motion, const std::vector<Leg>& legs, const LegTargets& targets,
                     Positions& positions, double size);

}  // namespace nec::detail
