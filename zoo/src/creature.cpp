// Procedural creatures (creature.h). One builder per body plan places joints
// at their rest positions, in meters, in the creature's frame (faces +Z, +Y up,
// left at +X); a common finish turns that into a BVH-ready skeleton: ground at
// y = 0, file units, depth-first joint order, names in the chosen style,
// channels, end sites, and the limb metadata.
//
// Legs are built on the left and mirrored (x negated), so both sides are
// exactly symmetric. A leg is a list of bones, each leaning from straight down
// towards a horizontal direction by an angle that depends on the rest pose;
// the bones are fitted so that the leg's last joint lands on y = 0.
#include "nec/zoo/creature.h"

#include "nec/motion/random.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>

namespace nec::zoo {
namespace {

constexpr double kPi = 3.14159265358979323846;
double radians(double degrees) { return degrees * kPi / 180.0; }

// ---- deterministic random numbers (motion/random.h: the same creature for a seed everywhere) ----

// Independent random streams of one (plan, seed): the body, the style options, the units.
enum class Stream : uint64_t { Body = 1, Options = 2, Units = 3 };

SplitMix64 stream(BodyPlan plan, uint64_t seed, Stream which) {
  SplitMix64 mixer(seed ^ (0xD1B54A32D192ED03ull * (static_cast<uint64_t>(plan) + 1)) ^
               (0x8CB92BA72F3D8DD7ull * static_cast<uint64_t>(which)));
  return SplitMix64(mixer.next());
}

// ---- joint names ----

// What a joint is; the naming style turns it into words.
enum class Part {
  Hips, Thorax, Spine, Abdomen, Neck, Head, Jaw, Mandible, Fang, Tail,
  Shoulder, UpperArm, ForeArm, Hand,
  Coxa, UpperLeg, LowerLeg, Foot, Toe,
  WingArm, WingForeArm, WingHand, WingFinger,
  Fin, Antenna, Palp,
};

// The word of a part in each naming style. Every word maps to a meaningful
// canonical name (nec::canonical_joint_name): thigh/UpLeg -> "upper leg",
// calf/shin -> "lower leg", clavicle -> "shoulder", pelvis -> "hips",
// abdomen -> "spine", thorax -> "chest", forearm -> "lower arm".
struct PartWords {
  const char* mixamo;
  const char* blender;
  const char* game;
  const char* biped3ds;
};

PartWords part_words(Part part) {
  switch (part) {
    case Part::Hips: return {"Hips", "hips", "pelvis", "Pelvis"};
    case Part::Thorax: return {"Thorax", "thorax", "thorax", "Thorax"};
    case Part::Spine: return {"Spine", "spine", "spine", "Spine"};
    case Part::Abdomen: return {"Abdomen", "abdomen", "abdomen", "Abdomen"};
    case Part::Neck: return {"Neck", "neck", "neck", "Neck"};
    case Part::Head: return {"Head", "head", "head", "Head"};
    case Part::Jaw: return {"Jaw", "jaw", "jaw", "Jaw"};
    case Part::Mandible: return {"Mandible", "mandible", "mandible", "Mandible"};
    case Part::Fang: return {"Fang", "fang", "fang", "Fang"};
    case Part::Tail: return {"Tail", "tail", "tail", "Tail"};
    case Part::Shoulder: return {"Shoulder", "shoulder", "clavicle", "Clavicle"};
    case Part::UpperArm: return {"Arm", "upper_arm", "upperarm", "UpperArm"};
    case Part::ForeArm: return {"ForeArm", "forearm", "forearm", "Forearm"};
    case Part::Hand: return {"Hand", "hand", "hand", "Hand"};
    case Part::Coxa: return {"Coxa", "coxa", "coxa", "Coxa"};
    case Part::UpperLeg: return {"UpLeg", "thigh", "thigh", "Thigh"};
    case Part::LowerLeg: return {"Leg", "shin", "calf", "Calf"};
    case Part::Foot: return {"Foot", "foot", "foot", "Foot"};
    case Part::Toe: return {"ToeBase", "toe", "toe", "Toe"};
    case Part::WingArm: return {"WingArm", "wing_upper_arm", "wing_upperarm", "Wing UpperArm"};
    case Part::WingForeArm: return {"WingForeArm", "wing_forearm", "wing_forearm", "Wing Forearm"};
    case Part::WingHand: return {"WingHand", "wing_hand", "wing_hand", "Wing Hand"};
    case Part::WingFinger: return {"WingFinger", "wing_finger", "wing_finger", "Wing Finger"};
    case Part::Fin: return {"Fin", "fin", "fin", "Fin"};
    case Part::Antenna: return {"Antenna", "antenna", "antenna", "Antenna"};
    case Part::Palp: return {"Palp", "palp", "palp", "Palp"};
  }
  return {"Joint", "joint", "joint", "Joint"};
}

bool is_leg_part(Part part) {
  return part == Part::Coxa || part == Part::UpperLeg || part == Part::LowerLeg || part == Part::Foot ||
         part == Part::Toe;
}

struct JointSpec {
  Part part = Part::Spine;
  Side side = Side::None;
  std::string qualifier;  // lower-case word before the part: "front", "hind", "pectoral", ...
  int pair = 0;           // leg pair number in the name (many-legged plans), 1-based; 0 = none
  int index = -1;         // position in a chain (spine, neck, tail, ...), 0-based; -1 = single joint
  int segment = 0;        // position in a numbered leg, 0-based ("leg_l_03_02" in the Game style)
};

JointSpec spec(Part part, Side side = Side::None, std::string qualifier = {}) {
  JointSpec s;
  s.part = part;
  s.side = side;
  s.qualifier = std::move(qualifier);
  return s;
}

// `count` joints of one part, numbered along the chain.
std::vector<JointSpec> chain_specs(Part part, int count, Side side = Side::None, const std::string& qualifier = {}) {
  std::vector<JointSpec> specs;
  for (int k = 0; k < count; ++k) {
    JointSpec s = spec(part, side, qualifier);
    s.index = k;
    specs.push_back(s);
  }
  return specs;
}

std::string capitalized(std::string word) {
  if (!word.empty()) word[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(word[0])));
  return word;
}

// Names for every style but Numbered (which only needs the joint index).
std::string joint_name(const JointSpec& joint, NamingStyle style) {
  const PartWords words = part_words(joint.part);
  const bool left = joint.side == Side::Left;
  const bool sided = joint.side != Side::None;
  std::string name;
  switch (style) {
    case NamingStyle::Mixamo:  // LeftFrontUpLeg, Spine2, LeftUpLeg3, LeftPectoralFin1
      if (sided) name = left ? "Left" : "Right";
      name += capitalized(joint.qualifier) + words.mixamo;
      if (joint.pair > 0) name += std::to_string(joint.pair);
      if (joint.index > 0) name += (joint.pair > 0 ? "_" : "") + std::to_string(joint.index);
      return name;
    case NamingStyle::Blender:  // front_thigh.L, spine.002, thigh.L.003, antenna.L.001
      if (!joint.qualifier.empty()) name = joint.qualifier + "_";
      name += words.blender;
      if (sided) name += left ? ".L" : ".R";
      if (joint.pair > 0) name += fmt::format(".{:03d}", joint.pair);
      if (joint.index > 0) name += fmt::format(".{:03d}", joint.index);
      return name;
    case NamingStyle::Game:  // front_thigh_l, spine_02, leg_l_03_02, pectoral_fin_r_01
      if (joint.pair > 0 && is_leg_part(joint.part)) {
        return fmt::format("leg_{}_{:02d}_{:02d}", left ? "l" : "r", joint.pair, joint.segment + 1);
      }
      if (!joint.qualifier.empty()) name = joint.qualifier + "_";
      name += words.game;
      if (sided) name += left ? "_l" : "_r";
      if (joint.pair > 0) name += fmt::format("_{:02d}", joint.pair);
      if (joint.index >= 0) name += fmt::format("_{:02d}", joint.index + 1);
      return name;
    case NamingStyle::Biped3ds:  // Bip01 L Front Thigh, Bip01 Spine2, Bip01 L Thigh3
      name = "Bip01";
      if (sided) name += left ? " L" : " R";
      if (!joint.qualifier.empty()) name += " " + capitalized(joint.qualifier);
      name += std::string(" ") + words.biped3ds;
      if (joint.pair > 0) name += std::to_string(joint.pair);
      if (joint.index > 0) name += (joint.pair > 0 ? " " : "") + std::to_string(joint.index);
      return name;
    case NamingStyle::Numbered:
      break;
  }
  throw std::logic_error("joint_name: Numbered names are assigned by index");
}

// ---- geometry helpers (meters, creature frame) ----

// Horizontal unit vector at `yaw_degrees` from +Z towards +X (the left side).
Vec3 horizontal(double yaw_degrees) {
  return Vec3(std::sin(radians(yaw_degrees)), 0.0, std::cos(radians(yaw_degrees)));
}

// `direction` (horizontal) raised by `degrees` (negative: lowered).
Vec3 elevated(const Vec3& direction, double degrees) {
  return direction * std::cos(radians(degrees)) + Vec3::UnitY() * std::sin(radians(degrees));
}

// Straight down, leaning by `degrees` towards the horizontal `out`.
Vec3 down_toward(const Vec3& out, double degrees) {
  return out * std::sin(radians(degrees)) - Vec3::UnitY() * std::cos(radians(degrees));
}

// The points start, start + steps[0], start + steps[0] + steps[1], ...
std::vector<Vec3> walk(const Vec3& start, const std::vector<Vec3>& steps) {
  std::vector<Vec3> points{start};
  for (const Vec3& step : steps) points.push_back(points.back() + step);
  return points;
}

// A chain of `count` equal segments of total `length` from `start`, each turned
// by `curl_degrees` more than the previous about the axis perpendicular to
// `direction` (horizontal) and up: positive curls upwards.
std::vector<Vec3> curled_chain(const Vec3& start, const Vec3& direction, double elevation_degrees,
                               double curl_degrees, int count, double length) {
  std::vector<Vec3> steps;
  for (int k = 0; k < count; ++k) {
    steps.push_back(elevated(direction, elevation_degrees + curl_degrees * k) * (length / count));
  }
  return walk(start, steps);
}

// Turns the points of a neck (from the chest to the head) into neck joint
// positions, each 30% along its segment so that no bone has zero length, and
// returns the head position (the last point).
Vec3 split_neck(std::vector<Vec3>& points) {
  const Vec3 head = points.back();
  points.pop_back();
  for (size_t k = 0; k < points.size(); ++k) {
    const Vec3 next = k + 1 < points.size() ? points[k + 1] : head;
    points[k] += 0.3 * (next - points[k]);
  }
  return head;
}

// Squashes a chain hanging from points[0] vertically so that no point is below `floor`.
void keep_above(std::vector<Vec3>& points, double floor) {
  const double base = points.front().y();
  double lowest = base;
  for (const Vec3& p : points) lowest = std::min(lowest, p.y());
  if (lowest >= floor || base <= floor) return;
  const double squash = (base - floor) / (base - lowest);
  for (Vec3& p : points) p.y() = base + (p.y() - base) * squash;
}

// Droop angle (degrees) of a limb of `length` hanging from `height`: `wanted`,
// or less so that its tip stays above 10% of the height.
double droop_within(double wanted, double height, double length) {
  const double limit = std::asin(std::clamp(0.9 * height / length, 0.0, 1.0)) * 180.0 / kPi;
  return std::min(wanted, limit);
}

// ---- the body under construction ----

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
  std::vector<int> add_chain(int parent, const std::vector<JointSpec>& specs, const std::vector<Vec3>& points) {
    if (points.size() != specs.size() && points.size() != specs.size() + 1) {
      throw std::logic_error("add_chain: need one point per joint, plus one for an end site");
    }
    std::vector<int> chain;
    for (size_t k = 0; k < specs.size(); ++k) {
      parent = add(specs[k], parent, points[k]);
      chain.push_back(parent);
    }
    if (points.size() > specs.size()) end(parent, points.back());
    return chain;
  }

