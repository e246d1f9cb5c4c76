// Four-legged body plans: quadrupeds of five species (dog, cat, horse, wolf,
// bear); ungulates (deer, goat, camel, giraffe) on hooves; elephants, with
// pillar legs and a trunk; and dragons, the same four-legged body with wings
// and a longer neck and tail.
#include "body_plans.h"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace nec::zoo::detail {
namespace {

// Species-level proportions of four-legged vertebrates, relative to the hind leg length.
struct QuadrupedSpecies {
  const char* name;
  double leg_min, leg_max;     // hind leg length, meters
  double body;                 // hips to chest
  double rise;                 // chest above the hips
  double neck;                 // neck length
  double neck_degrees;         // neck elevation
  int neck_min, neck_max;      // neck joints
  double head;                 // head length
  double head_degrees;         // head pitch (negative: muzzle down)
  double tail;                 // tail length
  int tail_min, tail_max;      // tail joints
  double tail_degrees;         // tail elevation at its base
  double tail_curl;            // extra elevation per tail segment
  double foot_degrees;         // metatarsus lean: ~10 digitigrade, ~70 plantigrade
};

const QuadrupedSpecies kQuadrupeds[] = {
    {"dog", 0.45, 0.70, 1.00, 0.03, 0.45, 40, 2, 3, 0.40, -15, 0.60, 4, 8, -25, 3, 15},
    {"cat", 0.25, 0.35, 1.05, 0.00, 0.30, 35, 1, 2, 0.30, -10, 1.00, 6, 10, 20, 6, 15},
    {"horse", 1.30, 1.70, 0.80, 0.08, 0.70, 50, 3, 6, 0.50, -50, 0.45, 3, 6, -55, -3, 5},
    {"wolf", 0.60, 0.85, 1.05, 0.02, 0.45, 35, 2, 4, 0.40, -10, 0.60, 5, 8, -35, 2, 15},
    {"bear", 0.70, 1.00, 1.20, 0.05, 0.35, 20, 1, 3, 0.35, -10, 0.12, 1, 2, -30, 0, 70},
};

const QuadrupedSpecies kUngulates[] = {
    {"deer", 0.80, 1.10, 0.85, 0.06, 0.55, 50, 3, 5, 0.35, -40, 0.12, 1, 2, -30, 0, 4},
    {"goat", 0.50, 0.70, 1.00, 0.05, 0.45, 45, 2, 4, 0.40, -40, 0.15, 1, 2, 20, 0, 8},
    {"camel", 1.50, 1.90, 0.75, 0.10, 0.85, 25, 4, 7, 0.35, -10, 0.30, 2, 3, -60, 0, 12},
    {"giraffe", 1.80, 2.20, 0.60, 0.35, 1.40, 60, 5, 7, 0.30, -30, 0.45, 2, 4, -70, 0, 4},
};

// Four-legged bodies: quadrupeds, ungulates, elephants and dragons (which add wings and longer necks and tails).
struct FourLegged {
  QuadrupedSpecies species;
  int spine_min, spine_max;
  bool wings;
  bool hooves = false;       // the last leg joint is always there, a Hoof
  double trunk = 0.0;        // trunk length / hind leg length, 0 without one
  int trunk_min = 0, trunk_max = 0;
};

void build_four_legged(Body& body, SplitMix64& rng, RestPose pose, const FourLegged& plan) {
  const QuadrupedSpecies& sp = plan.species;
  body.species = sp.name;
  const bool crouched = pose == RestPose::Crouched;
  const double leg = rng.uniform(sp.leg_min, sp.leg_max);
  const int spine_count = rng.integer(plan.spine_min, plan.spine_max);
  const int neck_count = rng.integer(sp.neck_min, sp.neck_max);
  const int tail_count = rng.integer(sp.tail_min, sp.tail_max);
  const bool toes = plan.hooves || rng.chance(0.75);
  const Part toe = plan.hooves ? Part::Hoof : Part::Toe;
  const bool jaw = rng.chance(plan.wings ? 0.75 : 0.35);
  const bool wing_finger = rng.chance(0.7);
  const double body_length = leg * sp.body * rng.uniform(0.9, 1.1);
  const double rise = leg * sp.rise * rng.uniform(0.5, 1.5);
  const double neck = leg * sp.neck * rng.uniform(0.9, 1.1);
  const double neck_degrees = sp.neck_degrees + rng.uniform(-8.0, 8.0);
  const double head = leg * sp.head * rng.uniform(0.9, 1.1);
  const double tail = leg * sp.tail * rng.uniform(0.85, 1.15);
  const double hip_width = leg * rng.uniform(0.10, 0.14);
  const double hip_drop = 0.06 * leg;
  const double front_ratio = rng.uniform(0.95, 1.1);  // front leg / hind leg
  const double wing = leg * rng.uniform(2.0, 2.8);     // wing root to tip

  // Hind leg: thigh, shin, metatarsus; toes forward on the ground. Crouched:
  // stifle forward, hock back, then the bent leg turned about the hip so that
  // the foot stands right under it (just behind the root).
  LegShape hind;
  hind.bones = {{0.36 * leg, crouched ? 50.0 : 0.0},
                {0.36 * leg, crouched ? -50.0 : 0.0},
                {0.28 * leg, crouched ? std::min(sp.foot_degrees + 10.0, 45.0) : sp.foot_degrees}};
  hind.end_length = (sp.foot_degrees > 45 ? 0.12 : 0.08) * leg;
  if (toes) {
    hind.joints = leg_specs({Part::UpperLeg, Part::LowerLeg, Part::Foot, toe}, "hind", 0);
  } else {
    hind.joints = leg_specs({Part::UpperLeg, Part::LowerLeg, Part::Foot}, "hind", 0);
    hind.bones[1].length += hind.bones[2].length;
    hind.bones.pop_back();
  }
  if (crouched) turn_leg_to_reach(hind.bones, 0.0);
  const double root_height = hip_drop + leg_drop(hind.bones);
  const Vec3 root_position(0.0, root_height, 0.0);
  body.add(spec(Part::Hips), -1, root_position);

  // Spine forward to the chest.
  std::vector<Vec3> spine_points;
  for (int k = 1; k <= spine_count; ++k) {
    spine_points.push_back(root_position + Vec3(0.0, rise * k / spine_count, body_length * k / spine_count));
  }
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, spine_count), spine_points);
  const int chest = spine.back();
  const Vec3 chest_position = body.at(chest);
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);

  // Neck and head, forward and up from the chest.
  std::vector<Vec3> neck_points = curled_chain(chest_position, Vec3::UnitZ(), neck_degrees,
                                               plan.wings ? -40.0 / neck_count : 0.0, neck_count, neck);
  const Vec3 head_position = split_neck(neck_points);
  const std::vector<int> necks = body.add_chain(chest, chain_specs(Part::Neck, neck_count), neck_points);
  const Vec3 head_direction = elevated(Vec3::UnitZ(), sp.head_degrees);
  const int head_joint = body.add(spec(Part::Head), necks.back(), head_position);
  body.head_tip = head_position + head_direction * head;
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Neck, Side::None, 0, necks);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  if (jaw) {
    const Vec3 jaw_position = head_position + head_direction * (0.2 * head) - Vec3::UnitY() * (0.12 * head);
    body.limb(LimbKind::Jaw, Side::None, 0,
              body.add_chain(head_joint, {spec(Part::Jaw)}, {jaw_position, jaw_position + head_direction * (0.7 * head)}));
  }
  if (plan.trunk > 0.0) {  // from the tip of the face, down and curling back a little at the end
    const int count = rng.integer(plan.trunk_min, plan.trunk_max);
    std::vector<Vec3> points = curled_chain(body.head_tip, Vec3::UnitZ(), -60.0, -30.0 / count, count,
                                            plan.trunk * leg * rng.uniform(0.9, 1.1));
    keep_above(points, 0.05 * root_height);
    body.limb(LimbKind::Trunk, Side::None, 0, body.add_chain(head_joint, chain_specs(Part::Trunk, count), points));
  }

  // Tail, back from the hips.
  std::vector<Vec3> tail_points = curled_chain(root_position + Vec3(0.0, 0.03 * leg, -0.1 * leg), -Vec3::UnitZ(),
                                               sp.tail_degrees, sp.tail_curl, tail_count, tail);
  keep_above(tail_points, 0.1 * root_height);
  const std::vector<int> tail_joints = body.add_chain(0, chain_specs(Part::Tail, tail_count), tail_points);
  body.tail_tip = tail_points.back();
  body.limb(LimbKind::Tail, Side::None, 0, tail_joints);

  // Front leg: scapula from the withers down and forward, then humerus, radius, metacarpus.
  // Crouched: elbow back, wrist forward, turned so that the forefoot stands under the withers.
  LegShape front;
  const double front_foot = crouched ? sp.foot_degrees + 5.0 : std::max(0.0, sp.foot_degrees - 5.0);
  front.bones = {{0.22 * leg, crouched ? 40.0 : 30.0},
                 {0.30 * leg * front_ratio, crouched ? -45.0 : 0.0},
                 {0.32 * leg * front_ratio, crouched ? 15.0 : 0.0},
                 {0.16 * leg * front_ratio, front_foot}};
  front.end_length = hind.end_length;
  if (toes) {
    front.joints = leg_specs({Part::Shoulder, Part::UpperLeg, Part::LowerLeg, Part::Foot, toe}, "front", 0);
  } else {
    front.joints = leg_specs({Part::Shoulder, Part::UpperLeg, Part::LowerLeg, Part::Foot}, "front", 0);
    front.bones[2].length += front.bones[3].length;
    front.bones.pop_back();
  }
  if (crouched) turn_leg_to_reach(front.bones, 0.0);
  front.joints[0].qualifier.clear();  // "LeftShoulder": the scapula
  const Vec3 shoulder = chest_position + Vec3(hip_width * 0.9, -0.08 * leg, -0.05 * leg);
  body.paired_limb(LimbKind::Leg, 0, add_leg(body, chest, shoulder, front, LegFit::Scale));
  body.paired_limb(LimbKind::Leg, 1,
                   add_leg(body, 0, root_position + Vec3(hip_width, -hip_drop, -0.02 * leg), hind, LegFit::Scale));

  if (plan.wings) {
    const Vec3 wing_root = chest_position + Vec3(0.12 * leg, 0.1 * leg, -0.05 * leg);
    std::vector<double> lengths = {0.22, 0.3, 0.12, 0.36};  // arm, forearm, hand, finger (fractions of the wing)
    std::vector<Part> parts = {Part::WingArm, Part::WingForeArm, Part::WingHand, Part::WingFinger};
    if (!wing_finger) {
      lengths = {0.25, 0.35, 0.4};
      parts.pop_back();
    }
    std::vector<Vec3> directions;
    if (crouched) {  // folded along the body: out and back, forward, back
      directions = {Vec3(0.5, 0.25, -0.6), Vec3(0.15, 0.1, 1.0), Vec3(0.1, -0.05, -1.0), Vec3(0.05, -0.1, -1.0)};
    } else {
      const Vec3 out = spread(Vec3(1.0, 0.0, -0.1).normalized(), pose, droop_within(45.0, wing_root.y(), wing));
      directions.assign(4, out);
    }
    body.paired_limb(LimbKind::Wing, 0,
                     add_wing(body, chest, wing_root, directions, lengths, parts, wing, 0.1 * root_height));
  }
}

}  // namespace

