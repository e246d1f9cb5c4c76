// Arthropod body plans: hexapods (ants, beetles), spiders, centipedes and
// crabs, whose legs of 3 to 5 joints lean out and splay to reach the ground.
#include "body_plans.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace nec::zoo::detail {
namespace {

// An arthropod leg of `joint_count` (3 to 5) joints and total `length`,
// leaning out along `out`, in `pose`; `straight` holds the lean of the
// straight T- and A-pose legs.
LegShape arthropod_leg(int joint_count, double length, const Vec3& out, RestPose pose,
                       std::array<double, 2> straight, int pair_number, double claw) {
  struct Layout {
    std::vector<Part> parts;
    std::vector<double> ratios;
    std::vector<double> crouched;  // femur up and out, tibia down: the knee above the body
  };
  static const Layout layouts[] = {
      {{Part::UpperLeg, Part::LowerLeg, Part::Foot}, {0.45, 0.55}, {125.0, 25.0}},
      {{Part::Coxa, Part::UpperLeg, Part::LowerLeg, Part::Foot}, {0.1, 0.4, 0.5}, {85.0, 130.0, 28.0}},
      {{Part::Coxa, Part::UpperLeg, Part::LowerLeg, Part::Foot, Part::Toe},
       {0.08, 0.32, 0.32, 0.28},
       {80.0, 140.0, 40.0, 15.0}},
  };
  const Layout& layout = layouts[std::clamp(joint_count, 3, 5) - 3];
  LegShape shape;
  shape.joints = leg_specs(layout.parts, "", pair_number);
  for (size_t b = 0; b < layout.ratios.size(); ++b) {
    const double degrees = pose == RestPose::TPose  ? straight[0]
                           : pose == RestPose::APose ? straight[1]
                                                     : layout.crouched[b];
    shape.bones.push_back({layout.ratios[b] * length, degrees});
  }
  shape.out = out;
  shape.end_direction = out;
  shape.end_length = claw * length;
  return shape;
}

// A thorax root standing on `first` (its hips `hip_drop` below the root) and a head at `head` from it (both
// relative to the root), its end site `head_tip` further; returns the head joint.
int add_thorax_and_head(Body& body, const LegShape& first, double hip_drop, const Vec3& head, const Vec3& head_tip) {
  const Vec3 root_position(0.0, hip_drop + leg_drop(first.bones), 0.0);
  body.add(spec(Part::Thorax), -1, root_position);
  const int head_joint = body.add(spec(Part::Head), 0, root_position + head);
  body.head_tip = root_position + head + head_tip;
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  return head_joint;
}

// Straight-leg lean (degrees from down) of arthropod legs in the T- and A-pose.
constexpr std::array<double, 2> kInsectLean{60.0, 40.0};
constexpr std::array<double, 2> kSpiderLean{62.0, 45.0};
constexpr std::array<double, 2> kCentipedeLean{70.0, 50.0};

}  // namespace

