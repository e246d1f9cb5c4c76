// Two-legged body plans: the person (spine, neck, head, arms; crouched: knees
// bent with the feet under the hips) and the birds (body tilted up, S-shaped
// neck, tail, wings spread, drooping or folded): any bird, and the ground birds
// (flamingo, heron, chicken, ostrich) with their own proportions and three toes.
#include "body_plans.h"

#include <cmath>
#include <iterator>
#include <utility>

namespace nec::zoo::detail {

void build_biped(Body& body, SplitMix64& rng, RestPose pose) {
  body.species = "person";
  const bool crouched = pose == RestPose::Crouched;
  const double height = rng.uniform(1.5, 1.95);
  const int spine_count = rng.integer(1, 4);
  const int neck_count = rng.integer(1, 2);
  const bool clavicles = rng.chance(0.8);
  const bool toes = rng.chance(0.8);
  const bool jaw = rng.chance(0.2);
  const double thigh = height * rng.uniform(0.235, 0.255);
  const double shin = height * rng.uniform(0.235, 0.255);
  const double foot = height * rng.uniform(0.07, 0.085);  // ankle to ball
  const double toe = height * rng.uniform(0.03, 0.04);
  const double hip_width = height * rng.uniform(0.05, 0.06);
  const double hip_drop = height * rng.uniform(0.025, 0.035);
  const double torso = height * rng.uniform(0.27, 0.30);  // hips to neck base
  const double neck = height * rng.uniform(0.05, 0.07);
  const double head = height * rng.uniform(0.11, 0.13);
  const double shoulder_width = height * rng.uniform(0.09, 0.11);
  const double upper_arm = height * rng.uniform(0.17, 0.19);
  const double forearm = height * rng.uniform(0.14, 0.16);
  const double hand = height * rng.uniform(0.09, 0.11);

  // Crouched: the knee bends forward and the ankle back (85 degrees at the
  // knee), then the bent leg turns about the hip so that the foot (its last
  // joint) stands under the hips, as a crouching person balances.
  LegShape leg;
  const double foot_degrees = crouched ? 75.0 : 68.0;
  const LegBone thigh_bone{thigh, crouched ? 50.0 : 0.0};
  const double shin_degrees = crouched ? -35.0 : 0.0;
  if (toes) {
    leg.joints = leg_specs({Part::UpperLeg, Part::LowerLeg, Part::Foot, Part::Toe}, "", 0);
    leg.bones = {thigh_bone, {shin, shin_degrees}, {foot, foot_degrees}};
    leg.end_length = toe;
  } else {
    leg.joints = leg_specs({Part::UpperLeg, Part::LowerLeg, Part::Foot}, "", 0);
    leg.bones = {thigh_bone, {shin + foot * std::cos(radians(foot_degrees)), shin_degrees}};
    leg.end_length = foot + toe;
  }
  if (crouched) turn_leg_to_reach(leg.bones, 0.0);  // the hips are right above the root
  const double root_height = hip_drop + leg_drop(leg.bones);
  const Vec3 root_position(0.0, root_height, 0.0);
  body.add(spec(Part::Hips), -1, root_position);

  const Vec3 up = crouched ? elevated(Vec3::UnitZ(), 70.0) : Vec3::UnitY();  // crouched leans forward
  std::vector<Vec3> spine_points;
  for (int k = 1; k <= spine_count; ++k) spine_points.push_back(root_position + up * (torso * k / (spine_count + 1)));
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, spine_count), spine_points);
  const Vec3 neck_base = root_position + up * torso;
  std::vector<Vec3> neck_points;
  for (int k = 0; k < neck_count; ++k) neck_points.push_back(neck_base + up * (neck * k / neck_count));
  const std::vector<int> necks = body.add_chain(spine.back(), chain_specs(Part::Neck, neck_count), neck_points);
  const Vec3 head_position = neck_base + up * neck;
  const int head_joint = body.add(spec(Part::Head), necks.back(), head_position);
  body.head_tip = head_position + up * head;
  body.end(head_joint, body.head_tip);
  body.tail_tip = root_position;
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);
  body.limb(LimbKind::Neck, Side::None, 0, necks);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  if (jaw) {
    const Vec3 jaw_position = head_position + Vec3(0.0, -0.01, 0.03) * height;
    body.limb(LimbKind::Jaw, Side::None, 0,
              body.add_chain(head_joint, {spec(Part::Jaw)}, {jaw_position, jaw_position + Vec3(0, -0.04, 0.06) * height}));
  }

  // Arms from the chest: horizontal (T), 45 degrees down (A), or down with the forearms forward (crouched).
  const Vec3 upper_direction = spread(Vec3::UnitX(), pose);
  const Vec3 lower_direction = crouched ? Vec3(0.3, -0.6, 0.75).normalized() : upper_direction;
  std::vector<JointSpec> arm_specs;
  std::vector<Vec3> arm_points;
  const Vec3 arm_base = neck_base + Vec3(shoulder_width, -0.04 * height, 0.0);
  if (clavicles) {
    arm_specs.push_back(spec(Part::Shoulder, Side::Left));
    arm_points.push_back(neck_base + Vec3(0.02 * height, -0.03 * height, 0.0));
  }
  for (Part part : {Part::UpperArm, Part::ForeArm, Part::Hand}) arm_specs.push_back(spec(part, Side::Left));
  for (const Vec3& p : walk(arm_base, {upper_direction * upper_arm, lower_direction * forearm, lower_direction * hand})) {
    arm_points.push_back(p);
  }
  const std::vector<int> arm = body.add_chain(spine.back(), arm_specs, arm_points);

  const std::vector<int> leg_joints = add_leg(body, 0, root_position + Vec3(hip_width, -hip_drop, 0.0), leg, LegFit::Scale);
  body.paired_limb(LimbKind::Leg, 0, leg_joints);
  body.paired_limb(LimbKind::Arm, 0, arm);
}

