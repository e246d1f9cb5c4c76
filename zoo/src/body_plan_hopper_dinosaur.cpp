// Two-legged body plans balanced by a tail: hoppers (kangaroo, wallaby: long
// hind feet flat on the ground, a body leaning forward, small arms, a heavy
// tail) and two-legged dinosaurs (the body level over the hips, an S-shaped
// neck, a big head with a jaw, short arms, a long tail held out behind).
#include "body_plans.h"

#include <cmath>

namespace nec::zoo::detail {
namespace {

// Short arms hanging from the chest: upper arm, forearm and hand (left side).
std::vector<int> add_short_arm(Body& body, int chest, const Vec3& base, double length, RestPose pose) {
  const Vec3 out = pose == RestPose::Crouched ? Vec3(0.3, -0.5, 0.8).normalized() : spread(Vec3::UnitX(), pose);
  const Vec3 forearm = pose == RestPose::Crouched ? Vec3(0.1, -0.3, 1.0).normalized() : out;
  return body.add_chain(chest, {spec(Part::UpperArm, Side::Left), spec(Part::ForeArm, Side::Left), spec(Part::Hand, Side::Left)},
                        walk(base, {out * (0.4 * length), forearm * (0.35 * length), forearm * (0.25 * length)}));
}

}  // namespace

void build_hopper(Body& body, SplitMix64& rng, RestPose pose) {
  const bool kangaroo = rng.chance(0.6);
  body.species = kangaroo ? "kangaroo" : "wallaby";
  const bool crouched = pose == RestPose::Crouched;
  const double leg = kangaroo ? rng.uniform(0.8, 1.1) : rng.uniform(0.4, 0.6);  // hip to toe, along the bones
  const int spine_count = rng.integer(2, 3);
  const int neck_count = rng.integer(1, 2);
  const int tail_count = rng.integer(5, 9);
  const double torso = leg * rng.uniform(0.7, 0.85);
  const double neck = leg * rng.uniform(0.15, 0.22);
  const double head = leg * rng.uniform(0.22, 0.28);
  const double tail = leg * rng.uniform(1.0, 1.3);
  const double arm = leg * rng.uniform(0.4, 0.5);
  const double hip_width = leg * rng.uniform(0.08, 0.1);
  const double hip_drop = 0.04 * leg;

  // Thigh forward, shin back, the long foot almost flat on the ground, a toe ahead.
  LegShape legs;
  legs.joints = leg_specs({Part::UpperLeg, Part::LowerLeg, Part::Foot, Part::Toe}, "", 0);
  legs.bones = {{0.3 * leg, crouched ? 70.0 : 45.0}, {0.38 * leg, crouched ? -60.0 : -40.0}, {0.32 * leg, 82.0}};
  legs.end_length = 0.12 * leg;
  turn_leg_to_reach(legs.bones, 0.05 * leg);  // the toe just ahead of the hip, the heel behind
  const double root_height = hip_drop + leg_drop(legs.bones);
  const Vec3 root_position(0.0, root_height, 0.0);
  body.add(spec(Part::Hips), -1, root_position);

  // Body leaning forward and up from the hips; neck and head forward.
  const Vec3 up = elevated(Vec3::UnitZ(), crouched ? 40.0 : 55.0);
  std::vector<Vec3> spine_points;
  for (int k = 1; k <= spine_count; ++k) spine_points.push_back(root_position + up * (torso * k / spine_count));
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, spine_count), spine_points);
  const int chest = spine.back();
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);
  std::vector<Vec3> neck_points = curled_chain(body.at(chest), Vec3::UnitZ(), 60.0, 0.0, neck_count, neck);
  const Vec3 head_position = split_neck(neck_points);
  const std::vector<int> necks = body.add_chain(chest, chain_specs(Part::Neck, neck_count), neck_points);
  const int head_joint = body.add(spec(Part::Head), necks.back(), head_position);
  body.head_tip = head_position + elevated(Vec3::UnitZ(), -20.0) * head;
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Neck, Side::None, 0, necks);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});

  // A heavy tail back and down to the ground, its tip lying on it.
  std::vector<Vec3> tail_points =
      curled_chain(root_position + Vec3(0.0, -0.02 * leg, -0.08 * leg), -Vec3::UnitZ(), -35.0, 5.0, tail_count, tail);
  keep_above(tail_points, 0.02 * root_height);
  body.tail_tip = tail_points.back();
  body.limb(LimbKind::Tail, Side::None, 0, body.add_chain(0, chain_specs(Part::Tail, tail_count), tail_points));

  const Vec3 arm_base = body.at(chest) + Vec3(0.1 * leg, -0.05 * leg, 0.03 * leg);
  const std::vector<int> arms = add_short_arm(body, chest, arm_base, arm, pose);
  body.paired_limb(LimbKind::Leg, 0, add_leg(body, 0, root_position + Vec3(hip_width, -hip_drop, 0.0), legs, LegFit::Scale));
  body.paired_limb(LimbKind::Arm, 0, arms);
}