void build_hexapod(Body& body, SplitMix64& rng, RestPose pose) {
  const bool ant = rng.chance(0.5);
  body.species = ant ? "ant" : "beetle";
  const double length = rng.uniform(0.05, 0.5);  // head to abdomen tip
  const bool neck = ant || rng.chance(0.3);
  const int antenna_count = rng.integer(2, 4);
  const int abdomen_count = rng.integer(1, 4);
  const int leg_joints = rng.chance(0.6) ? 4 : 3;
  const bool mandibles = rng.chance(0.5);
  const double leg = length * (ant ? 1.0 : 0.6) * rng.uniform(0.85, 1.15);  // middle leg
  const std::array<double, 3> leg_factor{0.85 * rng.uniform(0.95, 1.05), 1.0, 1.1 * rng.uniform(0.95, 1.05)};
  const std::array<double, 3> yaw{40.0 + rng.uniform(-8.0, 8.0), 90.0 + rng.uniform(-8.0, 8.0),
                                  140.0 + rng.uniform(-8.0, 8.0)};
  const double width = length * (ant ? 0.05 : 0.09);

  const double hip_drop = 0.02 * length;
  const LegShape middle = arthropod_leg(leg_joints, leg, horizontal(yaw[1]), pose, kInsectLean, 2, 0.18);
  const Vec3 root_position(0.0, hip_drop + leg_drop(middle.bones), 0.0);
  body.add(spec(Part::Thorax), -1, root_position);

  int head_parent = 0;
  if (neck) {
    const int neck_joint = body.add(chain_specs(Part::Neck, 1)[0], 0, root_position + Vec3(0.0, 0.02, 0.12) * length);
    body.limb(LimbKind::Neck, Side::None, 0, {neck_joint});
    head_parent = neck_joint;
  }
  const Vec3 head_position = root_position + Vec3(0.0, neck ? 0.04 : 0.0, neck ? 0.2 : 0.18) * length;
  const int head_joint = body.add(spec(Part::Head), head_parent, head_position);
  body.head_tip = head_position + Vec3(0.0, -0.01, 0.1) * length;
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  const std::vector<Vec3> antenna = curled_chain(head_position + Vec3(0.03, 0.02, 0.05) * length,
                                                 Vec3(0.5, 0.0, 1.0).normalized(), 35.0, -20.0, antenna_count,
                                                 (ant ? 0.35 : 0.2) * length);
  body.paired_limb(LimbKind::Antenna, 0,
                   body.add_chain(head_joint, chain_specs(Part::Antenna, antenna_count, Side::Left), antenna));
  if (mandibles) {
    const Vec3 base = head_position + Vec3(0.02, -0.02, 0.08) * length;
    body.paired_limb(LimbKind::Jaw, 0,
                     body.add_chain(head_joint, {spec(Part::Mandible, Side::Left)},
                                    {base, base + Vec3(-0.01, -0.005, 0.06) * length}));
  }
  std::vector<Vec3> abdomen;
  for (int k = 0; k < abdomen_count; ++k) {
    const double along = abdomen_count == 1 ? 0.1 : 0.1 + 0.35 * k / (abdomen_count - 1);
    abdomen.push_back(root_position + Vec3(0.0, (ant ? 0.03 : 0.0) * along, -along) * length);
  }
  body.tail_tip = root_position + Vec3(0.0, ant ? 0.02 : 0.0, -0.65) * length;
  abdomen.push_back(body.tail_tip);
  body.limb(LimbKind::Tail, Side::None, 0, body.add_chain(0, chain_specs(Part::Abdomen, abdomen_count), abdomen));

  const std::array<double, 3> attach_z{0.1, 0.0, -0.08};
  for (int pair = 0; pair < 3; ++pair) {
    const LegShape shape =
        arthropod_leg(leg_joints, leg * leg_factor[pair], horizontal(yaw[pair]), pose, kInsectLean, pair + 1, 0.18);
    const Vec3 hip = root_position + Vec3(width, -hip_drop, attach_z[pair] * length);
    body.paired_limb(LimbKind::Leg, pair, add_leg(body, 0, hip, shape, pair == 1 ? LegFit::Scale : LegFit::Splay));
  }
}

void build_spider(Body& body, SplitMix64& rng, RestPose pose) {
  body.species = "spider";
  const double length = rng.uniform(0.05, 0.6);  // head to abdomen tip
  const int leg_joints = rng.integer(3, 5);
  const int abdomen_count = rng.integer(1, 3);
  const bool fangs = rng.chance(0.5);
  const bool palps = rng.chance(0.6);
  const double leg = length * rng.uniform(1.0, 1.8);  // first pair
  const std::array<double, 4> leg_factor{1.0, 0.92 * rng.uniform(0.95, 1.05), 0.8 * rng.uniform(0.95, 1.05),
                                         0.97 * rng.uniform(0.95, 1.05)};
  std::array<double, 4> yaw{35.0, 70.0, 110.0, 150.0};
  for (double& y : yaw) y += rng.uniform(-6.0, 6.0);

  const double hip_drop = 0.01 * length;
  const LegShape first = arthropod_leg(leg_joints, leg, horizontal(yaw[0]), pose, kSpiderLean, 1, 0.15);
  const int head_joint =
      add_thorax_and_head(body, first, hip_drop, Vec3(0.0, 0.03, 0.18) * length, Vec3(0.0, 0.0, 0.1) * length);
  const Vec3 root_position = body.at(0);
  const Vec3 head_position = body.at(head_joint);
  const double floor = 0.1 * root_position.y();
  if (palps) {  // short leg-like feelers in front
    std::vector<Vec3> points = walk(head_position + Vec3(0.03, -0.01, 0.08) * length,
                                    {elevated(horizontal(25.0), -20.0) * (0.12 * length),
                                     elevated(horizontal(15.0), -35.0) * (0.14 * length)});
    keep_above(points, floor);
    body.paired_limb(LimbKind::Antenna, 0, body.add_chain(head_joint, chain_specs(Part::Palp, 2, Side::Left), points));
  }
  if (fangs) {
    std::vector<Vec3> points{head_position + Vec3(0.02, -0.02, 0.06) * length,
                             head_position + Vec3(0.015, -0.08, 0.08) * length};
    keep_above(points, floor);
    body.paired_limb(LimbKind::Jaw, 0, body.add_chain(head_joint, {spec(Part::Fang, Side::Left)}, points));
  }
  std::vector<Vec3> abdomen;
  for (int k = 0; k < abdomen_count; ++k) {
    const double along = abdomen_count == 1 ? 0.15 : 0.15 + 0.4 * k / (abdomen_count - 1);
    abdomen.push_back(root_position + Vec3(0.0, 0.05 * along, -along) * length);
  }
  body.tail_tip = root_position + Vec3(0.0, 0.03, -0.82) * length;
  abdomen.push_back(body.tail_tip);
  body.limb(LimbKind::Tail, Side::None, 0, body.add_chain(0, chain_specs(Part::Abdomen, abdomen_count), abdomen));

  const std::array<double, 4> attach_z{0.08, 0.03, -0.02, -0.07};
  for (int pair = 0; pair < 4; ++pair) {
    const LegShape shape =
        arthropod_leg(leg_joints, leg * leg_factor[pair], horizontal(yaw[pair]), pose, kSpiderLean, pair + 1, 0.15);
    const Vec3 hip = root_position + Vec3(0.06, 0.0, attach_z[pair]) * length - Vec3::UnitY() * hip_drop;
    body.paired_limb(LimbKind::Leg, pair, add_leg(body, 0, hip, shape, pair == 0 ? LegFit::Scale : LegFit::Splay));
  }
}

