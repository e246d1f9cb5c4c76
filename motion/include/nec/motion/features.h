// The feature tensor Θ (T, J, 9) that every model sees (NECromancer 4.1).
//
//   Features f = encode_features(skeleton, motion);   // f.at(t, j, k)
//   Motion back = decode_features(skeleton, f);       // equal up to float rounding
//
// Root (j = 0): [Δx, Δy, Δz, rot6D of the global root orientation], where Δ is
// the root displacement from the previous frame expressed in the current
// frame's heading (yaw-only) frame. Frame 0 holds (0, root height, 0); the
// frame-0 ground position (x, z) is kept in `start_xz` so the inverse is exact.
// Other joints: [0, 0, 0, rot6D of the local rotation].
#pragma once

#include "nec/motion/motion.h"

#include <array>
#include <vector>

namespace nec {

constexpr int kFeatureSize = 9;

struct Features {
  int frame_count = 0;
  int joint_count = 0;
  double fps = 30.0;
  std::array<double, 2> start_xz{0.0, 0.0};  // root ground position at frame 0
  std::vector<float> data;                    // (T, J, 9)

  float& at(int frame, int joint, int k) { return data[(static_cast<size_t>(frame) * joint_count + joint) * kFeatureSize + k]; }
  float at(int frame, int joint, int k) const { return data[(static_cast<size_t>(frame) * joint_count + joint) * kFeatureSize + k]; }
};

Features encode_features(const Skeleton& skeleton, const Motion& motion);
// Non-root joints get the skeleton's rest offsets as translations.
Motion decode_features(const Skeleton& skeleton, const Features& features);

// Heading of the root at `frame`: radians about +Y in [-pi, pi] (nec::heading_angle).
double root_heading(const Features& features, int frame);
// The root's height in frames [0, frame_count) (Θ's Δy summed; frame 0 holds the height): the heading
// frame turns about +Y only, so Δy is the height change.
std::vector<double> root_heights(const Features& features, int frame_count);
inline std::vector<double> root_heights(const Features& features) { return root_heights(features, features.frame_count); }
// Turns the motion about +Y (around its start point) so that the root's
// heading at frame 0 becomes `heading`: every root orientation is
// premultiplied by the same turn; the displacements, in each frame's own
// heading frame, stay as they are. Training crops start with the heading of
// their clip's frame 0 (where preprocessing made the body face +Z), and so do
// tokenizer windows: the tokens hold how a motion turns, never where it
// happens to face. Returns the angle turned (radians about +Y).
double turn_to_heading(Features& features, double heading);
// Turns the body about +Y by `angle` (radians) but not its path: every root
// orientation is premultiplied by the turn and every displacement, in its
// frame's heading frame, turned back by it, so the root goes where it went.
void turn_body(Features& features, double angle);

}  // namespace nec