namespace {

// Proportions of a bird species, relative to its leg length (the body's to the body length).
struct BirdSpecies {
  const char* name;
  double leg_min, leg_max;    // hip to foot, meters
  double body_min, body_max;  // hips to chest
  double neck_min, neck_max;
  double wing_min, wing_max;  // wing root to tip / body length
  double body_degrees;        // body elevation from the hips, standing
  bool side_toes;             // inner and outer toes beside the middle one (the leg's chain)
};

const BirdSpecies kBird{"bird", 0.12, 0.9, 0.8, 1.3, 0.4, 1.3, 1.2, 2.5, 25.0, false};
const BirdSpecies kGroundBirds[] = {
    {"flamingo", 0.9, 1.2, 0.45, 0.6, 0.9, 1.2, 1.8, 2.4, 10.0, true},
    {"heron", 0.6, 0.9, 0.55, 0.7, 0.8, 1.1, 2.0, 2.6, 20.0, true},
    {"chicken", 0.15, 0.25, 1.2, 1.6, 0.5, 0.8, 0.9, 1.3, 20.0, true},
    {"ostrich", 1.0, 1.3, 0.7, 0.9, 0.9, 1.2, 0.7, 1.0, 10.0, true},
};

void build_bird_of(Body& body, SplitMix64& rng, RestPose pose, const BirdSpecies& species) {
  body.species = species.name;
  const bool crouched = pose == RestPose::Crouched;
  const double leg = rng.uniform(species.leg_min, species.leg_max);
  const int spine_count = rng.integer(1, 3);
  const int neck_count = rng.integer(3, 8);
  const int tail_count = rng.integer(1, 3);
  const bool jaw = rng.chance(0.4);
  const bool wing_finger = rng.chance(0.4);
  const double body_length = leg * rng.uniform(species.body_min, species.body_max);
  const double neck = leg * rng.uniform(species.neck_min, species.neck_max);
  const double head = leg * rng.uniform(0.25, 0.4);
  const double tail = body_length * rng.uniform(0.4, 0.8);
  const double wing = body_length * rng.uniform(species.wing_min, species.wing_max);
  const double hip_width = leg * rng.uniform(0.08, 0.12);
  const double hip_drop = 0.05 * leg;

  // Crouched: knee forward, ankle back, the foot under the root (the hips
  // are slightly ahead of it; the bones are not scaled, see add_leg).
  LegShape legs;
  legs.joints = leg_specs({Part::UpperLeg, Part::LowerLeg, Part::Foot, Part::Toe}, "", 0);
  legs.bones = {
      {0.28 * leg, crouched ? 55.0 : 0.0}, {0.42 * leg, crouched ? -45.0 : 0.0}, {0.30 * leg, crouched ? 30.0 : 5.0}};
  legs.end_length = 0.18 * leg;
  const double hip_ahead = 0.05 * body_length;
  if (crouched) turn_leg_to_reach(legs.bones, -hip_ahead);
  const double root_height = hip_drop + leg_drop(legs.bones);
  const Vec3 root_position(0.0, root_height, 0.0);
  body.add(spec(Part::Hips), -1, root_position);

  // Body tilted up towards the chest; an S-shaped neck; the beak forward.
  const Vec3 body_direction = elevated(Vec3::UnitZ(), crouched ? 10.0 : species.body_degrees);
  std::vector<Vec3> spine_points;
  for (int k = 1; k <= spine_count; ++k)
    spine_points.push_back(root_position + body_direction * (body_length * k / spine_count));
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, spine_count), spine_points);
  const int chest = spine.back();
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);
  std::vector<Vec3> neck_points = curled_chain(body.at(chest), Vec3::UnitZ(), 75.0, -50.0 / neck_count, neck_count, neck);
  const Vec3 head_position = split_neck(neck_points);
  const std::vector<int> necks = body.add_chain(chest, chain_specs(Part::Neck, neck_count), neck_points);
  const int head_joint = body.add(spec(Part::Head), necks.back(), head_position);
  body.head_tip = head_position + Vec3::UnitZ() * head;
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Neck, Side::None, 0, necks);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  if (jaw) {  // lower beak
    const Vec3 jaw_position = head_position + Vec3(0.0, -0.08 * head, 0.3 * head);
    body.limb(LimbKind::Jaw, Side::None, 0,
              body.add_chain(head_joint, {spec(Part::Jaw)},
                             {jaw_position, jaw_position + Vec3(0.0, -0.02 * head, 0.65 * head)}));
  }
  const std::vector<Vec3> tail_points =
      curled_chain(root_position + Vec3(0.0, 0.0, -0.1 * body_length), -Vec3::UnitZ(), 15.0, 0.0, tail_count, tail);
  body.tail_tip = tail_points.back();
  body.limb(LimbKind::Tail, Side::None, 0, body.add_chain(0, chain_specs(Part::Tail, tail_count), tail_points));

  // Wings from the chest: spread (T), drooping (A) or folded back (crouched).
  const Vec3 wing_root = body.at(chest) + Vec3(0.1 * body_length, 0.05 * body_length, -0.1 * body_length);
  std::vector<double> lengths = {0.3, 0.35, 0.35};
  std::vector<Part> parts = {Part::WingArm, Part::WingForeArm, Part::WingHand};
  if (wing_finger) {
    lengths = {0.3, 0.35, 0.2, 0.15};
    parts.push_back(Part::WingFinger);
  }
  std::vector<Vec3> directions;
  if (crouched) {
    directions = {Vec3(0.4, 0.0, -0.9), Vec3(0.15, 0.05, 1.0), Vec3(0.05, 0.0, -1.0), Vec3(0.05, 0.0, -1.0)};
  } else {
    directions.assign(4, spread(Vec3::UnitX(), pose, droop_within(45.0, wing_root.y(), wing)));
  }
  const std::vector<int> wings = add_wing(body, chest, wing_root, directions, lengths, parts, wing, 0.1 * root_height);

  const std::vector<int> leg_joints =
      add_leg(body, 0, root_position + Vec3(hip_width, -hip_drop, hip_ahead), legs, LegFit::Scale);
  if (species.side_toes) {  // inner and outer toes fanning out from the foot, mirrored with the leg
    const int foot = leg_joints[leg_joints.size() - 2];
    const double toe = legs.end_length;
    std::vector<int> left = leg_joints;
    for (const auto& [qualifier, yaw] : {std::pair{"inner", -35.0}, std::pair{"outer", 35.0}}) {
      const Vec3 start = body.at(leg_joints.back());  // the ball of the foot, on the ground
      const int joint = body.add(spec(Part::Toe, Side::Left, qualifier), foot, start);
      body.end(joint, start + horizontal(yaw) * (0.8 * toe));
      left.push_back(joint);
    }
    const std::vector<int> right = body.mirror(left);
    body.limb(LimbKind::Leg, Side::Left, 0, leg_joints);
    body.limb(LimbKind::Leg, Side::Right, 0, std::vector<int>(right.begin(), right.begin() + leg_joints.size()));
  } else {
    body.paired_limb(LimbKind::Leg, 0, leg_joints);
  }
  body.paired_limb(LimbKind::Wing, 0, wings);
}

}  // namespace

void build_bird(Body& body, SplitMix64& rng, RestPose pose) { build_bird_of(body, rng, pose, kBird); }

void build_ground_bird(Body& body, SplitMix64& rng, RestPose pose) {
  build_bird_of(body, rng, pose, kGroundBirds[rng.integer(0, static_cast<int>(std::size(kGroundBirds)) - 1)]);
}

}  // namespace nec::zoo::detail
