// Procedural motion synthesis: rig analysis (legs, midline, appendages),
// root trajectory, body pose per action, leg stance planning with planted
// feet, root height adjustment for reach, and leg inverse kinematics.
#include "nec/zoo/motion_synthesis.h"

#include "nec/motion/kinematics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace nec::zoo {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

double radians(double degrees) { return degrees * kPi / 180.0; }

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// 0 before a, 1 after b, smooth in between.
double ramp_between(double t, double a, double b) { return b > a ? smoothstep((t - a) / (b - a)) : (t >= b ? 1.0 : 0.0); }

// 0 outside [rise_begin, fall_end], 1 on [rise_end, fall_begin], smooth ramps between.
double pulse(double t, double rise_begin, double rise_end, double fall_begin, double fall_end) {
  return ramp_between(t, rise_begin, rise_end) * (1.0 - ramp_between(t, fall_begin, fall_end));
}

Quat yaw_rotation(double angle) { return Quat(Eigen::AngleAxisd(angle, Vec3::UnitY())); }
Quat axis_angle(const Vec3& axis, double angle) { return Quat(Eigen::AngleAxisd(angle, axis)); }
// Body orientation: heading about +Y, then pitch (nose up for positive pitch), then roll.
Quat body_rotation(double yaw, double pitch, double roll) {
  return (yaw_rotation(yaw) * axis_angle(Vec3::UnitX(), -pitch) * axis_angle(Vec3::UnitZ(), roll)).normalized();
}

Vec3 flat(const Vec3& v) { return Vec3(v.x(), 0.0, v.z()); }
double side_sign(Side side) { return side == Side::Right ? -1.0 : 1.0; }

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
  std::vector<const Limb*> antennae, jaws;
  double max_stance_travel = 0.0;  // most a stance foot may travel relative to its hip, min over legs
  double foot_radius = 0.0;        // largest horizontal distance of a neutral foot from the root
};

std::vector<Vec3> rest_positions(const Skeleton& skeleton) {
  Motion rest = Motion::rest(skeleton, 1, 30.0);
  rest.translation(0, 0) = Vec3::Zero();
  std::vector<Vec3> positions;
  joint_positions(skeleton, rest, positions);
  return positions;
}

bool is_chain(const Skeleton& skeleton, const std::vector<int>& joints) {
  if (joints.empty()) return false;
  for (size_t k = 1; k < joints.size(); ++k) {
    if (skeleton.parents[joints[k]] != joints[k - 1]) return false;
  }
  return skeleton.parents[joints[0]] >= 0;
}

// Default knee direction (body axes) for a straight rest leg.
Vec3 default_pole(BodyPlan plan, const Limb& leg) {
  switch (plan) {
    case BodyPlan::Quadruped:
    case BodyPlan::Dragon:
      return leg.pair == 0 ? Vec3(0, 0, -1) : Vec3(0, 0, 1);
    case BodyPlan::Hexapod:
    case BodyPlan::Spider:
    case BodyPlan::Centipede:
      return Vec3(0.5 * side_sign(leg.side), 1.0, 0.0).normalized();
    default:
      return Vec3(0, 0, 1);
  }
}

LegRig analyze_leg(const Creature& creature, int limb_index, const std::vector<Vec3>& rest) {
  const Skeleton& s = creature.skeleton;
  const Limb& limb = creature.limbs[limb_index];
  LegRig leg;
  leg.limb = limb_index;
  leg.side = limb.side;
  leg.pair = limb.pair;
  leg.joints = limb.joints;
  if (!is_chain(s, leg.joints) || leg.joints.size() < 2) return leg;
  leg.attach = s.parents[leg.joints[0]];
  const int n = static_cast<int>(leg.joints.size());
  std::vector<double> bones;
  double total = 0.0;
  for (int k = 0; k + 1 < n; ++k) {
    bones.push_back(s.offsets[leg.joints[k + 1]].norm());
    total += bones.back();
  }
  if (total < 1e-9) return leg;
  leg.usable = true;
  // A foot lying flat-ish on the ground (plantigrade, a human foot) keeps its
  // rest direction; an upright last segment (hoof, paw, claw) is part of the IK chain.
  const int bone_count = n - 1;
  const Vec3 last_bone = rest[leg.joints[n - 1]] - rest[leg.joints[n - 2]];
  leg.fixed_foot = bone_count >= 3 && bones.back() < 0.3 * total && std::abs(last_bone.y()) < 0.6 * last_bone.norm();
  const int ik_joints = leg.fixed_foot ? n - 1 : n;
  if (leg.fixed_foot) leg.foot_vector = rest[leg.joints[n - 1]] - rest[leg.joints[n - 2]];
  leg.lengths.assign(bones.begin(), bones.begin() + (ik_joints - 1));
  for (double l : leg.lengths) leg.reach += l;
  const double longest = *std::max_element(leg.lengths.begin(), leg.lengths.end());
  leg.min_reach = std::max(0.0, 2.0 * longest - leg.reach);
  leg.hip_rest = rest[leg.joints[0]];

  // Template shape: the rest chain, or a zigzag when the rest chain is straight.
  const Vec3 hip = leg.hip_rest;
  const Vec3 end = rest[leg.joints[ik_joints - 1]];
  const Vec3 axis = (end - hip).norm() > 1e-9 ? Vec3((end - hip).normalized()) : Vec3(0, -1, 0);
  double bend = 0.0;
  for (int k = 1; k + 1 < ik_joints; ++k) {
    const Vec3 d = rest[leg.joints[k]] - hip;
    bend = std::max(bend, (d - d.dot(axis) * axis).norm());
  }
  leg.shape.resize(ik_joints);
  if (ik_joints <= 2 || bend > 0.06 * leg.reach) {
    for (int k = 0; k < ik_joints; ++k) leg.shape[k] = rest[leg.joints[k]] - hip;
  } else {
    Vec3 pole = default_pole(creature.plan, limb);
    pole = pole - pole.dot(axis) * axis;
    if (pole.norm() < 1e-6) pole = axis.cross(Vec3::UnitX());
    pole.normalize();
    const double angle = radians(ik_joints == 3 ? 30.0 : 25.0);
    leg.shape[0] = Vec3::Zero();
    for (int k = 0; k + 1 < ik_joints; ++k) {
      const double sign = k % 2 == 0 ? 1.0 : -1.0;
      const Vec3 direction = (axis * std::cos(angle) + pole * (sign * std::sin(angle))).normalized();
      leg.shape[k + 1] = leg.shape[k] + direction * leg.lengths[k];
    }
  }

  // Neutral foot: the rest tip over the ground, pulled in when the hip could not reach it comfortably.
  Vec3 tip = flat(rest[leg.joints[n - 1]]);
  const Vec3 foot_flat = leg.fixed_foot ? flat(leg.foot_vector) : Vec3::Zero();
  Vec3 end_offset = tip - foot_flat - flat(hip);
  const double limit = 0.75 * leg.reach;
  if (end_offset.norm() > limit) {
    end_offset *= limit / end_offset.norm();
    tip = flat(hip) + end_offset + foot_flat;
  }
  leg.neutral_from_attach = tip - flat(rest[leg.attach]);
  return leg;
}

Midline analyze_midline(const Creature& creature, const std::vector<Vec3>& rest) {
  const Skeleton& s = creature.skeleton;
  const int joints = s.joint_count();
  Midline m;
  m.member.assign(joints, 0);
  m.arc.assign(joints, 0.0);
  m.bone_mid.assign(joints, 0.0);
  m.chain_index.assign(joints, 0);
  m.kind.assign(joints, LimbKind::Spine);
  m.spine_index.assign(joints, -1);
  std::vector<double> direction(joints, 1.0);  // +1: the bone into this joint points forward
  for (size_t i = 0; i < creature.spine.size(); ++i) {
    const int j = creature.spine[i];
    if (j < 0 || j >= joints) continue;
    m.member[j] = 1;
    m.spine_index[j] = static_cast<int>(i);
  }
  m.member[0] = 1;
  for (const Limb& limb : creature.limbs) {
    const bool midline_kind = limb.kind == LimbKind::Spine || limb.kind == LimbKind::Neck ||
                              limb.kind == LimbKind::Head || limb.kind == LimbKind::Tail;
    if (!midline_kind || limb.side != Side::None) continue;
    for (size_t i = 0; i < limb.joints.size(); ++i) {
      const int j = limb.joints[i];
      if (j < 0 || j >= joints || m.spine_index[j] >= 0) continue;
      m.member[j] = 1;
      m.kind[j] = limb.kind;
      m.chain_index[j] = static_cast<int>(i);
      direction[j] = limb.kind == LimbKind::Tail ? -1.0 : 1.0;
    }
    if (limb.kind == LimbKind::Tail) m.tail_length = std::max(m.tail_length, static_cast<int>(limb.joints.size()));
    if (limb.kind == LimbKind::Neck || limb.kind == LimbKind::Head) {
      m.neck_length += static_cast<int>(limb.joints.size());
    }
  }
  // Head chains continue the neck: number them after it.
  int neck_joints = 0;
  for (const Limb& limb : creature.limbs) {
    if (limb.kind == LimbKind::Neck && limb.side == Side::None) neck_joints = static_cast<int>(limb.joints.size());
  }
  for (const Limb& limb : creature.limbs) {
    if (limb.kind != LimbKind::Head || limb.side != Side::None) continue;
    for (size_t i = 0; i < limb.joints.size(); ++i) {
      if (limb.joints[i] >= 0 && limb.joints[i] < joints) m.chain_index[limb.joints[i]] = neck_joints + static_cast<int>(i);
    }
  }
  // Arc coordinates: path length from the root, signed by which way the chain runs.
  for (int j = 1; j < joints; ++j) {
    if (!m.member[j]) continue;
    const int p = s.parents[j];
    const Vec3 step = rest[j] - rest[p];
    const double length = step.norm();
    double sign = m.member[p] && p != 0 ? direction[p] : direction[j];
    if (length > 1e-12 && std::abs(step.z()) > 0.3 * length) sign = step.z() > 0 ? 1.0 : -1.0;
    direction[j] = sign;
    m.arc[j] = (m.member[p] ? m.arc[p] : rest[p].z()) + sign * length;
  }
  m.front = 0.0;
  m.back = 0.0;
  for (int j = 0; j < joints; ++j) {
    if (!m.member[j]) continue;
    m.front = std::max(m.front, m.arc[j]);
    m.back = std::min(m.back, m.arc[j]);
    m.bone_mid[j] = m.arc[j];
  }
  // Outgoing bone middles (a joint with several midline children, like the root, keeps its own arc).
  std::vector<int> midline_children(joints, 0);
  for (int j = 1; j < joints; ++j) {
    if (m.member[j] && m.member[s.parents[j]]) ++midline_children[s.parents[j]];
  }
  for (int j = 1; j < joints; ++j) {
    const int p = s.parents[j];
    if (m.member[j] && m.member[p] && midline_children[p] == 1) m.bone_mid[p] = 0.5 * (m.arc[p] + m.arc[j]);
  }
  for (const EndSite& site : s.end_sites) {
    if (site.parent < 0 || site.parent >= joints || !m.member[site.parent]) continue;
    const double sign = direction[site.parent];
    const double tip = m.arc[site.parent] + sign * site.offset.norm();
    m.front = std::max(m.front, tip);
    m.back = std::min(m.back, tip);
    if (midline_children[site.parent] == 0) m.bone_mid[site.parent] = 0.5 * (m.arc[site.parent] + tip);
  }
  return m;
}