  // Right-side copies of left-side joints (listed parents first) and of their
  // end sites: x negated, so the offsets mirror exactly.
  std::vector<int> mirror(const std::vector<int>& left) {
    std::vector<int> right;
    auto mapped = [&](int joint) {
      const auto it = std::find(left.begin(), left.end(), joint);
      return it == left.end() ? joint : right[static_cast<size_t>(it - left.begin())];
    };
    for (int joint : left) {
      JointSpec copy = joints[joint].spec;
      copy.side = Side::Right;
      Vec3 position = joints[joint].position;
      position.x() = -position.x();
      right.push_back(add(copy, mapped(joints[joint].parent), position));
    }
    const size_t end_count = ends.size();
    for (size_t e = 0; e < end_count; ++e) {
      if (std::find(left.begin(), left.end(), ends[e].parent) == left.end()) continue;
      Vec3 position = ends[e].position;
      position.x() = -position.x();
      end(mapped(ends[e].parent), position);
    }
    return right;
  }

  void limb(LimbKind kind, Side side, int pair, std::vector<int> chain) {
    if (chain.empty()) return;
    Limb l;
    l.kind = kind;
    l.side = side;
    l.pair = pair;
    l.joints = std::move(chain);
    limbs.push_back(std::move(l));
  }

  // A left limb and its mirror.
  void paired_limb(LimbKind kind, int pair, const std::vector<int>& left) {
    const std::vector<int> right = mirror(left);
    limb(kind, Side::Left, pair, left);
    limb(kind, Side::Right, pair, right);
  }
};