void build_centipede(Body& body, SplitMix64& rng, RestPose pose) {
  body.species = "centipede";
  // Segments (one leg pair each) and leg joints within 140 joints: fewer leg
  // joints first, then fewer segments.
  int segments = rng.integer(12, 20);
  const int antenna_count = rng.integer(2, 4);
  const bool mandibles = rng.chance(0.5);
  int leg_joints = rng.integer(3, 4);  // 2 or 3 bones
  const int head_joints = 1 + 2 * antenna_count + (mandibles ? 2 : 0);
  auto joint_count = [&] { return head_joints + segments * (1 + 2 * leg_joints); };
  if (joint_count() > 140) leg_joints = 3;
  while (joint_count() > 140) --segments;
  const double length = rng.uniform(0.1, 0.6);
  const double segment = length / (segments + 1.5);
  const double leg = segment * rng.uniform(1.5, 2.5);  // first pair; the last pairs are longer
  const double rear = rng.uniform(0.15, 0.35);         // extra length of the last pair

  const double hip_drop = 0.1 * segment;
  const int middle = segments / 2;  // the root segment
  const LegShape first = arthropod_leg(leg_joints, leg, horizontal(70.0), pose, kCentipedeLean, 1, 0.25);
  const double root_height = hip_drop + leg_drop(first.bones);
  auto segment_position = [&](int k) { return Vec3(0.0, root_height, (middle - k) * segment); };
  body.add(spec(Part::Hips), -1, segment_position(middle));

  std::vector<Vec3> front_points, back_points;
  for (int k = middle - 1; k >= 0; --k) front_points.push_back(segment_position(k));
  for (int k = middle + 1; k < segments; ++k) back_points.push_back(segment_position(k));
  const std::vector<int> front = body.add_chain(0, chain_specs(Part::Spine, middle), front_points);
  body.tail_tip = segment_position(segments - 1) - Vec3::UnitZ() * (0.6 * segment);
  back_points.push_back(body.tail_tip);
  const std::vector<int> back = body.add_chain(0, chain_specs(Part::Abdomen, segments - 1 - middle), back_points);
  body.spine.insert(body.spine.end(), front.begin(), front.end());
  body.limb(LimbKind::Spine, Side::None, 0, front);
  body.limb(LimbKind::Tail, Side::None, 0, back);
  std::vector<int> trunk(static_cast<size_t>(segments));  // trunk joint of segment k, front to back
  trunk[middle] = 0;
  for (int k = 0; k < middle; ++k) trunk[k] = front[middle - 1 - k];
  for (int k = middle + 1; k < segments; ++k) trunk[k] = back[k - middle - 1];

  const Vec3 head_position = segment_position(0) + Vec3(0.0, 0.0, 0.8 * segment);
  const int head_joint = body.add(spec(Part::Head), trunk[0], head_position);
  body.head_tip = head_position + Vec3(0.0, 0.0, 0.6 * segment);
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  const std::vector<Vec3> antenna =
      curled_chain(head_position + Vec3(0.2, 0.1, 0.3) * segment, Vec3(0.4, 0.0, 1.0).normalized(), 20.0, -10.0,
                   antenna_count, 2.0 * segment);
  body.paired_limb(LimbKind::Antenna, 0,
                   body.add_chain(head_joint, chain_specs(Part::Antenna, antenna_count, Side::Left), antenna));
  if (mandibles) {
    std::vector<Vec3> points{head_position + Vec3(0.2, -0.15, 0.2) * segment,
                             head_position + Vec3(0.05, -0.2, 0.7) * segment};
    keep_above(points, 0.1 * root_height);
    body.paired_limb(LimbKind::Jaw, 0, body.add_chain(head_joint, {spec(Part::Mandible, Side::Left)}, points));
  }

  for (int pair = 0; pair < segments; ++pair) {
    const double along = static_cast<double>(pair) / (segments - 1);
    const LegShape shape = arthropod_leg(leg_joints, leg * (1.0 + rear * along), horizontal(70.0 + 40.0 * along), pose,
                                         kCentipedeLean, pair + 1, 0.25);
    const Vec3 hip = body.at(trunk[pair]) + Vec3(0.35 * segment, -hip_drop, 0.0);
    body.paired_limb(LimbKind::Leg, pair, add_leg(body, trunk[pair], hip, shape, pair == 0 ? LegFit::Scale : LegFit::Splay));
  }
}