Appendage analyze_appendage(const Creature& creature, const Limb& limb, const std::vector<Vec3>& rest) {
  const Skeleton& s = creature.skeleton;
  Appendage a;
  a.limb = &limb;
  const int n = static_cast<int>(limb.joints.size());
  std::vector<double> bones;
  for (int k = 0; k + 1 < n; ++k) bones.push_back(s.offsets[limb.joints[k + 1]].norm());
  // Arms swing at the upper arm: the start of the longest pair of consecutive bones.
  double best = -1.0;
  for (int k = 0; k + 1 < n; ++k) {
    const double pair = bones[k] + (k + 1 < static_cast<int>(bones.size()) ? bones[k + 1] : 0.0);
    if (pair > best + 1e-12) {
      best = pair;
      a.pivot = k;
    }
  }
  if (limb.kind != LimbKind::Arm) a.pivot = 0;
  for (int k = a.pivot; k + 1 < n; ++k) a.lengths.push_back(bones[k]);
  const Vec3 direction = rest[limb.joints[n - 1]] - rest[limb.joints[0]];
  Vec3 horizontal = flat(direction);
  if (horizontal.norm() < 1e-9 * std::max(direction.norm(), 1e-12)) horizontal = Vec3(side_sign(limb.side), 0, 0);
  horizontal.normalize();
  a.lift_axis = horizontal.cross(Vec3::UnitY()).normalized();
  a.sweep_axis = Vec3::UnitY() * side_sign(limb.side);
  a.rest_elevation = std::atan2(direction.y(), flat(direction).norm());
  return a;
}

// Gait timing per plan: speed in leg lengths per second and stride frequency
// (Hz) at that speed, and step height in leg lengths.
struct GaitTuning {
  double leg_speed = 1.5;   // typical speed, leg lengths per second
  double frequency = 1.0;   // stride cycles per second at the typical speed
  double step_height = 0.12;
};

GaitTuning gait_tuning(BodyPlan plan, Action action) {
  const bool trot = action == Action::Trot;
  const bool fast = action == Action::Run || action == Action::Gallop;
  switch (plan) {
    case BodyPlan::Quadruped:
      return trot ? GaitTuning{2.6, 1.5, 0.15} : fast ? GaitTuning{5.0, 2.0, 0.2} : GaitTuning{1.3, 0.9, 0.12};
    case BodyPlan::Dragon:
      return trot ? GaitTuning{2.0, 1.1, 0.15} : fast ? GaitTuning{3.8, 1.5, 0.2} : GaitTuning{1.0, 0.7, 0.12};
    case BodyPlan::Hexapod:
      return fast ? GaitTuning{5.0, 3.5, 0.22} : GaitTuning{2.2, 2.0, 0.2};
    case BodyPlan::Spider:
      return fast ? GaitTuning{4.5, 3.0, 0.25} : GaitTuning{1.8, 1.6, 0.2};
    case BodyPlan::Centipede:
      return fast ? GaitTuning{3.5, 2.6, 0.3} : GaitTuning{1.8, 1.6, 0.25};
    case BodyPlan::Bird:
      return fast ? GaitTuning{4.5, 2.3, 0.2} : GaitTuning{1.8, 1.5, 0.15};
    default:
      return fast ? GaitTuning{4.0, 1.4, 0.2} : GaitTuning{1.5, 0.95, 0.12};
  }
}

constexpr double kTailLag = 1.8;           // phase lag of the tail tip's sway behind its base, radians
constexpr double kMinSwingSeconds = 0.1;  // shortest swing the cadence may demand (3 frames at 30 fps)
constexpr double kStandReach = 0.9;        // standing: hip to foot at 90% of the leg's reach
constexpr double kMaxReach = 0.985;        // the root is lowered so stance legs never stretch beyond this

Rig analyze(const Creature& creature) {
  const Skeleton& s = creature.skeleton;
  Rig rig;
  rig.rest = rest_positions(s);
  rig.rest_height = creature.rest_root_height;
  rig.body_length = creature.body_length > 0.0 ? creature.body_length : std::max(s.diameter(), 1e-6);
  for (int i = 0; i < static_cast<int>(creature.limbs.size()); ++i) {
    const Limb& limb = creature.limbs[i];
    switch (limb.kind) {
      case LimbKind::Leg:
        rig.legs.push_back(analyze_leg(creature, i, rig.rest));
        break;
      case LimbKind::Arm:
        if (is_chain(s, limb.joints) && limb.joints.size() >= 2) rig.arms.push_back(analyze_appendage(creature, limb, rig.rest));
        break;
      case LimbKind::Wing:
        if (is_chain(s, limb.joints) && limb.joints.size() >= 2) rig.wings.push_back(analyze_appendage(creature, limb, rig.rest));
        break;
      case LimbKind::Fin:
        if (is_chain(s, limb.joints) && !limb.joints.empty()) rig.fins.push_back(analyze_appendage(creature, limb, rig.rest));
        break;
      case LimbKind::Antenna:
        rig.antennae.push_back(&limb);
        break;
      case LimbKind::Jaw:
        rig.jaws.push_back(&limb);
        break;
      default:
        break;
    }
  }
  rig.midline = analyze_midline(creature, rig.rest);

  // Standing height: every usable leg reaches its neutral foot at kStandReach.
  rig.stand_height = rig.rest_height;
  for (const LegRig& leg : rig.legs) {
    if (!leg.usable) continue;
    if (rig.leg_reach == 0.0) rig.leg_reach = leg.reach;
    const Vec3 tip = flat(rig.rest[leg.attach]) + leg.neutral_from_attach;
    const Vec3 end = tip - (leg.fixed_foot ? leg.foot_vector : Vec3::Zero());  // world y of the end is -foot.y
    const double horizontal = flat(end - leg.hip_rest).norm();
    const double vertical = std::sqrt(std::max(0.0, std::pow(kStandReach * leg.reach, 2) - horizontal * horizontal));
    rig.stand_height = std::min(rig.stand_height, end.y() - leg.hip_rest.y() + vertical);
  }
  rig.stand_height = std::max(rig.stand_height, 0.3 * rig.rest_height);

  // Stance travel: how far a foot may move along the body relative to its hip.
  rig.max_stance_travel = kInfinity;
  for (LegRig& leg : rig.legs) {
    if (!leg.usable) continue;
    const Vec3 tip = flat(rig.rest[leg.attach]) + leg.neutral_from_attach;
    Vec3 end = tip - (leg.fixed_foot ? leg.foot_vector : Vec3::Zero());
    const Vec3 hip_standing = leg.hip_rest + Vec3(0.0, rig.stand_height, 0.0);
    leg.end_from_hip = end - hip_standing;
    const double height = hip_standing.y() - 0.1 * leg.reach - end.y();
    const double room = std::pow(0.97 * leg.reach, 2) - height * height - std::pow(leg.end_from_hip.x(), 2);
    const double travel = room > 0.0 ? std::sqrt(room) - std::abs(leg.end_from_hip.z()) : 0.0;
    rig.max_stance_travel = std::min(rig.max_stance_travel, std::max(2.0 * 0.9 * travel, 0.1 * leg.reach));
    rig.foot_radius = std::max(rig.foot_radius, tip.norm());
  }
  if (!std::isfinite(rig.max_stance_travel)) rig.max_stance_travel = 0.0;
  return rig;
}

bool has_usable_legs(const Rig& rig) {
  for (const LegRig& leg : rig.legs) {
    if (leg.usable) return true;
  }
  return false;
}

// Body-length speeds of the non-gait actions.
double typical_body_speed(Action action) {
  switch (action) {
    case Action::Slither: return 0.25;
    case Action::Swim: return 0.8;
    case Action::Fly:
    case Action::Glide: return 2.5;
    case Action::TakeOff: return 1.5;
    default: return 0.0;
  }
}

double max_gait_frequency(double duty_factor) { return (1.0 - duty_factor) / kMinSwingSeconds; }

// Fastest a gait can go (body lengths per second): the legs' stance travel at the highest cadence.
double gait_speed_limit(const Creature& creature, const Rig& rig, Action action) {
  if (!has_usable_legs(rig)) return 0.0;
  const GaitPattern gait = gait_pattern(creature, action);
  const double frequency = std::min(max_gait_frequency(gait.duty_factor), 2.5 * gait_tuning(creature.plan, action).frequency);
  return rig.max_stance_travel * frequency / gait.duty_factor / rig.body_length;
}

double typical_speed(const Creature& creature, const Rig& rig, Action action) {
  if (is_gait(action)) {
    if (action == Action::Turn) return 0.0;
    // The plan's usual speed, kept well inside what its legs can do.
    const double usual = gait_tuning(creature.plan, action).leg_speed * rig.leg_reach / rig.body_length;
    return std::min(usual, 0.55 * gait_speed_limit(creature, rig, action));
  }
  if (action == Action::Jump) return 1.2 * rig.leg_reach / rig.body_length;
  return typical_body_speed(action);
}

double max_speed(const Creature& creature, const Rig& rig, Action action) {
  const double typical = typical_speed(creature, rig, action);
  if (is_gait(action)) {
    if (action == Action::Turn) return 0.0;
    return std::min(gait_speed_limit(creature, rig, action), 2.5 * typical);
  }
  if (action == Action::Jump) return 2.5 * typical;
  return 3.0 * typical;
}

