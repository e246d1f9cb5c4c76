// Procedural creatures (creature.h): the random streams of a (plan, seed), the
// finish that turns a built body into a BVH-ready skeleton with its limbs, and
// the public entry points. The body plans are in body_plan_*.cpp.
#include "nec/zoo/creature.h"

#include "body_plans.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>

namespace nec::zoo::detail {
namespace {

// ---- deterministic random numbers (motion/random.h: the same creature for a seed everywhere) ----

// Independent random streams of one (plan, seed): the body, the style options, the units.
enum class Stream : uint64_t { Body = 1, Options = 2, Units = 3 };

SplitMix64 stream(BodyPlan plan, uint64_t seed, Stream which) {
  SplitMix64 mixer(seed ^ (0xD1B54A32D192ED03ull * (static_cast<uint64_t>(plan) + 1)) ^
               (0x8CB92BA72F3D8DD7ull * static_cast<uint64_t>(which)));
  return SplitMix64(mixer.next());
}

// ---- the finish ----
//
// One builder per body plan places joints at their rest positions, in meters,
// in the creature's frame (faces +Z, +Y up, left at +X); the finish turns
// that into a BVH-ready skeleton: ground at y = 0, file units, depth-first
// joint order, names in the chosen style, channels, end sites, and the limb
// metadata.

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
}  // namespace nec::zoo::detail

namespace nec::zoo {

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
    case BodyPlan::Crab: return "crab";
    case BodyPlan::Ungulate: return "ungulate";
    case BodyPlan::Elephant: return "elephant";
    case BodyPlan::GroundBird: return "ground_bird";
    case BodyPlan::Hopper: return "hopper";
    case BodyPlan::Dinosaur: return "dinosaur";
    case BodyPlan::Primate: return "primate";
  }
  return "unknown";
}

BodyPlan moves_like(BodyPlan plan) {
  switch (plan) {
    case BodyPlan::Crab: return BodyPlan::Spider;
    case BodyPlan::Ungulate:
    case BodyPlan::Elephant:
    case BodyPlan::Primate: return BodyPlan::Quadruped;
    case BodyPlan::GroundBird:
    case BodyPlan::Hopper:
    case BodyPlan::Dinosaur: return BodyPlan::Bird;
    default: return plan;
  }
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
    case LimbKind::Trunk: return "trunk";
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
  SplitMix64 rng = detail::stream(plan, seed, detail::Stream::Options);
  CreatureOptions options;
  const double naming = rng.uniform();
  options.naming = naming < 0.22   ? NamingStyle::Mixamo
                   : naming < 0.37 ? NamingStyle::Blender
                   : naming < 0.55 ? NamingStyle::Game
                   : naming < 0.67 ? NamingStyle::Biped3ds
                   : naming < 0.77 ? NamingStyle::Maya
                   : naming < 0.88 ? NamingStyle::Truebones
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
  SplitMix64 rng = detail::stream(plan, seed, detail::Stream::Body);
  detail::Body body;
  switch (plan) {
    case BodyPlan::Biped: detail::build_biped(body, rng, options.rest_pose); break;
    case BodyPlan::Quadruped: detail::build_quadruped(body, rng, options.rest_pose); break;
    case BodyPlan::Hexapod: detail::build_hexapod(body, rng, options.rest_pose); break;
    case BodyPlan::Spider: detail::build_spider(body, rng, options.rest_pose); break;
    case BodyPlan::Snake: detail::build_snake(body, rng, options.rest_pose); break;
    case BodyPlan::Bird: detail::build_bird(body, rng, options.rest_pose); break;
    case BodyPlan::Fish: detail::build_fish(body, rng, options.rest_pose); break;
    case BodyPlan::Dragon: detail::build_dragon(body, rng, options.rest_pose); break;
    case BodyPlan::Centipede: detail::build_centipede(body, rng, options.rest_pose); break;
    case BodyPlan::Crab: detail::build_crab(body, rng, options.rest_pose); break;
    case BodyPlan::Ungulate: detail::build_ungulate(body, rng, options.rest_pose); break;
    case BodyPlan::Elephant: detail::build_elephant(body, rng, options.rest_pose); break;
    case BodyPlan::GroundBird: detail::build_ground_bird(body, rng, options.rest_pose); break;
    case BodyPlan::Hopper: detail::build_hopper(body, rng, options.rest_pose); break;
    case BodyPlan::Dinosaur: detail::build_dinosaur(body, rng, options.rest_pose); break;
    case BodyPlan::Primate: detail::build_primate(body, rng, options.rest_pose); break;
  }
  SplitMix64 units = detail::stream(plan, seed, detail::Stream::Units);
  return detail::finish(plan, seed, options, std::move(body), units.chance(0.4) ? 100.0 : 1.0);
}

}  // namespace nec::zoo
