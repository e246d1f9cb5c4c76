// Rig analysis for motion synthesis (motion_rig.h): legs (IK chains, bent
// templates, neutral feet), the midline (spine, neck, head, tail), arms,
// wings and fins, the standing height and the stance travel.
#include "nec/motion/kinematics.h"

#include "motion_rig.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace nec::zoo::detail {
namespace {

constexpr double kStandReach = 0.9;         // standing: hip to foot at 90% of the leg's reach
constexpr double kPillarStandReach = 0.97;  // an elephant stands on almost straight legs

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
  switch (moves_like(plan)) {
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

}  // namespace

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
      case LimbKind::Trunk:
        rig.trunks.push_back(&limb);
        break;
      default:
        break;
    }
  }
  rig.midline = analyze_midline(creature, rig.rest);

  // Standing height: every usable leg reaches its neutral foot at kStandReach (an elephant's at kPillarStandReach).
  rig.stand_height = rig.rest_height;
  for (const LegRig& leg : rig.legs) {
    if (!leg.usable) continue;
    if (rig.leg_reach == 0.0) rig.leg_reach = leg.reach;
    const Vec3 tip = flat(rig.rest[leg.attach]) + leg.neutral_from_attach;
    const Vec3 end = tip - (leg.fixed_foot ? leg.foot_vector : Vec3::Zero());  // world y of the end is -foot.y
    const double horizontal = flat(end - leg.hip_rest).norm();
    const double stand_reach = creature.plan == BodyPlan::Elephant ? kPillarStandReach : kStandReach;
    const double vertical = std::sqrt(std::max(0.0, std::pow(stand_reach * leg.reach, 2) - horizontal * horizontal));
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

}  // namespace nec::zoo::detail