// ---- legs ----

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

// A bone's lean (degrees from straight down towards `out`) when the leg splays
// `splay` degrees further out. Bones leaning out stay between straight down and
// (almost) straight up; a bone leaning back (negative: a vertebrate's shin
// going down and back from a knee bent forward) keeps its lean, it never splays.
double bone_lean(const LegBone& bone, double splay) {
  return bone.degrees < 0.0 ? std::max(bone.degrees, -178.0) : std::clamp(bone.degrees + splay, 0.0, 178.0);
}

// How far down the leg reaches when every bone leans `splay` degrees further out.
double leg_drop(const std::vector<LegBone>& bones, double splay = 0.0) {
  double drop = 0.0;
  for (const LegBone& bone : bones) drop += bone.length * std::cos(radians(bone_lean(bone, splay)));
  return drop;
}

// Turns the whole leg about its hip, every bone by the same angle (so each
// joint keeps its bend), until the last joint is `ahead` (bone units, negative:
// behind) in front of the hip along the leg's `out` direction. A crouch bends
// the knees forward and the ankles back; this keeps the foot under the body
// instead of wherever the bends happen to put it.
void turn_leg_to_reach(std::vector<LegBone>& bones, double ahead) {
  double along = 0.0, down = 0.0;
  for (const LegBone& bone : bones) {
    along += bone.length * std::sin(radians(bone.degrees));
    down += bone.length * std::cos(radians(bone.degrees));
  }
  // Turned by t: along cos t + down sin t = reach sin(t + phase).
  const double reach = std::hypot(along, down);
  if (!(reach > 0.0)) return;
  const double phase = std::atan2(along, down);
  const double turn = std::asin(std::clamp(ahead / reach, -1.0, 1.0)) - phase;
  for (LegBone& bone : bones) bone.degrees += turn * 180.0 / kPi;
}

