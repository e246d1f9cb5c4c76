// The primate body plan: great apes (chimpanzee, gorilla) that knuckle-walk. Their long arms are the front
// legs (clavicle, upper arm, forearm, hand on its knuckles), the shorter hind legs stand on flat feet, the
// body rises from the hips to the shoulders, and there is no tail.
#include "body_plans.h"

#include <algorithm>
#include <cmath>

namespace nec::zoo::detail {

void build_primate(Body& body, SplitMix64& rng, RestPose pose) {
  const bool gorilla = rng.chance(0.4);
  body.species = gorilla ? "gorilla" : "chimpanzee";
  const bool crouched = pose == RestPose::Crouched;
  const double leg = gorilla ? rng.uniform(0.55, 0.7) : rng.uniform(0.45, 0.55);  // hip to sole, along the bones
  const int spine_count = rng.integer(2, 3);
  const int neck_count = rng.integer(1, 2);
  const bool jaw = rng.chance(0.3);
  const double arm = leg * rng.uniform(1.35, 1.5);  // shoulder to knuckles: the arms are the longer limbs
  const double torso = leg * rng.uniform(0.9, 1.05);
  const double neck = leg * rng.uniform(0.08, 0.12);
  const double head = leg * rng.uniform(0.3, 0.35);
  const double hip_width = leg * rng.uniform(0.13, 0.16);
  const double shoulder_width = leg * (gorilla ? rng.uniform(0.32, 0.38) : rng.uniform(0.26, 0.3));
  const double hip_drop = 0.05 * leg;

  // Hind legs bent under the body, the feet flat.
  LegShape hind;
  hind.joints = leg_specs({Part::UpperLeg, Part::LowerLeg, Part::Foot, Part::Toe}, "", 0);
  hind.bones = {{0.45 * leg, crouched ? 60.0 : 35.0}, {0.42 * leg, crouched ? -55.0 : -30.0}, {0.13 * leg, 75.0}};
  hind.end_length = 0.1 * leg;
  turn_leg_to_reach(hind.bones, -0.02 * leg);  // the feet just behind the hips
  const double root_height = hip_drop + leg_drop(hind.bones);
  const Vec3 root_position(0.0, root_height, 0.0);
  body.add(spec(Part::Hips), -1, root_position);

  // The body rises forward from the hips to shoulders as high as the (nearly straight) arms reach.
  const double shoulder_height = 0.92 * arm;
  const double rise = std::asin(std::clamp((shoulder_height - root_height) / torso, 0.2, 0.95));
  const Vec3 up = elevated(Vec3::UnitZ(), rise * 180.0 / kPi);
  std::vector<Vec3> spine_points;
  for (int k = 1; k <= spine_count; ++k) spine_points.push_back(root_position + up * (torso * k / spine_count));
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, spine_count), spine_points);
  const int chest = spine.back();
  const Vec3 neck_base = body.at(chest);
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);

  // A short neck forward and up; the head looks ahead.
  std::vector<Vec3> neck_points = curled_chain(neck_base, Vec3::UnitZ(), 30.0, 0.0, neck_count, neck);
  const Vec3 head_position = split_neck(neck_points);
  const std::vector<int> necks = body.add_chain(chest, chain_specs(Part::Neck, neck_count), neck_points);
  const int head_joint = body.add(spec(Part::Head), necks.back(), head_position);
  body.head_tip = head_position + elevated(Vec3::UnitZ(), 10.0) * head;
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Neck, Side::None, 0, necks);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  if (jaw) {
    const Vec3 jaw_position = head_position + Vec3(0.0, -0.3, 0.3) * head;
    body.limb(LimbKind::Jaw, Side::None, 0,
              body.add_chain(head_joint, {spec(Part::Jaw)}, {jaw_position, jaw_position + Vec3(0.0, -0.05, 0.5) * head}));
  }
  body.tail_tip = root_position - Vec3(0.0, 0.0, 0.1 * leg);

  // Arms as front legs: the clavicle out to the shoulder, then upper arm, forearm and the hand on its knuckles,
  // the fingers curled back under it.
  const int clavicle = body.add(spec(Part::Shoulder, Side::Left), chest, neck_base + Vec3(0.03 * leg, -0.05 * leg, 0.0));
  LegShape front;
  front.joints = {spec(Part::UpperArm, Side::Left), spec(Part::ForeArm, Side::Left), spec(Part::Hand, Side::Left)};
  front.bones = {{0.5 * arm, crouched ? -35.0 : 0.0}, {0.42 * arm, crouched ? 30.0 : 0.0}};
  front.end_direction = -Vec3::UnitZ();
  front.end_length = 0.08 * arm;
  if (crouched) turn_leg_to_reach(front.bones, 0.0);
  std::vector<int> arm_chain{clavicle};
  for (int j : add_leg(body, clavicle, neck_base + Vec3(shoulder_width, -0.06 * leg, 0.0), front, LegFit::Scale)) {
    arm_chain.push_back(j);
  }
  body.paired_limb(LimbKind::Leg, 0, arm_chain);
  body.paired_limb(LimbKind::Leg, 1,
                   add_leg(body, 0, root_position + Vec3(hip_width, -hip_drop, 0.0), hind, LegFit::Scale));
}

}  // namespace nec::zoo::detail
