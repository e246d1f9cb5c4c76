// Motion: frames of local joint rotations and translations on a Skeleton.
//
//   Motion m = Motion::rest(skeleton, /*frames=*/10, /*fps=*/30);
//   m.rotation(t, j) = euler_to_quat({0, 45, 0}, EulerOrder::XYZ);
//
// Rotations are local and relative to the rest pose (BVH semantics). The
// translation of a joint is its local position in the parent frame: the rest
// offset for joints without position channels, the channel values otherwise
// (position channels replace the offset, as Blender and MotionBuilder read
// them; three.js BVHLoader adds the offset, which agrees only when the offset
// of a joint with position channels is zero, as nec's normalized output is).
#pragma once

#include "nec/motion/skeleton.h"

#include <vector>

namespace nec {

struct Motion {
  double fps = 30.0;
  int frame_count = 0;
  int joint_count = 0;
  std::vector<Quat> rotations;     // (T, J) local unit quaternions
  std::vector<Vec3> translations;  // (T, J) local translations

  // T frames of the rest pose of `skeleton`.
  static Motion rest(const Skeleton& skeleton, int frames, double fps);

  Quat& rotation(int frame, int joint) { return rotations[index(frame, joint)]; }
  const Quat& rotation(int frame, int joint) const { return rotations[index(frame, joint)]; }
  Vec3& translation(int frame, int joint) { return translations[index(frame, joint)]; }
  const Vec3& translation(int frame, int joint) const { return translations[index(frame, joint)]; }
  double duration_seconds() const { return frame_count / fps; }
  // Frames [begin, end) as a new motion.
  Motion slice(int begin, int end) const;

 private:
  size_t index(int frame, int joint) const {
    return static_cast<size_t>(frame) * joint_count + joint;
  }
};

// A skeleton and a motion on it, as read from one file (or one animation of it).
struct Clip {
  Skeleton skeleton;
  Motion motion;
  std::vector<std::string> warnings;  // what the reader tolerated, e.g. extra lines
  std::string name{};                 // the animation's name in a file that holds several; "" for BVH
};

// Reorders the joints of a clip: new joint i is old joint order[i]. Parents
// must still precede children in the new order.
void permute_joints(Clip& clip, const std::vector<int>& order);

}  // namespace nec