double leg_length(const std::vector<LegBone>& bones) {
  double length = 0.0;
  for (const LegBone& bone : bones) length += bone.length;
  return length;
}

enum class LegFit {
  Scale,  // keep the angles, scale the bones to reach the ground
  Splay,  // keep the lengths, lean the whole leg out or in to reach the ground (arthropods)
};

// Adds a left leg from `hip` whose last joint lands on y = 0; returns its joints.
std::vector<int> add_leg(Body& body, int parent, const Vec3& hip, LegShape shape, LegFit fit) {
  const double target = hip.y();
  double splay = 0.0;
  if (fit == LegFit::Splay && std::abs(leg_drop(shape.bones) - target) > 1e-12 * target) {
    double lo = -60.0, hi = 60.0;  // drop decreases as the leg splays out
    if (leg_drop(shape.bones, lo) >= target && leg_drop(shape.bones, hi) <= target) {
      for (int iteration = 0; iteration < 80; ++iteration) {
        const double mid = 0.5 * (lo + hi);
        (leg_drop(shape.bones, mid) > target ? lo : hi) = mid;
      }
      splay = 0.5 * (lo + hi);
    }
  }
  const double drop = leg_drop(shape.bones, splay);
  if (!(drop > 1e-6 * leg_length(shape.bones))) throw std::logic_error("add_leg: the leg does not reach down");
  const double scale = target / drop;
  std::vector<Vec3> steps;
  for (const LegBone& bone : shape.bones) {
    steps.push_back(down_toward(shape.out, bone_lean(bone, splay)) * (bone.length * scale));
  }
  std::vector<Vec3> points = walk(hip, steps);
  points.back().y() = 0.0;
  points.push_back(points.back() + shape.end_direction * (shape.end_length * scale));
  return body.add_chain(parent, shape.joints, points);
}

// Leg joint specs: the parts, with a side, qualifier and (many-legged plans) pair number.
std::vector<JointSpec> leg_specs(const std::vector<Part>& parts, const std::string& qualifier, int pair_number) {
  std::vector<JointSpec> specs;
  for (size_t k = 0; k < parts.size(); ++k) {
    JointSpec s = spec(parts[k], Side::Left, qualifier);
    s.pair = pair_number;
    s.segment = static_cast<int>(k);
    specs.push_back(s);
  }
  return specs;
}

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

// ---- body plans ----

// Arm, wing and fin directions of the rest poses (left side).
Vec3 spread(const Vec3& out, RestPose pose, double droop_limit = 45.0) {
  return pose == RestPose::TPose ? out : elevated(out, -std::min(45.0, droop_limit));
}

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

// Four-legged bodies: quadrupeds and dragons (which add wings and longer necks and tails).
struct FourLegged {
  QuadrupedSpecies species;
  int spine_min, spine_max;
  bool wings;
};

void build_four_legged(Body& body, SplitMix64& rng, RestPose pose, const FourLegged& plan) {
  const QuadrupedSpecies& sp = plan.species;
  body.species = sp.name;
  const bool crouched = pose == RestPose::Crouched;
  const double leg = rng.uniform(sp.leg_min, sp.leg_max);
  const int spine_count = rng.integer(plan.spine_min, plan.spine_max);
  const int neck_count = rng.integer(sp.neck_min, sp.neck_max);
  const int tail_count = rng.integer(sp.tail_min, sp.tail_max);
  const bool toes = rng.chance(0.75);
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
    hind.joints = leg_specs({Part::UpperLeg, Part::LowerLeg, Part::Foot, Part::Toe}, "hind", 0);
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
    front.joints = leg_specs({Part::Shoulder, Part::UpperLeg, Part::LowerLeg, Part::Foot, Part::Toe}, "front", 0);
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
    std::vector<Vec3> steps;
    for (size_t b = 0; b < lengths.size(); ++b) steps.push_back(directions[b].normalized() * (lengths[b] * wing));
    std::vector<Vec3> points = walk(wing_root, steps);
    keep_above(points, 0.1 * root_height);
    std::vector<JointSpec> specs;
    for (Part part : parts) specs.push_back(spec(part, Side::Left));
    body.paired_limb(LimbKind::Wing, 0, body.add_chain(chest, specs, points));
  }
}