void build_dinosaur(Body& body, SplitMix64& rng, RestPose pose) {
  const bool tyrannosaurus = rng.chance(0.4);
  body.species = tyrannosaurus ? "tyrannosaurus" : "dinosaur";
  const bool crouched = pose == RestPose::Crouched;
  const double leg = tyrannosaurus ? rng.uniform(2.5, 3.5) : rng.uniform(0.4, 1.6);
  const int spine_count = rng.integer(2, 4);
  const int neck_count = rng.integer(3, 6);
  const int tail_count = rng.integer(8, 16);
  const bool jaw = rng.chance(0.8);
  const double body_length = leg * rng.uniform(0.7, 0.9);
  const double neck = leg * rng.uniform(0.35, 0.5);
  const double head = leg * (tyrannosaurus ? rng.uniform(0.4, 0.5) : rng.uniform(0.2, 0.3));
  const double tail = leg * rng.uniform(1.6, 2.2);
  const double arm = leg * (tyrannosaurus ? rng.uniform(0.2, 0.25) : rng.uniform(0.45, 0.6));
  const double hip_width = leg * rng.uniform(0.1, 0.13);
  const double hip_drop = 0.05 * leg;

  // A bird's leg: thigh forward, shin back, a long metatarsus, toes forward.
  LegShape legs;
  legs.joints = leg_specs({Part::UpperLeg, Part::LowerLeg, Part::Foot, Part::Toe}, "", 0);
  legs.bones = {{0.34 * leg, crouched ? 55.0 : 20.0}, {0.38 * leg, crouched ? -50.0 : -20.0}, {0.28 * leg, 15.0}};
  legs.end_length = 0.15 * leg;
  turn_leg_to_reach(legs.bones, 0.0);  // feet under the hips: the balance point
  const double root_height = hip_drop + leg_drop(legs.bones);
  const Vec3 root_position(0.0, root_height, 0.0);
  body.add(spec(Part::Hips), -1, root_position);

  // The body level forward to the chest; the neck rises and the head looks ahead.
  std::vector<Vec3> spine_points;
  for (int k = 1; k <= spine_count; ++k) {
    spine_points.push_back(root_position + elevated(Vec3::UnitZ(), 5.0) * (body_length * k / spine_count));
  }
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, spine_count), spine_points);
  const int chest = spine.back();
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);
  std::vector<Vec3> neck_points = curled_chain(body.at(chest), Vec3::UnitZ(), 40.0, -40.0 / neck_count, neck_count, neck);
  const Vec3 head_position = split_neck(neck_points);
  const std::vector<int> necks = body.add_chain(chest, chain_specs(Part::Neck, neck_count), neck_points);
  const int head_joint = body.add(spec(Part::Head), necks.back(), head_position);
  const Vec3 head_direction = elevated(Vec3::UnitZ(), -10.0);
  body.head_tip = head_position + head_direction * head;
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Neck, Side::None, 0, necks);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  if (jaw) {
    const Vec3 jaw_position = head_position + head_direction * (0.15 * head) - Vec3::UnitY() * (0.15 * head);
    body.limb(LimbKind::Jaw, Side::None, 0,
              body.add_chain(head_joint, {spec(Part::Jaw)}, {jaw_position, jaw_position + head_direction * (0.8 * head)}));
  }

  // The tail straight back, level, drooping a little towards its tip.
  std::vector<Vec3> tail_points =
      curled_chain(root_position + Vec3(0.0, 0.0, -0.1 * leg), -Vec3::UnitZ(), 0.0, -1.0, tail_count, tail);
  keep_above(tail_points, 0.3 * root_height);
  body.tail_tip = tail_points.back();
  body.limb(LimbKind::Tail, Side::None, 0, body.add_chain(0, chain_specs(Part::Tail, tail_count), tail_points));

  const Vec3 arm_base = body.at(chest) + Vec3(0.1 * leg, -0.08 * leg, 0.0);
  const std::vector<int> arms = add_short_arm(body, chest, arm_base, arm, pose);
  body.paired_limb(LimbKind::Leg, 0, add_leg(body, 0, root_position + Vec3(hip_width, -hip_drop, 0.0), legs, LegFit::Scale));
  body.paired_limb(LimbKind::Arm, 0, arms);
}

}  // namespace nec::zoo::detail