double max_turn_rate(const Creature& creature, const Rig& rig, Action action, double speed) {
  if (!is_gait(action)) return action == Action::Slither ? 60.0 : 120.0;
  if (!has_usable_legs(rig) || rig.foot_radius <= 0.0) return 0.0;
  const GaitPattern gait = gait_pattern(creature, action);
  const GaitTuning tuning = gait_tuning(creature.plan, action == Action::Turn ? Action::Walk : action);
  const double frequency = std::min(max_gait_frequency(gait.duty_factor), 2.5 * tuning.frequency);
  // Foot speed from turning: omega * radius; travel per stance = (v + omega r) * duty / f.
  const double room = rig.max_stance_travel * frequency / gait.duty_factor - speed * rig.body_length;
  return std::clamp(room / rig.foot_radius * 180.0 / kPi, 0.0, 180.0);
}

// ---------------------------------------------------------------------------
// Synthesis

struct PathWave {
  double amplitude = 0.0;   // file units, 0 for bodies that do not follow a path
  double wavelength = 1.0;  // file units
};

enum class SwingStyle {
  Step,    // arc from one foothold to the next
  Tuck,    // follows the body, folded under it (jumps, flight)
  Strike,  // rises in front of the body and strikes the ground ahead (attacks)
};

// Where a foot stands: the tip on the ground and the foot's heading.
struct Foothold {
  Vec3 position = Vec3::Zero();
  double yaw = 0.0;  // radians about +Y
};

struct Swing {
  double begin = 0.0;
  double end = 0.0;  // kInfinity: the foot never lands again
  SwingStyle style = SwingStyle::Step;
};

class Synthesizer {
 public:
  Synthesizer(const Creature& creature, const Rig& rig, const MotionSpec& spec);
  SynthesizedMotion run();

 private:
  double time(int f) const { return (f - pad_) / fps_; }
  size_t at(int f, int j) const { return static_cast<size_t>(f) * joint_count_ + j; }
  double length_speed() const { return spec_.speed * rig_.body_length; }  // file units per second

  PathWave path_wave() const;
  void plan_travel();
  void plan_body();
  void pose_midline(int f, double t);
  void pose_appendages(int f, double t);
  void assemble_frame(int f);
  void pose_wing(const Appendage& wing, int f, double t);
  void plan_legs();
  std::vector<Swing> leg_swings(size_t leg) const;
  void adjust_height();
  void solve_legs();

  // Helpers.
  double gait_clock(double t) const { return frequency_ * t; }
  double gait_share(double t) const;  // 0 when standing still, 1 at full gait
  Foothold neutral_foot(size_t leg, double t) const;
  double attach_yaw(int f, int attach) const { return heading_angle(global_[at(f, attach)]); }
  Vec3 swing_position(size_t leg, const Swing& swing, const Vec3& from, const Vec3& to, double t, int f) const;

  const Creature& creature_;
  const Skeleton& skeleton_;
  const Rig& rig_;
  MotionSpec spec_;
  SplitMix64 style_;
  int joint_count_ = 0;
  int frames_ = 0;
  int pad_ = 0;
  int total_ = 0;
  double fps_ = 30.0;
  double reach_ = 1.0;  // leg reach or a body-size stand-in, file units

  GaitPattern gait_;
  double frequency_ = 0.0;
  GaitTuning tuning_;
  double move_begin_ = -kInfinity;  // gait swings may start in [move_begin_, move_end_)
  double move_end_ = kInfinity;

  // Style drawn from the seed.
  double breath_rate_ = 0.3, breath_phase_ = 0.0, look_phase_ = 0.0, look_amount_ = 0.3, sway_phase_ = 0.0;
  double step_scale_ = 1.0, tail_scale_ = 1.0;

  // Per extended frame (total_).
  std::vector<double> heading_;   // radians about +Y, + = left
  std::vector<double> speed_;     // file units per second along the heading
  std::vector<double> turn_;      // radians per second
  std::vector<double> travelled_; // path length so far (0 at t = 0)
  std::vector<Vec3> root_;        // root position
  std::vector<double> pitch_, roll_;
  std::vector<double> root_yaw_;  // root yaw relative to the heading
  // Action timeline (seconds), set by plan_body for the actions that use them.
  double event_a_ = 0.0, event_b_ = 0.0, event_c_ = 0.0, event_d_ = 0.0;
  double altitude_ = 0.0;

  std::vector<Quat> local_;       // (total_, J)
  std::vector<Quat> global_;      // (total_, J) body FK (legs at rest)
  std::vector<Vec3> position_;    // (total_, J)

  // Legs.
  std::vector<std::vector<Swing>> swings_;   // per leg
  std::vector<std::vector<Vec3>> targets_;   // per leg, (total_) tip target
  std::vector<std::vector<double>> foot_yaw_; // per leg, (total_) heading of the foot: fixed while planted
  std::vector<std::vector<uint8_t>> stance_; // per leg, (total_)
};

Synthesizer::Synthesizer(const Creature& creature, const Rig& rig, const MotionSpec& spec)
    : creature_(creature), skeleton_(creature.skeleton), rig_(rig), spec_(spec), style_(mix_seed(spec.seed, 0x5EED)) {
  joint_count_ = skeleton_.joint_count();
  fps_ = spec_.fps;
  frames_ = std::max(2, static_cast<int>(std::lround(spec_.seconds * spec_.fps)));
  reach_ = rig_.leg_reach > 0.0 ? rig_.leg_reach : 0.3 * rig_.body_length;
  gait_ = gait_pattern(creature_, spec_.action);
  if (is_gait(spec_.action) && has_usable_legs(rig_)) {
    tuning_ = gait_tuning(creature_.plan, spec_.action == Action::Turn ? Action::Walk : spec_.action);
    const double typical = tuning_.leg_speed * rig_.leg_reach;
    const double v = length_speed();
    const double f_max = std::min(max_gait_frequency(gait_.duty_factor), 2.5 * tuning_.frequency);
    double f = typical > 0.0 && v > 0.0 ? tuning_.frequency * std::sqrt(v / typical) : tuning_.frequency;
    const double foot_speed = v + std::abs(radians(spec_.turn_rate)) * rig_.foot_radius;
    if (rig_.max_stance_travel > 0.0) f = std::max(f, foot_speed * gait_.duty_factor / rig_.max_stance_travel);
    frequency_ = std::clamp(f, 0.3 * tuning_.frequency, f_max);
  }
  const double cycle = frequency_ > 0.0 ? 1.0 / frequency_ : 0.0;
  pad_ = static_cast<int>(std::ceil(std::max(1.5, 1.5 * cycle) * fps_));
  total_ = frames_ + 2 * pad_;

  breath_rate_ = style_.uniform(0.22, 0.36);
  breath_phase_ = style_.uniform(0.0, 2.0 * kPi);
  look_phase_ = style_.uniform(0.0, 2.0 * kPi);
  look_amount_ = style_.uniform(0.2, 0.45);
  sway_phase_ = style_.uniform(0.0, 2.0 * kPi);
  step_scale_ = style_.uniform(0.85, 1.15);
  tail_scale_ = style_.uniform(0.8, 1.2);

  if (is_gait(spec_.action)) {
    const double still = std::min(0.5, 0.12 * spec_.seconds);
    if (spec_.start_from_still) move_begin_ = still;
    if (spec_.stop_at_end && frequency_ > 0.0) {
      move_end_ = spec_.seconds - still - 0.5 * (1.0 - gait_.duty_factor) / frequency_;
    }
  }
}

double Synthesizer::gait_share(double t) const {
  if (!is_gait(spec_.action)) return 0.0;
  return is_locomotion(spec_.action) ? travel_ramp(spec_, t) : 0.0;
}

// Root trajectory: speed and turn rate integrated from t = 0 both ways.
void Synthesizer::plan_travel() {
  heading_.assign(total_, 0.0);
  speed_.assign(total_, 0.0);
  turn_.assign(total_, 0.0);
  travelled_.assign(total_, 0.0);
  root_.assign(total_, Vec3::Zero());
  const double v = length_speed();
  const double T = spec_.seconds;
  const double k = std::min(1.0, T / 3.0);
  for (int f = 0; f < total_; ++f) {
    const double t = time(f);
    double speed = 0.0;
    double turn = 0.0;
    switch (spec_.action) {
      case Action::Jump:
        speed = v * pulse(t, event_b_, event_b_ + 0.15 * k, event_c_ - 0.1 * k, event_c_);  // push-off to landing
        break;
      case Action::TakeOff:
        speed = v * ramp_between(t, event_b_ - 0.1, event_b_ + 1.2 * k);
        break;
      case Action::Attack:
        if (creature_.plan == BodyPlan::Fish) {
          const double burst = pulse(t, event_b_, event_b_ + 0.1, event_c_, event_c_ + 0.5 * k);
          speed = rig_.body_length * (0.1 + 2.4 * burst);
        }
        break;
      case Action::Idle:
        if (creature_.plan == BodyPlan::Fish) speed = 0.03 * rig_.body_length;
        break;
      default:
        if (is_locomotion(spec_.action)) {
          const double share = travel_ramp(spec_, t);
          speed = v * share;
          turn = radians(spec_.turn_rate) * share;
        }
        break;
    }
    speed_[f] = speed;
    turn_[f] = turn;
  }
  const double dt = 1.0 / fps_;
  for (int f = pad_ + 1; f < total_; ++f) {
    heading_[f] = heading_[f - 1] + 0.5 * (turn_[f - 1] + turn_[f]) * dt;
    const double step = 0.5 * (speed_[f - 1] + speed_[f]) * dt;
    const double mid = 0.5 * (heading_[f - 1] + heading_[f]);
    travelled_[f] = travelled_[f - 1] + step;
    root_[f] = root_[f - 1] + Vec3(std::sin(mid), 0.0, std::cos(mid)) * step;
  }
  for (int f = pad_ - 1; f >= 0; --f) {
    heading_[f] = heading_[f + 1] - 0.5 * (turn_[f + 1] + turn_[f]) * dt;
    const double step = 0.5 * (speed_[f + 1] + speed_[f]) * dt;
    const double mid = 0.5 * (heading_[f + 1] + heading_[f]);
    travelled_[f] = travelled_[f + 1] - step;
    root_[f] = root_[f + 1] - Vec3(std::sin(mid), 0.0, std::cos(mid)) * step;
  }
}