void build_quadruped(Body& body, SplitMix64& rng, RestPose pose) {
  const QuadrupedSpecies& species = kQuadrupeds[rng.integer(0, static_cast<int>(std::size(kQuadrupeds)) - 1)];
  build_four_legged(body, rng, pose, {species, 2, 4, false});
}

void build_dragon(Body& body, SplitMix64& rng, RestPose pose) {
  const int neck_max = rng.integer(8, 12);
  const int tail_max = rng.integer(14, 20);
  const QuadrupedSpecies dragon{"dragon", 0.8, 2.0, 1.4, 0.05,     1.3, 35,  6, neck_max,
                                0.5,      -10, 2.2, 8,   tail_max, -12, 1.2, 20};
  build_four_legged(body, rng, pose, {dragon, 3, 5, true});
}

void build_bird(Body& body, SplitMix64& rng, RestPose pose) {
  body.species = "bird";
  const bool crouched = pose == RestPose::Crouched;
  const double leg = rng.uniform(0.12, 0.9);
  const int spine_count = rng.integer(1, 3);
  const int neck_count = rng.integer(3, 8);
  const int tail_count = rng.integer(1, 3);
  const bool jaw = rng.chance(0.4);
  const bool wing_finger = rng.chance(0.4);
  const double body_length = leg * rng.uniform(0.8, 1.3);
  const double neck = leg * rng.uniform(0.4, 1.3);
  const double head = leg * rng.uniform(0.25, 0.4);
  const double tail = body_length * rng.uniform(0.4, 0.8);
  const double wing = body_length * rng.uniform(1.2, 2.5);
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
  const Vec3 body_direction = elevated(Vec3::UnitZ(), crouched ? 10.0 : 25.0);
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
  std::vector<Vec3> steps;
  for (size_t b = 0; b < lengths.size(); ++b) steps.push_back(directions[b].normalized() * (lengths[b] * wing));
  std::vector<Vec3> wing_points = walk(wing_root, steps);
  keep_above(wing_points, 0.1 * root_height);
  std::vector<JointSpec> wing_specs;
  for (Part part : parts) wing_specs.push_back(spec(part, Side::Left));
  const std::vector<int> wings = body.add_chain(chest, wing_specs, wing_points);

  body.paired_limb(
      LimbKind::Leg, 0,
      add_leg(body, 0, root_position + Vec3(hip_width, -hip_drop, hip_ahead), legs, LegFit::Scale));
  body.paired_limb(LimbKind::Wing, 0, wings);
}

// Fin chain: `count` joints of total `length` along `direction` from `base`.
std::vector<int> add_fin(Body& body, int parent, const Vec3& base, const Vec3& direction, double length, int count,
                         Side side, const std::string& qualifier) {
  std::vector<Vec3> steps(static_cast<size_t>(count), direction.normalized() * (length / count));
  return body.add_chain(parent, chain_specs(Part::Fin, count, side, qualifier), walk(base, steps));
}