void build_crab(Body& body, SplitMix64& rng, RestPose pose) {
  body.species = "crab";
  const double width = rng.uniform(0.04, 0.4);  // across the shell
  const int leg_joints = rng.integer(4, 5);
  const bool eyes = rng.chance(0.7);
  const bool pincer = rng.chance(0.7);  // the claw's moving finger as a joint of its own
  const double leg = width * rng.uniform(0.9, 1.4);
  const double claw = width * rng.uniform(0.6, 1.0);  // claw arm length
  std::array<double, 4> yaw{60.0, 82.0, 104.0, 126.0};  // legs out to the sides, the last ones swept back
  for (double& y : yaw) y += rng.uniform(-5.0, 5.0);

  const double hip_drop = 0.02 * width;
  const LegShape first = arthropod_leg(leg_joints, leg, horizontal(yaw[0]), pose, kSpiderLean, 1, 0.1);
  const int head_joint =
      add_thorax_and_head(body, first, hip_drop, Vec3(0.0, 0.02, 0.3) * width, Vec3(0.0, 0.0, 0.06) * width);
  const Vec3 root_position = body.at(0);
  const Vec3 head_position = body.at(head_joint);
  const double floor = 0.1 * root_position.y();
  if (eyes) {  // eye stalks, up and a little out
    const Vec3 base = head_position + Vec3(0.08, 0.03, 0.0) * width;
    body.paired_limb(LimbKind::Antenna, 0,
                     body.add_chain(head_joint, chain_specs(Part::Antenna, 1, Side::Left),
                                    {base, base + Vec3(0.03, 0.12, 0.02) * width}));
  }
  // The abdomen folded under the shell, at the back.
  body.tail_tip = root_position + Vec3(0.0, -0.08, -0.3) * width;
  body.limb(LimbKind::Tail, Side::None, 0,
            body.add_chain(0, chain_specs(Part::Abdomen, 1), {root_position + Vec3(0.0, -0.04, -0.15) * width, body.tail_tip}));

  // Claws from the front corners: out and forward, the forearm turned in, the pincer ahead.
  const Vec3 claw_base = root_position + Vec3(0.22, 0.0, 0.22) * width;
  std::vector<Vec3> claw_points = walk(claw_base, {Vec3(0.7, -0.2, 0.6).normalized() * (0.35 * claw),
                                                   Vec3(-0.2, 0.05, 1.0).normalized() * (0.3 * claw),
                                                   Vec3(-0.1, 0.0, 1.0).normalized() * (0.35 * claw)});
  std::vector<JointSpec> claw_specs = {spec(Part::UpperArm, Side::Left), spec(Part::ForeArm, Side::Left),
                                       spec(Part::Hand, Side::Left)};
  if (pincer) {  // the moving finger from the palm's middle, beside the fixed one
    claw_specs.push_back(spec(Part::Claw, Side::Left));
    claw_points.insert(claw_points.end() - 1, claw_points[2] + 0.45 * (claw_points[3] - claw_points[2]));
  }
  keep_above(claw_points, floor);
  body.paired_limb(LimbKind::Arm, 0, body.add_chain(0, claw_specs, claw_points));

  const std::array<double, 4> attach_z{0.12, 0.04, -0.04, -0.12};
  for (int pair = 0; pair < 4; ++pair) {
    const LegShape shape = arthropod_leg(leg_joints, leg * (pair == 3 ? 0.85 : 1.0), horizontal(yaw[pair]), pose,
                                         kSpiderLean, pair + 1, 0.1);
    const Vec3 hip = root_position + Vec3(0.3, 0.0, attach_z[pair]) * width - Vec3::UnitY() * hip_drop;
    body.paired_limb(LimbKind::Leg, pair, add_leg(body, 0, hip, shape, pair == 0 ? LegFit::Scale : LegFit::Splay));
  }
}

}  // namespace nec::zoo::detail