void build_quadruped(Body& body, SplitMix64& rng, RestPose pose) {
  const QuadrupedSpecies& species = kQuadrupeds[rng.integer(0, static_cast<int>(std::size(kQuadrupeds)) - 1)];
  build_four_legged(body, rng, pose, {species, 2, 4, false});
}

void build_ungulate(Body& body, SplitMix64& rng, RestPose pose) {
  const QuadrupedSpecies& species = kUngulates[rng.integer(0, static_cast<int>(std::size(kUngulates)) - 1)];
  FourLegged plan{species, 2, 4, false};
  plan.hooves = true;
  build_four_legged(body, rng, pose, plan);
}

void build_elephant(Body& body, SplitMix64& rng, RestPose pose) {
  const QuadrupedSpecies elephant{"elephant", 1.6, 2.2, 0.95, 0.05, 0.12, 10, 1, 2, 0.45, -20, 0.5, 2, 4, -75, 0, 0};
  FourLegged plan{elephant, 2, 4, false};
  plan.trunk = 0.75;
  plan.trunk_min = 4;
  plan.trunk_max = 8;
  build_four_legged(body, rng, pose, plan);
}

void build_dragon(Body& body, SplitMix64& rng, RestPose pose) {
  const int neck_max = rng.integer(8, 12);
  const int tail_max = rng.integer(14, 20);
  const QuadrupedSpecies dragon{"dragon", 0.8, 2.0, 1.4, 0.05,     1.3, 35,  6, neck_max,
                                0.5,      -10, 2.2, 8,   tail_max, -12, 1.2, 20};
  build_four_legged(body, rng, pose, {dragon, 3, 5, true});
}

}  // namespace nec::zoo::detail