void build_fish(Body& body, SplitMix64& rng, RestPose pose) {
  body.species = "fish";
  const double length = rng.uniform(0.25, 1.5);  // snout to tail fin
  const int spine_count = rng.integer(1, 2);
  const int tail_count = rng.integer(3, 8);
  const int caudal_count = rng.integer(1, 2);
  const int pectoral_count = rng.integer(1, 2);
  const int dorsal_count = rng.integer(1, 2);
  const bool jaw = rng.chance(0.5);
  const bool pelvic = rng.chance(0.5);
  const bool anal = rng.chance(0.4);
  const double fin = length * rng.uniform(0.10, 0.14);
  const bool folded = pose == RestPose::Crouched;

  // Built with the root at the origin; the finish lifts the lowest fin tip to y = 0.
  body.add(spec(Part::Hips), -1, Vec3::Zero());
  std::vector<Vec3> spine_points;
  for (int k = 1; k <= spine_count; ++k) spine_points.push_back(Vec3(0.0, 0.0, 0.13 * length * k / spine_count));
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, spine_count), spine_points);
  const int chest = spine.back();
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);
  const Vec3 head_position(0.0, 0.01 * length, 0.22 * length);
  const int head_joint = body.add(spec(Part::Head), chest, head_position);
  body.head_tip = Vec3(0.0, 0.0, 0.45 * length);
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  if (jaw) {
    body.limb(LimbKind::Jaw, Side::None, 0,
              body.add_chain(head_joint, {spec(Part::Jaw)},
                             {Vec3(0.0, -0.03, 0.3) * length, Vec3(0.0, -0.04, 0.43) * length}));
  }
  std::vector<Vec3> tail_points;
  for (int k = 0; k < tail_count; ++k) tail_points.push_back(Vec3(0.0, 0.0, -(0.1 + 0.35 * k / (tail_count - 1)) * length));
  const std::vector<int> tail = body.add_chain(0, chain_specs(Part::Tail, tail_count), tail_points);
  body.limb(LimbKind::Tail, Side::None, 0, tail);

  // Fins, indexed front to back in Limb::pair: pectoral 0, dorsal 1, pelvic 2, anal 3, caudal 4.
  const Vec3 pectoral_direction = folded ? Vec3(0.25, -0.15, -1.0) : spread(Vec3(1.0, 0.0, -0.3).normalized(), pose);
  body.paired_limb(LimbKind::Fin, 0,
                   add_fin(body, chest, body.at(chest) + Vec3(0.05, -0.04, 0.0) * length, pectoral_direction, fin,
                           pectoral_count, Side::Left, "pectoral"));
  body.limb(LimbKind::Fin, Side::None, 1,
            add_fin(body, 0, Vec3(0.0, 0.08, -0.02) * length, folded ? Vec3(0.0, 0.3, -1.0) : Vec3(0.0, 0.8, -0.6),
                    fin, dorsal_count, Side::None, "dorsal"));
  if (pelvic) {
    body.paired_limb(LimbKind::Fin, 2,
                     add_fin(body, 0, Vec3(0.03, -0.07, -0.05) * length,
                             folded ? Vec3(0.15, -0.3, -1.0) : Vec3(0.3, -0.8, -0.5), 0.7 * fin, 1, Side::Left, "pelvic"));
  }
  if (anal) {
    body.limb(LimbKind::Fin, Side::None, 3,
              add_fin(body, tail.front(), body.at(tail.front()) + Vec3(0.0, -0.06, -0.02) * length,
                      folded ? Vec3(0.0, -0.3, -1.0) : Vec3(0.0, -0.7, -0.7), 0.6 * fin, 1, Side::None, "anal"));
  }
  std::vector<Vec3> caudal_steps(static_cast<size_t>(caudal_count), Vec3(0.0, 0.0, -0.06 * length / caudal_count));
  caudal_steps.push_back(Vec3(0.0, 0.0, -0.04 * length));
  std::vector<Vec3> caudal_points = walk(body.at(tail.back()), caudal_steps);
  caudal_points.erase(caudal_points.begin());  // the last tail joint
  body.limb(LimbKind::Fin, Side::None, 4,
            body.add_chain(tail.back(), chain_specs(Part::Fin, caudal_count, Side::None, "caudal"), caudal_points));
  body.tail_tip = caudal_points.back();
}

void build_snake(Body& body, SplitMix64& rng, RestPose pose) {
  body.species = "snake";
  const int total = rng.integer(20, 60);  // joints without the jaw
  const double length = rng.uniform(0.8, 3.5);
  const int neck_count = rng.integer(1, 3);
  const int tail_count = static_cast<int>(std::lround(total * rng.uniform(0.2, 0.3)));
  const int front_count = total - 1 - tail_count - neck_count - 1;
  const bool jaw = rng.chance(0.5);
  const double segment = length / (total + 1.5);

  // Lying on the ground (the root too, so rest_root_height is 0); crouched
  // raises the neck and head like a cobra.
  body.add(spec(Part::Hips), -1, Vec3::Zero());
  const int raised = pose == RestPose::Crouched ? 3 + neck_count + 1 : 0;  // segments ahead of the raise
  std::vector<Vec3> steps;
  const int ahead = front_count + neck_count + 1;
  for (int k = 0; k < ahead; ++k) {
    const int into_raise = k - (ahead - raised);
    const double degrees = into_raise >= 0 ? std::min(50.0, 15.0 * (into_raise + 1)) : 0.0;
    steps.push_back(elevated(Vec3::UnitZ(), degrees) * segment);
  }
  std::vector<Vec3> points = walk(Vec3::Zero(), steps);
  points.erase(points.begin());  // the root
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, front_count),
                                                std::vector<Vec3>(points.begin(), points.begin() + front_count));
  const std::vector<int> necks = body.add_chain(
      spine.back(), chain_specs(Part::Neck, neck_count),
      std::vector<Vec3>(points.begin() + front_count, points.begin() + front_count + neck_count));
  const Vec3 head_position = points.back();
  const Vec3 head_direction = (points.back() - points[points.size() - 2]).normalized();
  const int head_joint = body.add(spec(Part::Head), necks.back(), head_position);
  body.head_tip = head_position + head_direction * (1.5 * segment);
  body.end(head_joint, body.head_tip);
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);
  body.limb(LimbKind::Neck, Side::None, 0, necks);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  if (jaw) {
    const Vec3 jaw_position = head_position + head_direction * (0.3 * segment);
    body.limb(
        LimbKind::Jaw, Side::None, 0,
        body.add_chain(head_joint, {spec(Part::Jaw)}, {jaw_position, jaw_position + head_direction * (0.9 * segment)}));
  }
  std::vector<Vec3> tail_points;
  for (int k = 1; k <= tail_count + 1; ++k)
    tail_points.push_back(Vec3(0.0, 0.0, -segment * (k <= tail_count ? k : k - 0.3)));
  body.tail_tip = tail_points.back();
  body.limb(LimbKind::Tail, Side::None, 0, body.add_chain(0, chain_specs(Part::Tail, tail_count), tail_points));
}