// Where a leg's foot rests at time t: under its attach joint, turned with it.
Foothold Synthesizer::neutral_foot(size_t leg_index, double t) const {
  const LegRig& leg = rig_.legs[leg_index];
  const double x = std::clamp(t * fps_ + pad_, 0.0, static_cast<double>(total_ - 1));
  const int f0 = static_cast<int>(std::floor(x));
  const int f1 = std::min(f0 + 1, total_ - 1);
  const double w = x - f0;
  const Vec3 position = (1.0 - w) * position_[at(f0, leg.attach)] + w * position_[at(f1, leg.attach)];
  const double yaw0 = attach_yaw(f0, leg.attach);
  double yaw1 = attach_yaw(f1, leg.attach);
  yaw1 = yaw0 + std::remainder(yaw1 - yaw0, 2.0 * kPi);
  const double yaw = (1.0 - w) * yaw0 + w * yaw1;
  Foothold hold;
  hold.position = flat(position) + yaw_rotation(yaw) * leg.neutral_from_attach;
  hold.position.y() = 0.0;
  hold.yaw = yaw;
  return hold;
}

// ---- body ------------------------------------------------------------------

void Synthesizer::plan_body() {
  const double T = spec_.seconds;
  const double k = std::min(1.0, T / 3.0);  // short clips compress the action timelines
  switch (spec_.action) {
    case Action::Jump:
      event_a_ = std::max(0.2 * T, 0.3);        // crouch starts
      event_b_ = event_a_ + 0.35 * k;           // push-off starts
      event_c_ = event_b_ + 0.15 * k + 0.5 * k; // landing (lift-off at b + 0.15k, 0.5k flight)
      event_d_ = event_c_ + 0.7 * k;            // standing again
      break;
    case Action::TakeOff:
      event_a_ = std::max(0.15 * T, 0.25);      // crouch starts
      event_b_ = event_a_ + 0.35 * k;           // lift-off
      break;
    case Action::Sit:
    case Action::LieDown:
      event_a_ = 0.15 * T;
      event_b_ = event_a_ + std::min(1.4, 0.4 * T);
      break;
    case Action::Attack:
      event_a_ = 0.2 * T;                       // wind-up
      event_b_ = event_a_ + 0.45 * k;           // strike
      event_c_ = event_b_ + 0.4 * k;            // strike held, recovery starts
      event_d_ = event_c_ + 0.7 * k;            // recovered
      break;
    default:
      break;
  }
  plan_travel();

  // Base heights.
  const double stand = rig_.stand_height;
  altitude_ = stand + 1.5 * rig_.body_length;
  root_yaw_.assign(total_, 0.0);
  pitch_.assign(total_, 0.0);
  roll_.assign(total_, 0.0);
  const double r = reach_;
  for (int f = 0; f < total_; ++f) {
    const double t = time(f);
    double y = stand;
    double pitch = 0.0, roll = 0.0, yaw = 0.0;
    Vec3 local_offset = Vec3::Zero();  // body-frame offset (x left, z forward)
    const double breath = std::sin(2.0 * kPi * breath_rate_ * t + breath_phase_);
    const double share = gait_share(t);
    const double clock = gait_clock(t);
    switch (spec_.action) {
      case Action::Idle:
      case Action::FlapWings:
        y += 0.008 * r * breath;
        local_offset.x() = 0.02 * r * std::sin(2.0 * kPi * 0.13 * t + sway_phase_);
        if (spec_.action == Action::FlapWings) {
          const double flap = std::sin(2.0 * kPi * (creature_.plan == BodyPlan::Dragon ? 1.3 : 2.6) * t);
          y += 0.03 * r * flap * pulse(t, 0.2, 0.5, T - 0.5, T - 0.2);
        }
        break;
      case Action::Walk:
      case Action::Trot:
      case Action::Run:
      case Action::Gallop:
      case Action::Turn: {
        if (creature_.plan == BodyPlan::Biped || creature_.plan == BodyPlan::Bird) {
          yaw = radians(spec_.action == Action::Run ? 7.0 : 5.0) * std::sin(2.0 * kPi * clock) * share;
          roll = radians(2.0) * std::sin(2.0 * kPi * clock) * share;
          local_offset.x() = 0.025 * r * std::sin(2.0 * kPi * clock + 0.5 * kPi) * share;
          pitch = -radians(spec_.action == Action::Run ? 8.0 : 2.0) * share;
        } else if (spec_.action == Action::Gallop) {
          pitch = radians(5.0) * std::sin(2.0 * kPi * clock) * share;
        } else if (spec_.action == Action::Trot) {
          roll = radians(1.5) * std::sin(2.0 * kPi * clock) * share;
        }
        break;
      }
      case Action::Jump: {
        const double t_lo = event_b_ + 0.15 * k;
        const double crouch = 0.22 * r;
        const double launch = 0.06 * r;
        const double apex = 0.45 * r;
        if (t < event_b_) {
          y -= crouch * ramp_between(t, event_a_, event_b_);
        } else if (t < t_lo) {
          y += (-crouch) + (crouch + launch) * ramp_between(t, event_b_, t_lo);
        } else if (t < event_c_) {
          const double u = (t - t_lo) / (event_c_ - t_lo);
          y += launch + 4.0 * apex * u * (1.0 - u);
        } else {
          const double absorb = 0.2 * r;
          const double down = ramp_between(t, event_c_, event_c_ + 0.2 * k);
          const double up = ramp_between(t, event_c_ + 0.25 * k, event_d_);
          y += launch * (1.0 - down) - absorb * down * (1.0 - up);
        }
        pitch = -radians(8.0) * pulse(t, event_a_, event_b_, event_b_, t_lo) +
                radians(6.0) * pulse(t, t_lo, t_lo + 0.1, event_c_ - 0.2 * k, event_c_) -
                radians(6.0) * pulse(t, event_c_, event_c_ + 0.1, event_c_ + 0.2, event_d_);
        break;
      }
      case Action::Sit: {
        const double w = ramp_between(t, event_a_, event_b_);
        if (creature_.plan == BodyPlan::Biped) {
          // Squat down and back onto the ground, leaning forward on the way.
          y = stand + (0.3 * r - stand) * w;
          local_offset.z() = -0.45 * r * w;
          pitch = -radians(25.0) * pulse(t, event_a_, 0.5 * (event_a_ + event_b_), 0.5 * (event_a_ + event_b_), event_b_ + 0.3) -
                  radians(5.0) * w;
        } else if (creature_.plan == BodyPlan::Bird) {
          y = stand + (0.45 * r - stand) * w;
        } else {
          // Hindquarters down, chest up on straight front legs.
          const double hips = 0.4 * r;
          y = stand + (hips - stand) * w;
          local_offset.z() = -0.1 * r * w;
          double chest_rise = 0.0;
          for (const LegRig& leg : rig_.legs) {
            if (!leg.usable || leg.pair != 0) continue;
            const Vec3 shoulder = leg.hip_rest;
            const double radius = std::hypot(shoulder.y(), shoulder.z());
            const double phi = std::atan2(shoulder.y(), shoulder.z());
            const double wanted = (stand + shoulder.y() - 0.05 * r) - hips;
            if (radius > 1e-9) chest_rise = std::asin(std::clamp(wanted / radius, -0.8, 0.8)) - phi;
            break;
          }
          pitch = std::clamp(chest_rise, 0.0, radians(40.0)) * w;
        }
        y += 0.006 * r * breath * w;
        break;
      }
      case Action::LieDown: {
        const double w = ramp_between(t, event_a_, event_b_);
        const bool sprawler = creature_.plan == BodyPlan::Hexapod || creature_.plan == BodyPlan::Spider ||
                              creature_.plan == BodyPlan::Centipede;
        const double low = sprawler ? 0.12 * r : 0.32 * r;
        y = stand + (std::min(low, stand) - stand) * w;
        y += 0.006 * r * breath;
        break;
      }
      case Action::Attack: {
        const double windup = pulse(t, event_a_, event_b_ - 0.05, event_b_ - 0.05, event_b_);
        const double strike = pulse(t, event_b_ - 0.05, event_b_ + 0.08, event_c_, event_d_);
        switch (creature_.plan) {
          case BodyPlan::Biped:
            yaw = radians(25.0) * side_sign(spec_.side) * (windup - 1.4 * strike);
            local_offset.z() = 0.08 * r * strike;
            break;
          case BodyPlan::Hexapod:
          case BodyPlan::Spider:
            pitch = radians(18.0) * pulse(t, event_a_, event_b_, event_b_ + 0.05, event_c_) - radians(6.0) * strike;
            local_offset.z() = -0.1 * r * windup + 0.15 * r * strike;
            y -= 0.05 * r * windup;
            break;
          case BodyPlan::Bird: {
            // Three quick pecks.
            const double peck = pulse(t, event_a_, event_b_, event_d_ - 0.2, event_d_);
            pitch = -radians(20.0) * peck;
            break;
          }
          case BodyPlan::Fish:
          case BodyPlan::Snake:
          case BodyPlan::Centipede:
            break;
          default:
            local_offset.z() = -0.12 * r * windup + 0.3 * r * strike;
            y -= 0.08 * r * windup + 0.04 * r * strike;
            pitch = radians(6.0) * windup - radians(8.0) * strike;
            yaw = radians(12.0) * side_sign(spec_.side) * strike;
            break;
        }
        y += 0.008 * r * breath;
        break;
      }
      case Action::TakeOff: {
        const double crouch = 0.18 * r * pulse(t, event_a_, event_b_ - 0.12 * k, event_b_ - 0.12 * k, event_b_);
        const double climb = t > event_b_ ? (t - event_b_) : 0.0;
        const double rise = (0.5 * r) * ramp_between(t, event_b_ - 0.12 * k, event_b_ + 0.3 * k) +
                            0.35 * rig_.body_length * climb * climb / std::max(T - event_b_, 0.5);
        y = stand - crouch + rise;
        pitch = radians(14.0) * pulse(t, event_b_ - 0.1, event_b_ + 0.3, T - 0.6, T + 1.0) - radians(10.0) * crouch / r;
        break;
      }
      case Action::Fly: {
        const double flap_rate = creature_.plan == BodyPlan::Dragon ? 1.4 : 3.0;
        y = altitude_ + 0.03 * rig_.body_length * std::sin(2.0 * kPi * flap_rate * t + 0.5 * kPi);
        roll = -std::clamp(0.6 * turn_[f], -radians(35.0), radians(35.0));
        pitch = radians(3.0);
        break;
      }
      case Action::Glide:
        y = altitude_ + 0.1 * length_speed() * (0.5 * T - t);
        roll = -std::clamp(0.7 * turn_[f], -radians(40.0), radians(40.0));
        pitch = -radians(3.0) + radians(1.5) * std::sin(2.0 * kPi * 0.4 * t + sway_phase_);
        break;
      case Action::Swim:
      case Action::Slither:
        y = rig_.rest_height;
        break;
      default:
        break;
    }
    if (creature_.plan == BodyPlan::Fish) {
      y = std::max(rig_.rest_height, 0.4 * rig_.body_length);
      if (spec_.action == Action::Idle) y += 0.01 * rig_.body_length * breath;
    }
    if (creature_.plan == BodyPlan::Snake) y = rig_.rest_height;
    // Path followers sit on their undulating path, off the centre line.
    const PathWave wave = path_wave();
    if (wave.amplitude > 0.0) {
      local_offset.x() += wave.amplitude * std::sin(2.0 * kPi * travelled_[f] / wave.wavelength);
    }
    const Vec3 offset = yaw_rotation(heading_[f]) * local_offset;
    root_[f] = Vec3(root_[f].x() + offset.x(), y, root_[f].z() + offset.z());
    root_yaw_[f] = yaw;
    pitch_[f] = pitch;
    roll_[f] = roll;
  }

  local_.assign(static_cast<size_t>(total_) * joint_count_, Quat::Identity());
  global_.assign(local_.size(), Quat::Identity());
  position_.assign(local_.size(), Vec3::Zero());
  for (int f = 0; f < total_; ++f) {
    const double t = time(f);
    pose_appendages(f, t);
    pose_midline(f, t);
    assemble_frame(f);
  }
}

