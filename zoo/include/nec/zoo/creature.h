// Procedural creatures: skeletons of many body plans, with the semantic
// structure (limbs, spine, tail) that motion synthesis and captions need.
//
//   Creature spider = make_creature(BodyPlan::Spider, /*seed=*/7);
//   write_bvh("spider.bvh", spider.skeleton, Motion::rest(spider.skeleton, 1, 30));
//   for (const Limb& leg : spider.limbs_of(LimbKind::Leg)) ...;
//
// Conventions of every creature (whatever its rest pose, names or channels):
// with identity rotations the creature faces +Z, +Y is up and its left side
// is at +X; the root (pelvis-like joint, joint 0) sits at rest_root_height
// above the ground plane y = 0, where its lowest feet touch. Same (plan, seed)
// -> the same creature, bit for bit.
//
// More precisely, as built by make_creature:
// - The root's OFFSET is (0, rest_root_height, 0) and it has 6 channels.
// - Every leg's last joint (the tip) is on y = 0 in the rest pose, and left
//   and right limbs mirror exactly (offsets with x negated). Without legs
//   (snake, fish) the lowest joint or end site is on y = 0: a snake lies on
//   the ground (rest_root_height 0), a fish rests on its lowest fin.
// - Joints are in depth-first (BVH file) order; end sites sit on leaf joints
//   only (Blender gives an End Site to the last joint it read).
// - Joints outside paired limbs lie on the midline (x = 0); nothing is below y = 0.
#pragma once

#include "nec/motion/motion.h"
#include "nec/motion/names.h"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace nec::zoo {

enum class BodyPlan {
  Biped, Quadruped, Hexapod, Spider, Snake, Bird, Fish, Dragon, Centipede,
  Crab,        // eight walking legs and two claws on a wide shell; walks sideways
  Ungulate,    // deer, goat, camel, giraffe: long legs on hooves, a long neck
  Elephant,    // pillar legs, a heavy body, a trunk
  GroundBird,  // flamingo, heron, chicken, ostrich: long legs and toes, a pecking neck, wings folded
  Hopper,      // kangaroo, wallaby: long hind feet, small arms, a heavy tail; hops with both feet
  Dinosaur,    // a two-legged dinosaur: body level over the hips, balanced by a long tail
  Primate,     // chimpanzee, gorilla: knuckle-walks on its long arms (the front legs), no tail
};
constexpr BodyPlan kAllBodyPlans[] = {BodyPlan::Biped,    BodyPlan::Quadruped,  BodyPlan::Hexapod,
                                      BodyPlan::Spider,   BodyPlan::Snake,      BodyPlan::Bird,
                                      BodyPlan::Fish,     BodyPlan::Dragon,     BodyPlan::Centipede,
                                      BodyPlan::Crab,     BodyPlan::Ungulate,   BodyPlan::Elephant,
                                      BodyPlan::GroundBird, BodyPlan::Hopper,   BodyPlan::Dinosaur,
                                      BodyPlan::Primate};

std::string_view body_plan_name(BodyPlan plan);  // "biped", "quadruped", ..., "ground_bird", "dinosaur"
// Parses a name as printed by body_plan_name; false when unknown.
bool parse_body_plan(std::string_view name, BodyPlan& plan);
// The plan whose motion rules a plan's creatures move by (gait timing, knee directions, how the
// body is carried): a crab moves as a spider does, an ungulate, an elephant or a primate as a quadruped,
// a ground bird, a hopper or a two-legged dinosaur as a bird (a hopper with both feet together).
// The first nine plans move by their own.
BodyPlan moves_like(BodyPlan plan);