// Straight-leg lean (degrees from down) of arthropod legs in the T- and A-pose.
constexpr std::array<double, 2> kInsectLean{60.0, 40.0};
constexpr std::array<double, 2> kSpiderLean{62.0, 45.0};
constexpr std::array<double, 2> kCentipedeLean{70.0, 50.0};

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
  const Vec3 root_position(0.0, hip_drop + leg_drop(first.bones), 0.0);
  body.add(spec(Part::Thorax), -1, root_position);
  const double floor = 0.1 * root_position.y();

  const Vec3 head_position = root_position + Vec3(0.0, 0.03, 0.18) * length;
  const int head_joint = body.add(spec(Part::Head), 0, head_position);
  body.head_tip = head_position + Vec3(0.0, 0.0, 0.1) * length;
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
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

// ---- the finish ----

int side_rank(Side side) { return side == Side::Left ? 0 : side == Side::Right ? 1 : 2; }

Creature finish(BodyPlan plan, uint64_t seed, const CreatureOptions& options, Body body, double units_per_meter) {
  // Ground: the lowest leg tip, or without legs the lowest point of the body.
  double ground = std::numeric_limits<double>::infinity();
  for (const Limb& limb : body.limbs) {
    if (limb.kind == LimbKind::Leg) ground = std::min(ground, body.at(limb.joints.back()).y());
  }
  if (!std::isfinite(ground)) {
    for (const Body::Joint& joint : body.joints) ground = std::min(ground, joint.position.y());
    for (const Body::EndPoint& end : body.ends) ground = std::min(ground, end.position.y());
  }
  if (ground != 0.0) {
    for (Body::Joint& joint : body.joints) joint.position.y() -= ground;
    for (Body::EndPoint& end : body.ends) end.position.y() -= ground;
    body.head_tip.y() -= ground;
    body.tail_tip.y() -= ground;
  }

  // Depth-first order (children in the order they were added): the order BVH lists joints.
  const int count = static_cast<int>(body.joints.size());
  std::vector<std::vector<int>> children(static_cast<size_t>(count));
  for (int j = 1; j < count; ++j) children[body.joints[j].parent].push_back(j);
  std::vector<int> order;
  std::vector<int> stack{0};
  while (!stack.empty()) {
    const int j = stack.back();
    stack.pop_back();
    order.push_back(j);
    for (auto it = children[j].rbegin(); it != children[j].rend(); ++it) stack.push_back(*it);
  }
  std::vector<int> new_index(static_cast<size_t>(count), -1);
  for (int i = 0; i < count; ++i) new_index[order[i]] = i;

  Creature creature;
  creature.plan = plan;
  creature.seed = seed;
  creature.species = body.species;
  creature.options = options;
  creature.units_per_meter = units_per_meter;
  Skeleton& skeleton = creature.skeleton;
  const ChannelLayout root_layout = ChannelLayout::position_rotations(options.euler_order);
  const ChannelLayout joint_layout = options.position_channels_on_all_joints
                                         ? ChannelLayout::position_rotations(options.euler_order)
                                         : ChannelLayout::rotations(options.euler_order);
  std::unordered_set<std::string> used;
  for (int i = 0; i < count; ++i) {
    const Body::Joint& joint = body.joints[order[i]];
    const bool root = joint.parent < 0;
    const Vec3 offset = root ? joint.position : joint.position - body.at(joint.parent);
    std::string name = options.naming == NamingStyle::Numbered ? "joint" + std::to_string(i)
                                                               : joint_name(joint.spec, options.naming);
    if (!used.insert(name).second) throw std::logic_error("make_creature: duplicate joint name '" + name + "'");
    skeleton.add_joint(std::move(name), root ? -1 : new_index[joint.parent], offset * units_per_meter,
                       root ? root_layout : joint_layout);
  }
  // End sites on leaves only: Blender's importer gives an End Site to the last
  // joint it read, which for a joint with children is one of its descendants.
  std::vector<Body::EndPoint> ends;
  for (const Body::EndPoint& end : body.ends) {
    if (children[end.parent].empty()) ends.push_back(end);
  }
  std::stable_sort(ends.begin(), ends.end(), [&](const Body::EndPoint& a, const Body::EndPoint& b) {
    return new_index[a.parent] < new_index[b.parent];
  });
  for (const Body::EndPoint& end : ends) {
    skeleton.end_sites.push_back({new_index[end.parent], (end.position - body.at(end.parent)) * units_per_meter});
  }
  skeleton.validate();

  // Rest positions as forward kinematics computes them (identity rotations).
  std::vector<Vec3> rest(static_cast<size_t>(count));
  for (int j = 0; j < count; ++j) rest[j] = j == 0 ? skeleton.offsets[0] : rest[skeleton.parents[j]] + skeleton.offsets[j];

  for (Limb limb : body.limbs) {
    for (int& j : limb.joints) j = new_index[j];
    if (limb.kind == LimbKind::Leg) limb.rest_foot = rest[limb.joints.back()];
    creature.limbs.push_back(std::move(limb));
  }
  std::stable_sort(creature.limbs.begin(), creature.limbs.end(), [](const Limb& a, const Limb& b) {
    if (a.kind != b.kind) return a.kind < b.kind;
    if (a.pair != b.pair) return a.pair < b.pair;
    return side_rank(a.side) < side_rank(b.side);
  });
  for (int j : body.spine) creature.spine.push_back(new_index[j]);
  creature.rest_root_height = skeleton.offsets[0].y();
  creature.body_length = (body.head_tip - body.tail_tip).norm() * units_per_meter;
  if (const std::vector<const Limb*> legs = creature.limbs_of(LimbKind::Leg); !legs.empty()) {
    const std::vector<int>& chain = legs.front()->joints;
    for (size_t k = 1; k < chain.size(); ++k) creature.leg_length += (rest[chain[k]] - rest[chain[k - 1]]).norm();
  }
  return creature;
}

}  // namespace