// Snakes and centipedes follow their own path: a sine of this amplitude and
// wavelength (file units) around the travelled centre line.
PathWave Synthesizer::path_wave() const {
  PathWave wave;
  const double body = rig_.body_length;
  if (creature_.plan == BodyPlan::Snake) {
    wave.amplitude = (spec_.action == Action::Idle ? 0.05 : 0.07) * body;
    wave.wavelength = 0.45 * body;
  } else if (creature_.plan == BodyPlan::Centipede) {
    wave.amplitude = (spec_.action == Action::Run ? 0.025 : 0.008) * body;
    wave.wavelength = 0.5 * body;
  }
  return wave;
}

// The midline: global rotations of spine, neck, head and tail joints, stored
// in local_ as GLOBAL targets (assemble_frame converts them to locals).
void Synthesizer::pose_midline(int f, double t) {
  const Midline& m = rig_.midline;
  const double heading = heading_[f];
  const double share = gait_share(t);
  const double clock = gait_clock(t);
  const double span = std::max(m.front - m.back, 1e-9);
  const double body = rig_.body_length;
  const Action action = spec_.action;
  const bool path_follower = creature_.plan == BodyPlan::Snake || creature_.plan == BodyPlan::Centipede;
  const bool fish = creature_.plan == BodyPlan::Fish;

  // Curvature of the travelled path (radians per file unit), for bending the
  // body along it; turning on the spot bends as if walking at 2 leg lengths/s.
  const double curvature = turn_[f] / std::max(speed_[f], 2.0 * reach_);

  // Lateral wave: path followers take it from their path; fish beat their
  // tail with a wave running from head to tail, growing towards the tail.
  const PathWave path = path_wave();
  double amplitude = path.amplitude, wavelength = path.wavelength, wave_phase = 0.0;
  if (fish) {
    amplitude = action == Action::Idle ? 0.025 * body : 0.09 * body;
    if (action == Action::Swim) amplitude *= 0.25 + 0.75 * travel_ramp(spec_, t);  // hovering before a start, after a stop
    if (action == Action::Attack) {
      const double burst = pulse(t, event_b_ - 0.05, event_b_ + 0.05, event_c_, event_c_ + 0.3);
      amplitude = (0.05 + 0.08 * burst) * body;
    }
    wavelength = body;
    const double rate = action == Action::Idle     ? 0.7
                        : action == Action::Attack ? 1.8
                                                   : std::clamp(length_speed() / (0.7 * body), 0.8, 4.0);
    wave_phase = 2.0 * kPi * rate * t;
  }

  auto lateral = [&](double s) {  // fish: displacement at arc s, amplitude growing towards the tail
    const double x = (m.front - s) / span;
    return amplitude * (0.1 + 0.9 * x * x) * std::sin(wave_phase + 2.0 * kPi * s / wavelength);
  };
  auto lateral_slope = [&](double s) {
    const double h = 1e-3 * span;
    return (lateral(s + h) - lateral(s - h)) / (2.0 * h);
  };
  // Path follower: yaw of the undulating path at path length u relative to its centre line.
  const double u_now = travelled_[f];
  auto path_yaw = [&](double s) {
    const double u = u_now + s;
    const double k = 2.0 * kPi / wavelength;
    // Heading of the centre line at path length u: find the frame where it was (or will be) travelled.
    double centre_heading = heading;
    if (speed_[f] > 0.0 || length_speed() > 0.0) {
      const auto it = std::lower_bound(travelled_.begin(), travelled_.end(), u);
      const int g = static_cast<int>(std::clamp<long>(it - travelled_.begin(), 0, total_ - 1));
      centre_heading = heading_[g];
    }
    return centre_heading + std::atan(amplitude * k * std::cos(k * u));
  };

  // Secondary motion drivers.
  const double tail_sway_rate = is_gait(action) && frequency_ > 0.0 ? frequency_ : 0.35;
  const double look = (action == Action::Idle || action == Action::FlapWings || action == Action::Sit ||
                       action == Action::LieDown)
                          ? look_amount_ * std::sin(2.0 * kPi * 0.12 * t + look_phase_) *
                                std::min(1.0, t / 0.8 + 0.2)
                          : 0.0;
  const double breath = std::sin(2.0 * kPi * breath_rate_ * t + breath_phase_);

  for (int j = 0; j < joint_count_; ++j) {
    if (!m.member[j]) continue;
    const LimbKind kind = m.kind[j];
    const bool is_root = j == 0;
    const double s = m.bone_mid[j];
    const int index = m.chain_index[j];
    double yaw = heading;
    double pitch = pitch_[f];
    double roll = kind == LimbKind::Spine ? roll_[f] : 0.0;

    if (path_follower) {
      yaw = path_yaw(s);
    } else {
      yaw += std::clamp(curvature * s, -radians(35.0), radians(35.0));
      if (fish) yaw += std::atan(lateral_slope(s));
    }
    if (is_root) yaw += root_yaw_[f];

    switch (kind) {
      case LimbKind::Spine:
        if (!is_root) {
          const int spine_index = std::max(m.spine_index[j], 0);
          const double up_the_spine = std::min(1.0, spine_index / 3.0);
          // Bipeds: the chest counter-rotates against the pelvis; everyone breathes.
          if (creature_.plan == BodyPlan::Biped || creature_.plan == BodyPlan::Bird) {
            yaw -= (root_yaw_[f] * 1.6) * up_the_spine;
          }
          pitch += radians(1.2) * breath * up_the_spine;
          if ((creature_.plan == BodyPlan::Quadruped || creature_.plan == BodyPlan::Dragon) && action == Action::Walk) {
            yaw += radians(3.0) * share * std::sin(2.0 * kPi * clock - 2.0 * kPi * s / span);
          }
        }
        break;
      case LimbKind::Neck:
      case LimbKind::Head: {
        // Keep the head steadier than the body; look around when standing; nod with the gait.
        const int neck_count = std::max(rig_.midline.neck_length, 1);
        const double share_of_neck = 1.0 / neck_count;
        pitch = 0.4 * pitch_[f];
        yaw += look * share_of_neck * 1.2 + 0.25 * turn_[f] * share_of_neck;
        if (is_gait(action) && creature_.plan != BodyPlan::Biped) {
          // Nod twice per stride, each joint a little behind the one below it.
          pitch += radians(3.0) * share * std::sin(4.0 * kPi * clock - 0.3 * index) * share_of_neck * 2.0;
        }
        if (action == Action::Attack) {
          const double windup = pulse(t, event_a_, event_b_ - 0.05, event_b_ - 0.05, event_b_);
          const double strike = pulse(t, event_b_ - 0.05, event_b_ + 0.08, event_c_, event_d_);
          switch (creature_.plan) {
            case BodyPlan::Bird: {
              const double pecks = 0.5 - 0.5 * std::cos(2.0 * kPi * 3.0 * (t - event_a_) / (event_d_ - event_a_));
              const double active = pulse(t, event_a_, event_a_ + 0.05, event_d_ - 0.05, event_d_);
              pitch -= radians(45.0) * pecks * active * share_of_neck * 2.0;
              break;
            }
            case BodyPlan::Snake:
            case BodyPlan::Centipede:
              break;
            default:
              pitch += (radians(25.0) * windup - radians(35.0) * strike) * share_of_neck * 2.0;
              break;
          }
        }
        if (action == Action::Fly || action == Action::Glide) pitch = -0.3 * pitch_[f];
        if (action == Action::Sit && creature_.plan != BodyPlan::Biped) pitch = 0.2 * pitch_[f];
        break;
      }
      case LimbKind::Tail: {
        const int tail_count = std::max(rig_.midline.tail_length, 1);
        const double along = static_cast<double>(index + 1) / tail_count;
        const double lag = kTailLag * along;  // the tip trails the base by kTailLag radians
        double sway_amount = radians(4.0) * tail_scale_;
        if (is_gait(action)) sway_amount = radians(action == Action::Walk ? 6.0 : 4.0) * tail_scale_;
        if (action == Action::Fly || action == Action::Glide) sway_amount = radians(2.0);
        const bool abdomen = creature_.plan == BodyPlan::Hexapod || creature_.plan == BodyPlan::Spider;
        if (abdomen) sway_amount = radians(1.5);  // an arthropod's abdomen barely sways
        if (!fish && !path_follower) {
          yaw += sway_amount * along * std::sin(2.0 * kPi * tail_sway_rate * t - lag + sway_phase_);
        }
        // Tail carriage: follows the body pitch, raised when running, lowered when resting.
        double carriage = 0.0;
        if (action == Action::Run || action == Action::Gallop || action == Action::Trot) carriage = radians(8.0) * share;
        if (action == Action::Sit || action == Action::LieDown) {
          carriage = -radians(10.0) * ramp_between(t, event_a_, event_b_);
        }
        // Lagged response to the body's vertical motion: the tail droops when the body rises.
        const int delayed = std::clamp(f - static_cast<int>(std::lround(0.06 * (index + 1) * fps_)), 1, total_ - 1);
        const double rise = (root_[delayed].y() - root_[delayed - 1].y()) * fps_;
        const double droop = std::clamp(-0.5 * rise / std::max(reach_, 1e-9), -radians(12.0), radians(12.0)) * along;
        if (!fish && !path_follower) pitch = pitch_[f] - carriage - droop;
        if (path_follower || fish) pitch = 0.0;
        break;
      }
      default:
        break;
    }

    // Plan-specific strikes of the front body.
    if (action == Action::Attack && (creature_.plan == BodyPlan::Snake || creature_.plan == BodyPlan::Centipede) &&
        s > 0.0) {
      const double front_share = std::clamp(s / std::max(m.front, 1e-9), 0.0, 1.0);
      const double coil = pulse(t, event_a_, event_b_, event_b_, event_b_ + 0.1);
      const double strike = pulse(t, event_b_, event_b_ + 0.1, event_c_, event_d_);
      if (creature_.plan == BodyPlan::Snake && front_share > 0.35) {
        const double w = (front_share - 0.35) / 0.65;
        yaw += radians(55.0) * coil * std::sin(2.0 * kPi * w * 1.5) * (1.0 - 0.8 * strike) * (1.0 - w * 0.3);
        pitch = radians(35.0) * (coil + 0.6 * strike) * w * (1.0 - w) * 2.0;
        if (front_share > 0.9) pitch = -radians(15.0) * strike;
      }
      if (creature_.plan == BodyPlan::Centipede && kind != LimbKind::Spine) {
        pitch = radians(30.0) * coil - radians(25.0) * strike;
        yaw += radians(20.0) * side_sign(spec_.side) * strike;
      }
    }
    if (creature_.plan == BodyPlan::Snake && kind != LimbKind::Spine && s > 0.6 * m.front &&
        action != Action::Attack) {
      pitch = radians(action == Action::Idle ? 8.0 : 4.0);  // head held a little off the ground
    }

    local_[at(f, j)] = body_rotation(yaw, pitch, roll);
  }
}

