// Joint-frame conventions: the same motion on the same bones, written with other joint frames.
//
//   const std::vector<Quat> frames = mean_pose_frames(clip);          // (J), the clip's canonical rest
//   Clip canonical = reexpress_joint_frames(clip, frames);             // rest = mean pose, frames world-aligned there
//   Clip authored = reexpress_joint_frames(canonical, inverse_frames(frames));  // the rig as it was (rounding)
//   SplitMix64 rng(3);
//   Clip maya = reorient_joint_axes(clip, JointAxes::BonesAlongX, rng);  // every bone along its parent's +X
//
// A BVH rig fixes, per joint, the frame its local rotations are measured in;
// the rest pose (all rotations identity) is whatever those frames make. Two
// exports of one character (a T-pose with world-aligned frames, a Maya rig with
// every bone along +X and a straight line as its rest) give the same world
// positions with different local rotations. reexpress_joint_frames changes the
// frames and nothing else: with F_j the frame of joint j, the new global
// rotation is G_j F_j^-1, so local rotations become F_p q_j F_j^-1, offsets
// F_p o_j and end sites F_p e; every joint's world position in every frame is
// unchanged.
//
// The canonical rest (docs/features.md#canonical-rest-pose) is the mean pose
// of the motion: F_j is the chordal mean over frames of Y_t^-1 G_j(t), where Y_t
// is the root's turn about +Y since frame 0. Changing the authored frames
// (G_j -> G_j D_j) changes every F_j to F_j D_j, so the canonical clip is the same
// for every authoring convention; its rest is the motion's average pose facing
// where frame 0 faces, and at rest every joint frame is aligned with the world.
#pragma once

#include "nec/motion/motion.h"
#include "nec/motion/random.h"

#include <vector>

namespace nec {

// The skeleton with joint frames `frames` (J): offsets F_p o_j, end sites F_p e (the root's offset stays).
Skeleton reexpress_skeleton(const Skeleton& skeleton, const std::vector<Quat>& frames);
// The clip with joint frames `frames` (J); world positions unchanged. std::invalid_argument on a size mismatch.
Clip reexpress_joint_frames(const Clip& clip, const std::vector<Quat>& frames);
// F_j^-1 for every joint: undoes reexpress_joint_frames(., frames).
std::vector<Quat> inverse_frames(const std::vector<Quat>& frames);

// Chordal means of the yaw-free global rotations of every joint over the
// frames of one or more motions of one rig.
class MeanPoseFrames {
 public:
  explicit MeanPoseFrames(const Skeleton& skeleton);
  // Adds every frame of `motion`; `frames` (J, or empty for identity) are
  // the joint frames it was re-expressed with, so that the sum is in the
  // frames of the rig that was first given (a clip canonicalized on its own,
  // added to a rig-wide mean).
  void add(const Motion& motion, const std::vector<Quat>& frames = {});
  // (J) the mean frames; identity for a joint no frame was added for.
  std::vector<Quat> frames() const;

 private:
  Skeleton skeleton_;
  std::vector<Mat3> sums_;
};

// The canonical rest frames of one clip: MeanPoseFrames over its own frames.
std::vector<Quat> mean_pose_frames(const Clip& clip);

enum class JointAxes {
  BonesAlongX,  // each joint's +X along the bone to its first child (else its end site); the rest pose a straight line
  Random,       // a uniformly random frame per joint
};
// The clip in another joint-orient convention (reexpress_joint_frames), as
// other pipelines author rigs: a test rig for the canonical rest.
Clip reorient_joint_axes(const Clip& clip, JointAxes axes, SplitMix64& rng);

}  // namespace nec