std::string_view body_plan_name(BodyPlan plan) {
  switch (plan) {
    case BodyPlan::Biped: return "biped";
    case BodyPlan::Quadruped: return "quadruped";
    case BodyPlan::Hexapod: return "hexapod";
    case BodyPlan::Spider: return "spider";
    case BodyPlan::Snake: return "snake";
    case BodyPlan::Bird: return "bird";
    case BodyPlan::Fish: return "fish";
    case BodyPlan::Dragon: return "dragon";
    case BodyPlan::Centipede: return "centipede";
  }
  return "unknown";
}

bool parse_body_plan(std::string_view name, BodyPlan& plan) {
  for (BodyPlan candidate : kAllBodyPlans) {
    if (body_plan_name(candidate) == name) {
      plan = candidate;
      return true;
    }
  }
  return false;
}

std::string_view limb_kind_name(LimbKind kind) {
  switch (kind) {
    case LimbKind::Leg: return "leg";
    case LimbKind::Arm: return "arm";
    case LimbKind::Wing: return "wing";
    case LimbKind::Fin: return "fin";
    case LimbKind::Tail: return "tail";
    case LimbKind::Neck: return "neck";
    case LimbKind::Head: return "head";
    case LimbKind::Spine: return "spine";
    case LimbKind::Antenna: return "antenna";
    case LimbKind::Jaw: return "jaw";
  }
  return "unknown";
}

std::vector<const Limb*> Creature::limbs_of(LimbKind kind) const {
  std::vector<const Limb*> out;
  for (const Limb& limb : limbs) {
    if (limb.kind == kind) out.push_back(&limb);
  }
  return out;
}

CreatureOptions sample_creature_options(BodyPlan plan, uint64_t seed) {
  SplitMix64 rng = stream(plan, seed, Stream::Options);
  CreatureOptions options;
  const double naming = rng.uniform();
  options.naming = naming < 0.25   ? NamingStyle::Mixamo
                   : naming < 0.45 ? NamingStyle::Blender
                   : naming < 0.70 ? NamingStyle::Game
                   : naming < 0.85 ? NamingStyle::Biped3ds
                                   : NamingStyle::Numbered;
  const double pose = rng.uniform();
  options.rest_pose = pose < 0.4 ? RestPose::TPose : pose < 0.7 ? RestPose::APose : RestPose::Crouched;
  options.euler_order = static_cast<EulerOrder>(rng.integer(0, 5));
  options.position_channels_on_all_joints = rng.chance(0.15);
  return options;
}

Creature make_creature(BodyPlan plan, uint64_t seed) {
  return make_creature(plan, seed, sample_creature_options(plan, seed));
}

Creature make_creature(BodyPlan plan, uint64_t seed, const CreatureOptions& options) {
  SplitMix64 rng = stream(plan, seed, Stream::Body);
  Body body;
  switch (plan) {
    case BodyPlan::Biped: build_biped(body, rng, options.rest_pose); break;
    case BodyPlan::Quadruped: build_quadruped(body, rng, options.rest_pose); break;
    case BodyPlan::Hexapod: build_hexapod(body, rng, options.rest_pose); break;
    case BodyPlan::Spider: build_spider(body, rng, options.rest_pose); break;
    case BodyPlan::Snake: build_snake(body, rng, options.rest_pose); break;
    case BodyPlan::Bird: build_bird(body, rng, options.rest_pose); break;
    case BodyPlan::Fish: build_fish(body, rng, options.rest_pose); break;
    case BodyPlan::Dragon: build_dragon(body, rng, options.rest_pose); break;
    case BodyPlan::Centipede: build_centipede(body, rng, options.rest_pose); break;
  }
  SplitMix64 units = stream(plan, seed, Stream::Units);
  return finish(plan, seed, options, std::move(body), units.chance(0.4) ? 100.0 : 1.0);
}

}  // namespace nec::zoo
