// Internal to creature building: what each joint is (for its name), the body
// under construction, the geometry and leg builders every plan shares
// (body_builder.cpp), and one builder per body plan (body_plan_*.cpp).
#pragma once

#include "nec/zoo/creature.h"

#include "nec/motion/random.h"

#include "zoo_math.h"

#include <string>
#include <vector>

namespace nec::zoo::detail {

// ---- joint names (creature_naming.cpp) ----

// What a joint is; the naming style turns it into words.
enum class Part {
  Hips, Thorax, Spine, Abdomen, Neck, Head, Jaw, Mandible, Fang, Tail,
  Shoulder, UpperArm, ForeArm, Hand,
  Coxa, UpperLeg, LowerLeg, Foot, Toe,
  WingArm, WingForeArm, WingHand, WingFinger,
  Fin, Antenna, Palp,
  Claw,   // a crab's pincer
  Hoof,   // an ungulate's last joint
  Trunk,  // an elephant's trunk
};

struct JointSpec {
  Part part = Part::Spine;
  Side side = Side::None;
  std::string qualifier;  // lower-case word before the part: "front", "hind", "pectoral", ...
  int pair = 0;           // leg pair number in the name (many-legged plans), 1-based; 0 = none
  int index = -1;         // position in a chain (spine, neck, tail, ...), 0-based; -1 = single joint
  int segment = 0;        // position in a numbered leg, 0-based ("leg_l_03_02" in the Game style)
};

// One joint of `part`.
JointSpec spec(Part part, Side side = Side::None, std::string qualifier = {});
// `count` joints of one part, numbered along the chain.
std::vector<JointSpec> chain_specs(Part part, int count, Side side = Side::None, const std::string& qualifier = {});
// Names for every style but Numbered (which only needs the joint index).
std::string joint_name(const JointSpec& joint, NamingStyle style);

// ---- geometry helpers (meters, creature frame; body_builder.cpp) ----

// Horizontal unit vector at `yaw_degrees` from +Z towards +X (the left side).
Vec3 horizontal(double yaw_degrees);
// `direction` (horizontal) raised by `degrees` (negative: lowered).
Vec3 elevated(const Vec3& direction, double degrees);
// Straight down, leaning by `degrees` towards the horizontal `out`.
Vec3 down_toward(const Vec3& out, double degrees);
// The points start, start + steps[0], start + steps[0] + steps[1], ...
std::vector<Vec3> walk(const Vec3& start, const std::vector<Vec3>& steps);
// A chain of `count` equal segments of total `length` from `start`, each turned
// by `curl_degrees` more than the previous about the axis perpendicular to
// `direction` (horizontal) and up: positive curls upwards.
std::vector<Vec3> curled_chain(const Vec3& start, const Vec3& direction, double elevation_degrees,
                               double curl_degrees, int count, double length);
// Turns the points of a neck (from the chest to the head) into neck joint
// positions, each 30% along its segment so that no bone has zero length, and
// returns the head position (the last point).
Vec3 split_neck(std::vector<Vec3>& points);
// Squashes a chain hanging from points[0] vertically so that no point is below `floor`.
void keep_above(std::vector<Vec3>& points, double floor);
// Droop angle (degrees) of a limb of `length` hanging from `height`: `wanted`,
// or less so that its tip stays above 10% of the height.
double droop_within(double wanted, double height, double length);
// Arm, wing and fin directions of the rest poses (left side).
Vec3 spread(const Vec3& out, RestPose pose, double droop_limit = 45.0);

// ---- the body under construction (body_builder.cpp) ----

struct Body {
  struct Joint {
    JointSpec spec;
    int parent = -1;
    Vec3 position = Vec3::Zero();  // rest position, meters, creature frame
  };
  struct EndPoint {
    int parent = 0;
    Vec3 position = Vec3::Zero();
  };

  std::string species;
  std::vector<Joint> joints;
  std::vector<EndPoint> ends;
  std::vector<Limb> limbs;  // joints are Body indices until the finish
  std::vector<int> spine{0};
  Vec3 head_tip = Vec3::Zero();  // front and back ends of the body, for body_length
  Vec3 tail_tip = Vec3::Zero();

  int add(const JointSpec& joint, int parent, const Vec3& position) {
    joints.push_back({joint, parent, position});
    return static_cast<int>(joints.size()) - 1;
  }
  void end(int parent, const Vec3& position) { ends.push_back({parent, position}); }
  const Vec3& at(int joint) const { return joints[joint].position; }