// Fins, antennae and jaws: local rotations.
void Synthesizer::pose_appendages(int f, double t) {
  const Action action = spec_.action;
  const double share = gait_share(t);
  // Fins: sculling pectorals, swaying median fins.
  for (const Appendage& fin : rig_.fins) {
    const std::vector<int>& joints = fin.limb->joints;
    const double rate = action == Action::Idle ? 0.8 : 1.6;
    if (fin.limb->side == Side::None) {
      const double sway = radians(8.0) * std::sin(2.0 * kPi * rate * t);
      for (size_t k = 0; k < joints.size(); ++k) local_[at(f, joints[k])] = yaw_rotation(sway / joints.size());
    } else {
      const double beat = std::sin(2.0 * kPi * rate * t + (fin.limb->side == Side::Right ? kPi : 0.0) * 0.0);
      const double tuck = action == Action::Swim || action == Action::Attack ? radians(30.0) : radians(5.0);
      local_[at(f, joints[0])] =
          (axis_angle(fin.sweep_axis, tuck + radians(10.0) * std::cos(2.0 * kPi * rate * t)) *
           axis_angle(fin.lift_axis, radians(15.0) * beat))
              .normalized();
    }
  }
  // Antennae: lagged sway.
  for (const Limb* antenna : rig_.antennae) {
    for (size_t k = 0; k < antenna->joints.size(); ++k) {
      const double phase = 2.0 * kPi * 0.7 * t - 0.6 * k + sway_phase_ + (antenna->side == Side::Right ? 1.3 : 0.0);
      local_[at(f, antenna->joints[k])] =
          (yaw_rotation(radians(6.0) * std::sin(phase)) * axis_angle(Vec3::UnitX(), radians(5.0) * std::cos(phase * 0.7)))
              .normalized();
    }
  }
  // Jaws: open for attacks, a little while breathing hard.
  for (const Limb* jaw : rig_.jaws) {
    double open = 0.0;
    if (action == Action::Attack) open = radians(30.0) * pulse(t, event_a_ + 0.15, event_b_, event_b_ + 0.05, event_b_ + 0.15);
    if (action == Action::Gallop || action == Action::Run) open = radians(6.0) * share;
    const Quat q = axis_angle(Vec3::UnitX(), open);
    if (!jaw->joints.empty()) local_[at(f, jaw->joints[0])] = q;
  }
}

// Converts the midline's global targets (in local_) into locals top-down,
// adds arms, and runs forward kinematics for the frame.
void Synthesizer::assemble_frame(int f) {
  const Midline& m = rig_.midline;
  const std::vector<int>& parents = skeleton_.parents;
  for (int j = 0; j < joint_count_; ++j) {
    const int p = parents[j];
    const Quat parent_global = p >= 0 ? global_[at(f, p)] : Quat::Identity();
    if (m.member[j]) {
      const Quat target = local_[at(f, j)];
      local_[at(f, j)] = (parent_global.conjugate() * target).normalized();
    }
    global_[at(f, j)] = (parent_global * local_[at(f, j)]).normalized();
    position_[at(f, j)] = p >= 0 ? Vec3(position_[at(f, p)] + parent_global * skeleton_.offsets[j]) : root_[f];
  }

  // Arms: directions in the chest's heading frame, then aimed; wings after them.
  const double t = time(f);
  const double share = gait_share(t);
  const double clock = gait_clock(t);
  const Action action = spec_.action;
  for (const Appendage& arm : rig_.arms) {
    const std::vector<int>& joints = arm.limb->joints;
    const int pivot = joints[arm.pivot];
    const int parent = parents[pivot];
    const double side = side_sign(arm.limb->side);
    // Swing opposite to the same-side leg: forward while that leg is behind.
    double same_side_phase = 0.0;
    for (size_t i = 0; i < rig_.legs.size() && i < gait_.phases.size(); ++i) {
      if (rig_.legs[i].side == arm.limb->side) same_side_phase = gait_.phases[i];
    }
    const bool running = action == Action::Run;
    double swing = -radians(running ? 35.0 : 18.0) * share * std::cos(2.0 * kPi * (clock + same_side_phase));
    double elbow = radians(running ? 85.0 : 20.0) * share + radians(10.0) * (1.0 - share);
    double raise = 0.0;  // sideways, away from the body
    if (action == Action::Sit) {
      const double w = ramp_between(t, event_a_, event_b_);
      swing = radians(45.0) * w;
      elbow = radians(10.0) + radians(35.0) * w;
    }
    if (action == Action::Jump) {
      const double kk = std::min(1.0, spec_.seconds / 3.0);
      swing = -radians(40.0) * pulse(t, event_a_, event_b_, event_b_, event_b_ + 0.1 * kk) +
              radians(60.0) * pulse(t, event_b_, event_b_ + 0.15 * kk, event_c_ - 0.1, event_c_ + 0.2);
      elbow = radians(25.0);
    }
    if (action == Action::Attack && creature_.plan == BodyPlan::Biped) {
      const bool striking = arm.limb->side == spec_.side;
      const double windup = pulse(t, event_a_, event_b_ - 0.05, event_b_ - 0.05, event_b_);
      const double strike = pulse(t, event_b_ - 0.05, event_b_ + 0.08, event_c_, event_d_);
      const double guard = pulse(t, event_a_ - 0.3, event_a_, event_d_, event_d_ + 0.3);
      if (striking) {
        swing = radians(20.0) * guard - radians(25.0) * windup + radians(70.0) * strike;
        elbow = radians(100.0) * guard * (1.0 - strike) + radians(5.0) * strike;
      } else {
        swing = radians(40.0) * guard;
        elbow = radians(110.0) * guard;
      }
      raise = radians(5.0);
    }
    const Quat chest = yaw_rotation(heading_angle(global_[at(f, parent)]));
    const Vec3 down(side * (0.12 + std::sin(raise)), -1.0, 0.0);
    const Vec3 upper = chest * (axis_angle(Vec3::UnitX(), -swing) * down.normalized());
    const Vec3 lower = chest * (axis_angle(Vec3::UnitX(), -(swing + elbow)) * Vec3(side * 0.05, -1.0, 0.0).normalized());
    std::vector<int> chain(joints.begin() + arm.pivot, joints.end());
    std::vector<Vec3> points(chain.size());
    points[0] = position_[at(f, pivot)];
    for (size_t k = 1; k < chain.size(); ++k) {
      const Vec3& direction = k == 1 ? upper : lower;
      points[k] = points[k - 1] + direction * arm.lengths[k - 1];
    }
    // Only the upper arm and forearm are aimed; the hand keeps its rest relation to the forearm.
    const size_t aimed = std::min<size_t>(chain.size(), 3);
    chain.resize(aimed);
    points.resize(aimed);
    aim_chain(skeleton_, chain, points, global_[at(f, parent)], &local_[at(f, 0)]);
  }
  for (const Appendage& wing : rig_.wings) pose_wing(wing, f, t);
}

