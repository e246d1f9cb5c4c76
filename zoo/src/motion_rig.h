// Internal to motion synthesis: small geometry helpers, and the rig every
// synthesis step reads (legs, midline, appendages) with its analysis.
#pragma once

#include "nec/zoo/motion_synthesis.h"

#include "zoo_math.h"

#include <algorithm>
#include <limits>
#include <vector>

namespace nec::zoo::detail {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

inline double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// 0 before a, 1 after b, smooth in between.
inline double ramp_between(double t, double a, double b) {
  return b > a ? smoothstep((t - a) / (b - a)) : (t >= b ? 1.0 : 0.0);
}

// 0 outside [rise_begin, fall_end], 1 on [rise_end, fall_begin], smooth ramps between.
inline double pulse(double t, double rise_begin, double rise_end, double fall_begin, double fall_end) {
  return ramp_between(t, rise_begin, rise_end) * (1.0 - ramp_between(t, fall_begin, fall_end));
}

inline Quat yaw_rotation(double angle) { return Quat(Eigen::AngleAxisd(angle, Vec3::UnitY())); }
inline Quat axis_angle(const Vec3& axis, double angle) { return Quat(Eigen::AngleAxisd(angle, axis)); }
// Body orientation: heading about +Y, then pitch (nose up for positive pitch), then roll.
inline Quat body_rotation(double yaw, double pitch, double roll) {
  return (yaw_rotation(yaw) * axis_angle(Vec3::UnitX(), -pitch) * axis_angle(Vec3::UnitZ(), roll)).normalized();
}

inline Vec3 flat(const Vec3& v) { return Vec3(v.x(), 0.0, v.z()); }
inline double side_sign(Side side) { return side == Side::Right ? -1.0 : 1.0; }

// ---------------------------------------------------------------------------
// Rig analysis

struct LegRig {
  int limb = 0;                 // index into Creature::limbs
  Side side = Side::None;
  int pair = 0;
  std::vector<int> joints;      // the limb's joints, hip ... tip
  int attach = 0;               // body joint the hip hangs from
  bool usable = false;          // a parent-child chain with at least one bone
  bool fixed_foot = false;      // the last bone (foot) keeps its rest direction, turned with the heading
  Vec3 foot_vector = Vec3::Zero();  // rest vector from joints[n-2] to the tip (fixed_foot)
  std::vector<double> lengths;  // (IK bones) hip -> IK end
  double reach = 0.0;           // sum of lengths
  double min_reach = 0.0;       // closest the IK end can come to the hip (folded)
  std::vector<Vec3> shape;      // (IK joints) bent template relative to the hip, body axes
  Vec3 neutral_from_attach = Vec3::Zero();  // neutral tip on the ground relative to the attach joint, body axes (xz)
  Vec3 hip_rest = Vec3::Zero();             // rest position of the hip, root at the origin
  Vec3 end_from_hip = Vec3::Zero();         // neutral IK end relative to the hip (body axes) at stand height
};

// Spine, neck, head and tail joints: the body's midline.
struct Midline {
  std::vector<char> member;     // (J) on the midline
  std::vector<double> arc;      // (J) signed path length from the root along the rest midline, + forward
  std::vector<double> bone_mid; // (J) arc at the middle of the joint's outgoing midline bone
  std::vector<int> chain_index; // (J) index within its neck/head/tail chain, from the body outward
  std::vector<LimbKind> kind;   // (J) Spine, Neck, Head or Tail
  double front = 0.0;           // largest arc (head tip)
  double back = 0.0;            // smallest arc (tail tip)
  int tail_length = 0;          // joints in the longest tail chain
  int neck_length = 0;          // joints in the neck + head chains
  std::vector<int> spine_index; // (J) index along Creature::spine, -1 elsewhere
};

// Arms, wings, fins: chains posed by rotations relative to their rest direction.
struct Appendage {
  const Limb* limb = nullptr;
  int pivot = 0;                // index into limb->joints of the joint that swings (arms: the upper arm)
  std::vector<double> lengths;  // (bones from the pivot)
  Vec3 lift_axis = Vec3::UnitZ();   // rotating about it by + raises the limb (body axes)
  Vec3 sweep_axis = Vec3::UnitY();  // rotating about it by + sweeps the limb backwards
  double rest_elevation = 0.0;      // radians above horizontal in the rest pose
};

struct Rig {
  std::vector<Vec3> rest;       // (J) rest positions with the root at the origin
  double rest_height = 1.0;     // Creature::rest_root_height
  double stand_height = 1.0;    // root height for standing motion (legs slightly bent)
  double leg_reach = 0.0;       // reach of the first usable leg, 0 without legs
  double body_length = 1.0;
  std::vector<LegRig> legs;     // usable or not, in Creature::limbs order
  Midline midline;
  std::vector<Appendage> arms, wings, fins;
  std::vector<const Limb*> antennae, jaws, trunks;
  double max_stance_travel = 0.0;  // most a stance foot may travel relative to its hip, min over legs
  double foot_radius = 0.0;        // largest horizontal distance of a neutral foot from the root
};

// The rig of a creature: rest positions, legs, midline, appendages, standing
// height and how far a stance foot may travel.
Rig analyze(const Creature& creature);
// Whether any leg is a chain IK can move.
bool has_usable_legs(const Rig& rig);

}  // namespace nec::zoo::detail