  // One joint per spec at points[k], each the child of the previous and the
  // first the child of `parent`; an end site at points[n] when there is one more point.
  std::vector<int> add_chain(int parent, const std::vector<JointSpec>& specs, const std::vector<Vec3>& points);

  // Right-side copies of left-side joints (listed parents first) and of their
  // end sites: x negated, so the offsets mirror exactly.
  std::vector<int> mirror(const std::vector<int>& left);

  // A limb of these joints (none when `chain` is empty).
  void limb(LimbKind kind, Side side, int pair, std::vector<int> chain);

  // A left limb and its mirror.
  void paired_limb(LimbKind kind, int pair, const std::vector<int>& left);
};

// ---- legs (body_builder.cpp) ----

struct LegBone {
  double length = 0.0;   // meters, or a ratio before fitting
  double degrees = 0.0;  // lean from straight down towards the leg's `out` direction
};

struct LegShape {
  std::vector<JointSpec> joints;        // proximal -> distal; the last one stands on the ground
  std::vector<LegBone> bones;           // joints.size() - 1 bones between consecutive joints
  Vec3 out = Vec3::UnitZ();             // horizontal direction the bones lean towards (left side)
  Vec3 end_direction = Vec3::UnitZ();   // horizontal direction of the tip's end site (toe, claw)
  double end_length = 0.0;              // length of that end site, in the bones' units
};

enum class LegFit {
  Scale,  // keep the angles, scale the bones to reach the ground
  Splay,  // keep the lengths, lean the whole leg out or in to reach the ground (arthropods)
};

// How far down the leg reaches when every bone leans `splay` degrees further out.
double leg_drop(const std::vector<LegBone>& bones, double splay = 0.0);
// Turns the whole leg about its hip, every bone by the same angle (so each
// joint keeps its bend), until the last joint is `ahead` (bone units, negative:
// behind) in front of the hip along the leg's `out` direction. A crouch bends
// the knees forward and the ankles back; this keeps the foot under the body
// instead of wherever the bends happen to put it.
void turn_leg_to_reach(std::vector<LegBone>& bones, double ahead);
// Adds a left leg from `hip` whose last joint lands on y = 0; returns its joints.
std::vector<int> add_leg(Body& body, int parent, const Vec3& hip, LegShape shape, LegFit fit);
// Leg joint specs: the parts, with a side, qualifier and (many-legged plans) pair number.
std::vector<JointSpec> leg_specs(const std::vector<Part>& parts, const std::string& qualifier, int pair_number);

// ---- wings (body_builder.cpp) ----

// Adds a left wing from `root`, one joint per part: bone b is lengths[b] * `wing`
// long along directions[b], the chain squashed to stay above `floor`; returns its joints.
std::vector<int> add_wing(Body& body, int parent, const Vec3& root, const std::vector<Vec3>& directions,
                          const std::vector<double>& lengths, const std::vector<Part>& parts, double wing,
                          double floor);

// ---- body plans: each adds the joints, end sites and limbs of one animal drawn from `rng` ----

// body_plan_biped_bird.cpp
void build_biped(Body& body, SplitMix64& rng, RestPose pose);
void build_bird(Body& body, SplitMix64& rng, RestPose pose);
// body_plan_quadruped_dragon.cpp
void build_quadruped(Body& body, SplitMix64& rng, RestPose pose);
void build_dragon(Body& body, SplitMix64& rng, RestPose pose);
void build_ungulate(Body& body, SplitMix64& rng, RestPose pose);
void build_elephant(Body& body, SplitMix64& rng, RestPose pose);
// body_plan_snake_fish.cpp
void build_snake(Body& body, SplitMix64& rng, RestPose pose);
void build_fish(Body& body, SplitMix64& rng, RestPose pose);
// body_plan_arthropods.cpp
void build_hexapod(Body& body, SplitMix64& rng, RestPose pose);
void build_spider(Body& body, SplitMix64& rng, RestPose pose);
void build_centipede(Body& body, SplitMix64& rng, RestPose pose);
void build_crab(Body& body, SplitMix64& rng, RestPose pose);
// body_plan_bird.cpp (ground birds: species of longer legs and necks, on the bird's builder)
void build_ground_bird(Body& body, SplitMix64& rng, RestPose pose);
// body_plan_hopper_dinosaur.cpp
void build_hopper(Body& body, SplitMix64& rng, RestPose pose);
void build_dinosaur(Body& body, SplitMix64& rng, RestPose pose);
// body_plan_primate.cpp
void build_primate(Body& body, SplitMix64& rng, RestPose pose);

}  // namespace nec::zoo::detail