// Wings: a direction per bone in the body's frame, blended between folded
// along the body and spread, beating about the body's long axis with the
// distal bones lagging; then aimed. Independent of the rest pose (a crouched
// rest may already be folded).
void Synthesizer::pose_wing(const Appendage& wing, int f, double t) {
  const std::vector<int>& joints = wing.limb->joints;
  const Action action = spec_.action;
  const double T = spec_.seconds;
  const double side = side_sign(wing.limb->side);
  const double rate = creature_.plan == BodyPlan::Dragon ? 1.4 : 3.0;  // wing beats per second
  double open = 0.0;       // 0 folded, 1 spread
  double amplitude = 0.0;  // beat amplitude, radians
  double beat_rate = rate;
  double elevation = radians(8.0);
  switch (action) {
    case Action::Fly:
      open = 1.0;
      amplitude = radians(42.0);
      break;
    case Action::Glide:
      open = 1.0;
      elevation = radians(6.0) + radians(2.0) * std::sin(2.0 * kPi * 0.5 * t);
      break;
    case Action::TakeOff:
      open = ramp_between(t, event_a_, event_b_ - 0.1);
      amplitude = radians(50.0) * open;
      beat_rate = 1.15 * rate;
      break;
    case Action::FlapWings:
      open = pulse(t, 0.2, 0.5, T - 0.5, T - 0.2);
      amplitude = radians(45.0) * open;
      break;
    default:
      break;
  }
  const double phase = 2.0 * kPi * beat_rate * t;
  // Folded directions (left wing; x mirrored for the right): humerus back, forearm forward, the rest back.
  const Vec3 folded[3] = {Vec3(0.45, -0.15, -0.85).normalized(), Vec3(0.2, 0.0, 0.98).normalized(),
                          Vec3(0.15, -0.05, -0.99).normalized()};
  const Quat parent_global = global_[at(f, skeleton_.parents[joints[0]])];
  const Quat& body = parent_global;  // wings pitch and bank with the chest
  const size_t n = joints.size();
  std::vector<Vec3> points(n);
  points[0] = position_[at(f, joints[0])];
  auto direction = [&](size_t bone) {  // bone `bone` runs from joints[bone] to the next joint (or the end site)
    const double lag = 0.5 * static_cast<double>(bone);
    const double e = elevation + amplitude * std::sin(phase - lag);
    const double sweep = open * radians(8.0) * std::cos(phase - lag);
    // Beating wings fold a little on the upstroke, distal bones only.
    const double upstroke_fold = bone > 0 && amplitude > 0.0 ? 0.15 * open * (0.5 - 0.5 * std::sin(phase - lag)) : 0.0;
    const Vec3 spread = axis_angle(Vec3::UnitY(), side * sweep) *
                        (axis_angle(Vec3::UnitZ(), side * e) * Vec3(side, 0.0, -0.12).normalized());
    Vec3 tuck = folded[std::min<size_t>(bone, 2)];
    tuck.x() *= side;
    const double w = std::clamp(1.0 - open + upstroke_fold, 0.0, 1.0);
    return Vec3(body * ((1.0 - w) * spread + w * tuck).normalized());
  };
  for (size_t k = 1; k < n; ++k) points[k] = points[k - 1] + direction(k - 1) * skeleton_.offsets[joints[k]].norm();
  const Quat last = aim_chain(skeleton_, joints, points, parent_global, &local_[at(f, 0)]);
  // The last joint carries the wing tip's end site: aim it too.
  for (const EndSite& site : skeleton_.end_sites) {
    if (site.parent != joints[n - 1] || site.offset.norm() < 1e-12) continue;
    const Vec3 want = direction(n - 1);
    const Quat global = (Quat::FromTwoVectors(last * site.offset, want) * last).normalized();
    local_[at(f, joints[n - 1])] = (last.conjugate() * global).normalized();
    break;
  }
}

// ---- legs ------------------------------------------------------------------

// Swing intervals of one leg for the whole extended timeline.
std::vector<Swing> Synthesizer::leg_swings(size_t leg_index) const {
  std::vector<Swing> swings;
  const LegRig& leg = rig_.legs[leg_index];
  const double t_first = time(0);
  const double t_last = time(total_ - 1);
  const double T = spec_.seconds;
  const double k = std::min(1.0, T / 3.0);
  const Action action = spec_.action;
  if (is_gait(action) && frequency_ > 0.0 && leg_index < gait_.phases.size()) {
    const double phase = gait_.phases[leg_index];
    const double beta = gait_.duty_factor;
    const long first = static_cast<long>(std::floor(frequency_ * t_first)) - 2;
    const long last = static_cast<long>(std::ceil(frequency_ * t_last)) + 2;
    for (long n = first; n <= last; ++n) {
      const double begin = (n + beta - phase) / frequency_;
      const double end = (n + 1 - phase) / frequency_;
      if (begin < move_begin_ || begin >= move_end_) continue;
      swings.push_back({begin, end, SwingStyle::Step});
    }
    return swings;
  }
  switch (action) {
    case Action::Jump: {
      // Feet leave the ground in order from front to back within a few frames; land together.
      const double lift_off = event_b_ + 0.15 * k + 0.01 * leg.pair;
      swings.push_back({lift_off, event_c_, SwingStyle::Tuck});
      break;
    }
    case Action::TakeOff:
      swings.push_back({event_b_ + 0.01 * leg.pair, kInfinity, SwingStyle::Tuck});
      break;
    case Action::Fly:
    case Action::Glide:
      swings.push_back({-kInfinity, kInfinity, SwingStyle::Tuck});
      break;
    case Action::Attack:
      if ((creature_.plan == BodyPlan::Spider || creature_.plan == BodyPlan::Hexapod) && leg.pair == 0) {
        swings.push_back({event_a_ + 0.05, event_d_, SwingStyle::Strike});
      }
      break;
    default:
      break;
  }
  return swings;
}

Vec3 Synthesizer::swing_position(size_t leg_index, const Swing& swing, const Vec3& from, const Vec3& to, double t,
                                 int f) const {
  const LegRig& leg = rig_.legs[leg_index];
  const double yaw = attach_yaw(f, leg.attach);
  const Quat heading = yaw_rotation(yaw);
  const Vec3 hip = position_[at(f, leg.joints[0])];
  const double r = leg.reach;
  const bool open_ended = !std::isfinite(swing.end) || !std::isfinite(swing.begin);
  const double u = open_ended ? 0.5 : std::clamp((t - swing.begin) / (swing.end - swing.begin), 0.0, 1.0);
  switch (swing.style) {
    case SwingStyle::Step: {
      const double height = std::min(tuning_.step_height * r * step_scale_, 0.45 * r);
      const double travel = (to - from).norm();
      const double lift = std::min(height, std::max(0.35 * height, 0.6 * travel));
      Vec3 p = from + (to - from) * smoothstep(u);
      p.y() = from.y() + (to.y() - from.y()) * u + lift * std::sin(kPi * u);
      return p;
    }
    case SwingStyle::Tuck: {
      // Folded under the body, trailing a little.
      const Vec3 tucked =
          hip + heading * Vec3(0.5 * leg.end_from_hip.x(), -0.55 * r, 0.5 * leg.end_from_hip.z() - 0.2 * r);
      double w;
      if (!std::isfinite(swing.begin)) {
        w = 1.0;
      } else if (!std::isfinite(swing.end)) {
        w = smoothstep((t - swing.begin) / 0.3);
      } else {
        w = smoothstep(u / 0.3) * smoothstep((1.0 - u) / 0.3);
      }
      const Vec3 line = std::isfinite(swing.end) && std::isfinite(swing.begin) ? Vec3(from + (to - from) * smoothstep(u)) : from;
      return (1.0 - w) * line + w * tucked;
    }
    case SwingStyle::Strike: {
      const Vec3 raised = hip + heading * Vec3(0.6 * leg.end_from_hip.x(), 0.3 * r, 0.45 * r + std::max(0.0, leg.end_from_hip.z()));
      const Vec3 ground_ahead = from + heading * Vec3(0.0, 0.0, 0.35 * r);
      // Timeline within the swing: rise, hold, strike down, return.
      const double strike_at = std::clamp((event_b_ - swing.begin) / (swing.end - swing.begin), 0.3, 0.7);
      if (u < strike_at - 0.08) {
        const double w = smoothstep(u / (strike_at - 0.08));
        Vec3 p = from + (raised - from) * w;
        p.y() += 0.1 * r * std::sin(kPi * w);
        return p;
      }
      if (u < strike_at + 0.05) {
        const double w = smoothstep((u - (strike_at - 0.08)) / 0.13);
        return raised + (ground_ahead - raised) * w;
      }
      const double w = smoothstep((u - (strike_at + 0.05)) / (1.0 - strike_at - 0.05));
      Vec3 p = ground_ahead + (to - ground_ahead) * w;
      p.y() += 0.12 * r * std::sin(kPi * w);
      return p;
    }
  }
  return from;
}

void Synthesizer::plan_legs() {
  const size_t legs = rig_.legs.size();
  swings_.assign(legs, {});
  targets_.assign(legs, std::vector<Vec3>(total_, Vec3::Zero()));
  foot_yaw_.assign(legs, std::vector<double>(total_, 0.0));
  stance_.assign(legs, std::vector<uint8_t>(total_, 1));
  const double t_first = time(0);
  const double t_last = time(total_ - 1);
  const double T = spec_.seconds;
  for (size_t i = 0; i < legs; ++i) {
    if (!rig_.legs[i].usable) continue;
    swings_[i] = leg_swings(i);
    const std::vector<Swing>& swings = swings_[i];
    // Stance footholds: the neutral point at mid-stance; open-ended stances use
    // the clip's first or last pose.
    std::vector<Foothold> holds(swings.size() + 1);
    for (size_t s = 0; s <= swings.size(); ++s) {
      const double begin = s == 0 ? -kInfinity : swings[s - 1].end;
      const double end = s == swings.size() ? kInfinity : swings[s].begin;
      double when;
      if (!std::isfinite(begin) && !std::isfinite(end)) {
        when = 0.0;
      } else if (!std::isfinite(begin)) {
        when = std::min(end, 0.0);
      } else if (!std::isfinite(end)) {
        when = std::max(begin, T);
      } else {
        when = 0.5 * (begin + end);
      }
      holds[s] = neutral_foot(i, std::clamp(when, t_first, t_last));
    }
    size_t next = 0;  // first swing that has not ended
    for (int f = 0; f < total_; ++f) {
      const double t = time(f);
      while (next < swings.size() && swings[next].end <= t) ++next;
      if (next < swings.size() && swings[next].begin < t) {
        const Swing& swing = swings[next];
        stance_[i][f] = 0;
        targets_[i][f] = swing_position(i, swing, holds[next].position, holds[next + 1].position, t, f);
        // The foot turns while it is in the air: towards its next foothold, or with the body.
        const double body_yaw = attach_yaw(f, rig_.legs[i].attach);
        const double from = holds[next].yaw;
        if (std::isfinite(swing.begin) && std::isfinite(swing.end)) {
          const double u = smoothstep((t - swing.begin) / (swing.end - swing.begin));
          foot_yaw_[i][f] = from + std::remainder(holds[next + 1].yaw - from, 2.0 * kPi) * u;
        } else if (std::isfinite(swing.begin)) {
          foot_yaw_[i][f] = from + std::remainder(body_yaw - from, 2.0 * kPi) * smoothstep((t - swing.begin) / 0.3);
        } else {
          foot_yaw_[i][f] = body_yaw;
        }
      } else {
        stance_[i][f] = 1;
        targets_[i][f] = holds[next].position;
        foot_yaw_[i][f] = holds[next].yaw;
      }
    }
  }
}