// How joints are named (all styles must map to sensible canonical names via
// nec::canonical_joint_name, except Numbered, which carries no meaning on purpose).
enum class NamingStyle {
  Mixamo,    // "LeftUpLeg", "Spine2", "LeftLeg3"
  Blender,   // "thigh.L", "spine.002", "leg.L.003"
  Game,      // "leg_l_01", "spine_02", "tail_05"
  Biped3ds,  // "Bip01 L Thigh", "Bip01 Spine1", "Bip01 Tail3"
  Numbered,  // "joint12"
  Maya,      // "L_thigh_JNT", "C_spine_02_JNT", "R_leg_03_02_JNT"
  Truebones, // "BN_Thigh_L", "BN_Spine02", "BN_Tail05" (as the Truebones zoo's rigs)
};

enum class RestPose {
  TPose,     // limbs straight out: arms/wings horizontal, legs straight down
  APose,     // arms/wings 45 degrees down, legs straight down
  Crouched,  // legs bent at every joint, body lowered
};

enum class LimbKind { Leg, Arm, Wing, Fin, Tail, Neck, Head, Spine, Antenna, Jaw, Trunk };

std::string_view limb_kind_name(LimbKind kind);  // "leg", "arm", ...

// A chain of joints, proximal to distal. joints.front()'s parent is on the
// body (spine or root); joints.back() is the tip (foot, hand, wing tip, tail end).
// Kinds by plan: the chain behind the root is the Tail (an insect's, spider's
// or centipede's abdomen too); the chain from the root forward is the Spine
// (root excluded); spider palps are Antennae, mandibles and fangs are Jaws
// (paired); a quadruped's front Leg starts at the scapula ("LeftShoulder"); a
// crab's claws are Arms; an elephant's trunk is a Trunk hanging from the head.
struct Limb {
  LimbKind kind = LimbKind::Leg;
  Side side = Side::None;   // Left/Right for paired limbs, None on the midline
  int pair = 0;             // legs/wings: pair index from the front, 0 = frontmost; fins: position
                            // from the front (pectoral 0, dorsal 1, pelvic 2, anal 3, caudal 4)
  std::vector<int> joints;  // skeleton indices, proximal -> distal
  // Tip position on the ground (y = 0) in the rest pose, in the creature's frame
  // (origin on the ground below the root), i.e. the FK position of
  // joints.back() for Motion::rest; for legs only, zero for other limbs.
  Vec3 rest_foot = Vec3::Zero();
};

struct CreatureOptions {
  NamingStyle naming = NamingStyle::Mixamo;
  RestPose rest_pose = RestPose::TPose;
  EulerOrder euler_order = EulerOrder::ZXY;
  bool position_channels_on_all_joints = false;  // as Bandai files: 6 channels everywhere
};

struct Creature {
  BodyPlan plan = BodyPlan::Biped;
  uint64_t seed = 0;
  std::string species;         // noun for captions, e.g. "person", "dog", "spider", "dragon"
  CreatureOptions options;     // what the seed chose
  Skeleton skeleton;           // BVH-ready: names in options.naming, channels, end sites
  std::vector<Limb> limbs;     // every chain, legs first (front to back, left before right)
  std::vector<int> spine;      // root -> chest/neck base along the body, starting with 0
  double rest_root_height = 1.0;  // root above the ground in the rest pose, file units
  double body_length = 1.0;       // head tip to tail tip (or to the hips), file units
  double leg_length = 0.0;        // hip to foot of the first leg pair, 0 without legs
  double units_per_meter = 1.0;   // file units per meter: 1 (meters) or 100 (centimeters)

  std::vector<const Limb*> limbs_of(LimbKind kind) const;
};

// Samples proportions, segment counts, joint count (about 7 to 140), naming
// style, rest pose, Euler order and channel layout from the seed.
Creature make_creature(BodyPlan plan, uint64_t seed);
// Same, with the style choices fixed by the caller. The body (proportions,
// segment counts, species, units) depends on (plan, seed) only, so one seed
// with other options is the same animal renamed, re-posed or re-channelled.
Creature make_creature(BodyPlan plan, uint64_t seed, const CreatureOptions& options);
// The options make_creature(plan, seed) uses.
CreatureOptions sample_creature_options(BodyPlan plan, uint64_t seed);

}  // namespace nec::zoo