// Raises the body in flight phases of fast gaits, lowers it wherever a
// stance foot would be out of reach and raises it where a leg would have to
// fold more than it can.
void Synthesizer::adjust_height() {
  std::vector<double> shift(total_, 0.0);
  if ((spec_.action == Action::Run || spec_.action == Action::Gallop) && !rig_.legs.empty()) {
    std::vector<double> flight(total_, 0.0);
    for (int f = 0; f < total_; ++f) {
      bool any = false;
      for (size_t i = 0; i < rig_.legs.size(); ++i) any = any || (rig_.legs[i].usable && stance_[i][f]);
      flight[f] = any ? 0.0 : 1.0;
    }
    const int half = std::max(1, static_cast<int>(std::lround(0.05 * fps_)));
    for (int f = 0; f < total_; ++f) {
      double sum = 0.0, weight = 0.0;
      for (int g = std::max(0, f - half); g <= std::min(total_ - 1, f + half); ++g) {
        const double w = 1.0 + half - std::abs(g - f);
        sum += w * flight[g];
        weight += w;
      }
      shift[f] = 0.06 * reach_ * (sum / weight) * gait_share(time(f));
    }
  }
  // Drop needed for reach, lift needed for folding.
  std::vector<double> drop(total_, 0.0), lift(total_, 0.0);
  for (int f = 0; f < total_; ++f) {
    for (size_t i = 0; i < rig_.legs.size(); ++i) {
      const LegRig& leg = rig_.legs[i];
      if (!leg.usable || !stance_[i][f]) continue;
      const Vec3 hip = position_[at(f, leg.joints[0])] + Vec3(0.0, shift[f], 0.0);
      const Vec3 end = targets_[i][f] - yaw_rotation(foot_yaw_[i][f]) * (leg.fixed_foot ? leg.foot_vector : Vec3::Zero());
      const double horizontal = flat(hip - end).norm();
      const double limit = kMaxReach * leg.reach;
      const double vertical = std::sqrt(std::max(0.0, limit * limit - horizontal * horizontal));
      drop[f] = std::max(drop[f], (hip.y() - end.y()) - vertical);
      const double fold = 1.05 * leg.min_reach;
      if (horizontal < fold) lift[f] = std::max(lift[f], std::sqrt(fold * fold - horizontal * horizontal) - (hip.y() - end.y()));
    }
  }
  // Smooth envelopes that never fall below the needed drop and lift.
  const int window = std::max(1, static_cast<int>(std::lround(0.15 * fps_)));
  auto envelope = [&](const std::vector<double>& need, int f) {
    double out = 0.0;
    for (int g = std::max(0, f - window); g <= std::min(total_ - 1, f + window); ++g) {
      if (need[g] <= 0.0) continue;
      const double c = std::cos(0.5 * kPi * std::abs(g - f) / (window + 1));
      out = std::max(out, need[g] * c * c);
    }
    return out;
  };
  for (int f = 0; f < total_; ++f) shift[f] += envelope(lift, f) - envelope(drop, f);
  for (int f = 0; f < total_; ++f) {
    if (shift[f] == 0.0) continue;
    root_[f].y() += shift[f];
    for (int j = 0; j < joint_count_; ++j) position_[at(f, j)].y() += shift[f];
  }
}

void Synthesizer::solve_legs() {
  std::vector<Vec3> points;
  for (size_t i = 0; i < rig_.legs.size(); ++i) {
    const LegRig& leg = rig_.legs[i];
    if (!leg.usable) continue;
    const int n = static_cast<int>(leg.joints.size());
    const int ik_joints = static_cast<int>(leg.shape.size());
    for (int f = 0; f < total_; ++f) {
      const Quat parent_global = global_[at(f, leg.attach)];
      const Quat heading = yaw_rotation(heading_angle(parent_global));  // the knee's frame follows the body
      const Quat foot = yaw_rotation(foot_yaw_[i][f]);                   // the foot's stays planted
      const Vec3 hip = position_[at(f, leg.joints[0])];
      const Vec3 tip = targets_[i][f];
      const Vec3 end = leg.fixed_foot ? Vec3(tip - foot * leg.foot_vector) : tip;
      points.assign(ik_joints, hip);
      for (int k = 1; k < ik_joints; ++k) points[k] = heading * leg.shape[k];
      const Vec3 template_end = points[ik_joints - 1];
      const Vec3 wanted = end - hip;
      const Quat align = template_end.norm() > 1e-12 && wanted.norm() > 1e-12 ? Quat::FromTwoVectors(template_end, wanted)
                                                                              : Quat::Identity();
      // Squash the template along the hip-target axis to the target's distance:
      // the bend keeps its direction and FABRIK starts close to the answer.
      const double ratio = template_end.norm() > 1e-12 ? wanted.norm() / template_end.norm() : 1.0;
      const Vec3 axis = wanted.norm() > 1e-12 ? Vec3(wanted.normalized()) : Vec3(0, -1, 0);
      for (int k = 1; k < ik_joints; ++k) {
        const Vec3 p = align * points[k];
        const double along = p.dot(axis);
        points[k] = hip + axis * (along * ratio) + (p - along * axis);
      }
      if (ik_joints == 2) {
        points[1] = hip + wanted.normalized() * leg.lengths[0];
      } else if (ik_joints == 3) {
        points[1] = two_bone_middle(hip, end, leg.lengths[0], leg.lengths[1], points[1] - hip);
        const Vec3 lower = end - points[1];
        points[2] = points[1] + (lower.norm() > 1e-12 ? Vec3(lower.normalized()) : Vec3(0, -1, 0)) * leg.lengths[1];
      } else {
        fabrik(points, leg.lengths, end);
      }
      if (leg.fixed_foot) points.push_back(points.back() + foot * leg.foot_vector);
      Quat* locals = &local_[at(f, 0)];
      const Quat last = aim_chain(skeleton_, leg.joints, points, parent_global, locals);
      locals[leg.joints[n - 1]] = (last.conjugate() * foot).normalized();
    }
  }
}

SynthesizedMotion Synthesizer::run() {
  plan_body();
  plan_legs();
  adjust_height();
  solve_legs();

  SynthesizedMotion out;
  out.spec = spec_;
  out.gait = gait_;
  out.gait_frequency = frequency_;
  Motion& motion = out.motion;
  motion = Motion::rest(skeleton_, frames_, fps_);
  for (int t = 0; t < frames_; ++t) {
    const int f = t + pad_;
    for (int j = 0; j < joint_count_; ++j) motion.rotation(t, j) = local_[at(f, j)];
    motion.translation(t, 0) = root_[f];
  }
  for (size_t i = 0; i < rig_.legs.size(); ++i) {
    LegTrack track;
    track.limb = rig_.legs[i].limb;
    track.stance.assign(frames_, rig_.legs[i].usable ? 1 : 0);
    if (rig_.legs[i].usable) {
      for (int t = 0; t < frames_; ++t) track.stance[t] = stance_[i][t + pad_];
    }
    out.legs.push_back(std::move(track));
  }
  return out;
}

// The spec as it will be made.
MotionSpec effective_spec(const Creature& creature, const Rig& rig, const MotionSpec& requested) {
  MotionSpec spec = requested;
  const Action action = spec.action;
  const double typical = typical_speed(creature, rig, action);
  const double most = max_speed(creature, rig, action);
  if (!is_locomotion(action)) {
    spec.turn_rate = 0.0;
    spec.start_from_still = false;
    spec.stop_at_end = false;
  }
  switch (action) {
    case Action::Turn:
      spec.speed = 0.0;
      if (std::abs(spec.turn_rate) < 15.0) spec.turn_rate = spec.turn_rate < 0.0 ? -60.0 : 60.0;
      break;
    case Action::Jump:
      spec.speed = std::clamp(spec.speed, 0.0, most);
      break;
    case Action::TakeOff:
      spec.speed = std::clamp(spec.speed, 0.5 * typical, 2.0 * typical);
      break;
    case Action::Fly:
    case Action::Glide:
      spec.start_from_still = false;
      spec.stop_at_end = false;
      spec.speed = std::clamp(spec.speed, 0.4 * typical, most);
      break;
    default:
      if (is_locomotion(action)) {
        spec.speed = std::clamp(spec.speed, 0.3 * typical, std::max(most, 0.3 * typical));
      } else {
        spec.speed = 0.0;
      }
      break;
  }
  if (is_locomotion(action)) {
    const double turn_limit = max_turn_rate(creature, rig, action, spec.speed);
    spec.turn_rate = std::clamp(spec.turn_rate, -turn_limit, turn_limit);
  }
  if (action == Action::Attack) {
    if (spec.side == Side::None) spec.side = (mix_seed(spec.seed, 0xA77AC) & 1) ? Side::Left : Side::Right;
  } else {
    spec.side = Side::None;
  }
  return spec;
}

}  // namespace

double typical_speed(const Creature& creature, Action action) { return typical_speed(creature, analyze(creature), action); }

double max_speed(const Creature& creature, Action action) { return max_speed(creature, analyze(creature), action); }

double max_turn_rate(const Creature& creature, Action action, double speed) {
  return max_turn_rate(creature, analyze(creature), action, speed);
}

SynthesizedMotion synthesize_motion(const Creature& creature, const MotionSpec& spec) {
  spec.validate();
  if (!supports_action(creature.plan, spec.action)) {
    throw std::invalid_argument("synthesize_motion: a " + std::string(body_plan_name(creature.plan)) + " cannot " +
                                std::string(action_name(spec.action)));
  }
  creature.skeleton.validate();
  const Rig rig = analyze(creature);
  const MotionSpec effective = effective_spec(creature, rig, spec);
  Synthesizer synthesizer(creature, rig, effective);
  return synthesizer.run();
}

}  // namespace nec::zoo
