// Procedural creatures: determinism, joint counts, BVH round trip, preprocessing,
// ground contact, mirror symmetry, canonical names, limb metadata, facing.
#include "nec/motion/bvh.h"
#include "nec/motion/kinematics.h"
#include "nec/motion/names.h"
#include "nec/corpus/preprocess.h"
#include "nec/zoo/creature.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

namespace nec::zoo {
namespace {

constexpr int kSeeds = 50;

std::string plan_name(BodyPlan plan) { return std::string(body_plan_name(plan)); }

constexpr NamingStyle kAllStyles[] = {NamingStyle::Mixamo,   NamingStyle::Blender, NamingStyle::Game,
                                      NamingStyle::Biped3ds, NamingStyle::Maya,    NamingStyle::Truebones,
                                      NamingStyle::Numbered};
constexpr RestPose kAllPoses[] = {RestPose::TPose, RestPose::APose, RestPose::Crouched};

// Rest positions by forward kinematics: joints (J) and end sites (E).
struct RestPositions {
  std::vector<Vec3> joints;
  std::vector<Vec3> end_sites;
};

RestPositions rest_positions(const Skeleton& skeleton) {
  const Pose pose = forward_kinematics(skeleton, Motion::rest(skeleton, 1, 30.0));
  RestPositions out;
  for (int j = 0; j < skeleton.joint_count(); ++j) out.joints.push_back(pose.position(0, j));
  out.end_sites = end_site_positions(skeleton, pose);
  return out;
}

// Every option combination once, for one seed.
std::vector<CreatureOptions> all_option_combinations() {
  std::vector<CreatureOptions> out;
  int k = 0;
  for (NamingStyle naming : kAllStyles) {
    for (RestPose pose : kAllPoses) {
      for (bool positions : {false, true}) {
        CreatureOptions options;
        options.naming = naming;
        options.rest_pose = pose;
        options.euler_order = static_cast<EulerOrder>(k++ % 6);
        options.position_channels_on_all_joints = positions;
        out.push_back(options);
      }
    }
  }
  return out;
}

TEST(ZooCreature, PlanAndLimbNames) {
  std::set<std::string> names;
  for (BodyPlan plan : kAllBodyPlans) {
    BodyPlan parsed = BodyPlan::Biped;
    ASSERT_TRUE(parse_body_plan(body_plan_name(plan), parsed)) << plan_name(plan);
    EXPECT_EQ(parsed, plan);
    names.insert(plan_name(plan));
  }
  EXPECT_EQ(names.size(), std::size(kAllBodyPlans));
  BodyPlan unused = BodyPlan::Biped;
  EXPECT_FALSE(parse_body_plan("unicorn", unused));
  EXPECT_EQ(limb_kind_name(LimbKind::Leg), "leg");
  EXPECT_EQ(limb_kind_name(LimbKind::Wing), "wing");
  EXPECT_EQ(limb_kind_name(LimbKind::Antenna), "antenna");
}

TEST(ZooCreature, SameSeedSameBvhOtherSeedOtherBvh) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed : {0ull, 7ull, 123456789ull}) {
      const Creature a = make_creature(plan, seed);
      const Creature b = make_creature(plan, seed);
      EXPECT_EQ(format_bvh(a.skeleton, Motion::rest(a.skeleton, 2, 30.0)),
                format_bvh(b.skeleton, Motion::rest(b.skeleton, 2, 30.0)))
          << plan_name(plan) << " seed " << seed;
      EXPECT_EQ(a.species, b.species);
      EXPECT_EQ(a.rest_root_height, b.rest_root_height);
      ASSERT_EQ(a.limbs.size(), b.limbs.size());
      for (size_t l = 0; l < a.limbs.size(); ++l) EXPECT_EQ(a.limbs[l].joints, b.limbs[l].joints);
    }
    const Creature one = make_creature(plan, 1);
    const Creature two = make_creature(plan, 2);
    EXPECT_NE(format_bvh(one.skeleton, Motion::rest(one.skeleton, 2, 30.0)),
              format_bvh(two.skeleton, Motion::rest(two.skeleton, 2, 30.0)))
        << plan_name(plan);
  }
}

TEST(ZooCreature, SeedOnlyOverloadUsesSampledOptions) {
  for (BodyPlan plan : kAllBodyPlans) {
    std::set<int> namings, poses, orders;
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      const CreatureOptions options = sample_creature_options(plan, seed);
      const Creature sampled = make_creature(plan, seed);
      const Creature given = make_creature(plan, seed, options);
      EXPECT_EQ(sampled.skeleton.names, given.skeleton.names);
      EXPECT_EQ(sampled.options.naming, options.naming);
      EXPECT_EQ(sampled.options.rest_pose, options.rest_pose);
      EXPECT_EQ(sampled.options.euler_order, options.euler_order);
      EXPECT_EQ(sampled.options.position_channels_on_all_joints, options.position_channels_on_all_joints);
      namings.insert(static_cast<int>(options.naming));
      poses.insert(static_cast<int>(options.rest_pose));
      orders.insert(static_cast<int>(options.euler_order));
    }
    // 50 seeds see (almost surely) several of every choice.
    EXPECT_GE(namings.size(), 4u) << plan_name(plan);
    EXPECT_EQ(poses.size(), 3u) << plan_name(plan);
    EXPECT_GE(orders.size(), 5u) << plan_name(plan);
  }
}

TEST(ZooCreature, BodyDependsOnSeedOnly) {
  // The same seed with other options is the same animal: species, joint count, tree and units.
  for (BodyPlan plan : kAllBodyPlans) {
    const Creature reference = make_creature(plan, 11);
    for (const CreatureOptions& options : all_option_combinations()) {
      const Creature c = make_creature(plan, 11, options);
      EXPECT_EQ(c.species, reference.species) << plan_name(plan);
      EXPECT_EQ(c.skeleton.parents, reference.skeleton.parents) << plan_name(plan);
      EXPECT_EQ(c.units_per_meter, reference.units_per_meter) << plan_name(plan);
      EXPECT_EQ(c.limbs.size(), reference.limbs.size()) << plan_name(plan);
    }
  }
}

TEST(ZooCreature, JointCountsAndValidSkeletons) {
  for (BodyPlan plan : kAllBodyPlans) {
    int fewest = 1 << 30, most = 0;
    std::set<int> counts;
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      const Creature c = make_creature(plan, seed);
      const int joints = c.skeleton.joint_count();
      EXPECT_GE(joints, 7) << plan_name(plan) << " seed " << seed;
      EXPECT_LE(joints, 140) << plan_name(plan) << " seed " << seed;
      EXPECT_NO_THROW(c.skeleton.validate()) << plan_name(plan) << " seed " << seed;
      EXPECT_EQ(c.plan, plan);
      EXPECT_EQ(c.seed, seed);
      fewest = std::min(fewest, joints);
      most = std::max(most, joints);
      counts.insert(joints);
    }
    // Segment counts are sampled: the joint count varies with the seed.
    EXPECT_GE(counts.size(), 3u) << plan_name(plan) << ": " << fewest << ".." << most;
  }
}

TEST(ZooCreature, ChannelLayoutFollowsOptions) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (const CreatureOptions& options : all_option_combinations()) {
      const Creature c = make_creature(plan, 5, options);
      const Skeleton& s = c.skeleton;
      EXPECT_EQ(s.channels[0], ChannelLayout::position_rotations(options.euler_order));
      const ChannelLayout expected = options.position_channels_on_all_joints
                                         ? ChannelLayout::position_rotations(options.euler_order)
                                         : ChannelLayout::rotations(options.euler_order);
      for (int j = 1; j < s.joint_count(); ++j) ASSERT_EQ(s.channels[j], expected) << plan_name(plan) << " " << s.names[j];
      if (options.naming == NamingStyle::Numbered) {
        for (int j = 0; j < s.joint_count(); ++j) EXPECT_EQ(s.names[j], "joint" + std::to_string(j));
      }
    }
  }
}

TEST(ZooCreature, BvhRoundTripKeepsTheSkeleton) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed = 0; seed < 6; ++seed) {
      const Creature c = make_creature(plan, seed);
      const Motion rest = Motion::rest(c.skeleton, 3, 30.0);
      const Clip back = parse_bvh(format_bvh(c.skeleton, rest), plan_name(plan));
      ASSERT_EQ(back.skeleton.joint_count(), c.skeleton.joint_count()) << plan_name(plan);
      EXPECT_EQ(back.skeleton.names, c.skeleton.names);
      EXPECT_EQ(back.skeleton.parents, c.skeleton.parents);  // built in BVH (depth-first) order
      ASSERT_EQ(back.skeleton.end_sites.size(), c.skeleton.end_sites.size());
      double worst = 0.0;
      const double scale = c.skeleton.diameter();
      for (int j = 0; j < c.skeleton.joint_count(); ++j) {
        worst = std::max(worst, (back.skeleton.offsets[j] - c.skeleton.offsets[j]).norm() / scale);
        EXPECT_EQ(back.skeleton.channels[j], c.skeleton.channels[j]);
      }
      EXPECT_LT(worst, 1e-7) << plan_name(plan) << ": largest relative offset difference " << worst;
    }
  }
}

TEST(ZooCreature, PreprocessingAcceptsRestMotionFacingForward) {
  for (BodyPlan plan : kAllBodyPlans) {
    std::vector<Creature> creatures;
    for (uint64_t seed = 0; seed < 12; ++seed) creatures.push_back(make_creature(plan, seed));
    for (const CreatureOptions& options : all_option_combinations()) creatures.push_back(make_creature(plan, 3, options));
    for (const Creature& c : creatures) {
      Motion rest = Motion::rest(c.skeleton, 60, 30.0);
      for (int t = 0; t < rest.frame_count; ++t) rest.translation(t, 0) = c.skeleton.offsets[0];
      const PreparedClip prepared = preprocess({c.skeleton, rest, {}}, plan_name(plan));
      ASSERT_TRUE(prepared.report.accepted()) << plan_name(plan) << " seed " << c.seed << ": " << prepared.report.rejection;
      EXPECT_EQ(prepared.clip.skeleton.joint_count(), c.skeleton.joint_count()) << "root merged away";
      // Already +Y up and facing +Z: preprocessing turns nothing (it finds the
      // heading from left/right joints, or from the head when names carry no side).
      const bool has_heading_cue = c.options.naming != NamingStyle::Numbered;
      if (has_heading_cue) {
        const double turned = geodesic_distance(prepared.normalization.rotation, Quat::Identity());
        EXPECT_LT(turned, 1e-9) << plan_name(plan) << " seed " << c.seed << " turned by " << turned << " rad";
      }
    }
  }
}

TEST(ZooCreature, RestPoseStandsOnTheGround) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      const Creature c = make_creature(plan, seed);
      const RestPositions rest = rest_positions(c.skeleton);
      const double size = c.skeleton.diameter();
      const double tolerance = 1e-9 * size;
      EXPECT_LT((rest.joints[0] - Vec3(0.0, c.rest_root_height, 0.0)).norm(), tolerance) << plan_name(plan);
      EXPECT_GE(c.rest_root_height, 0.0);
      double lowest_foot = std::numeric_limits<double>::infinity();
      for (const Limb* leg : c.limbs_of(LimbKind::Leg)) {
        const double y = rest.joints[leg->joints.back()].y();
        EXPECT_NEAR(y, 0.0, tolerance) << plan_name(plan) << " seed " << seed << ": every foot on the ground";
        lowest_foot = std::min(lowest_foot, y);
      }
      double lowest = std::numeric_limits<double>::infinity();
      for (const Vec3& p : rest.joints) lowest = std::min(lowest, p.y());
      for (const Vec3& p : rest.end_sites) lowest = std::min(lowest, p.y());
      EXPECT_GT(lowest, -tolerance) << plan_name(plan) << " seed " << seed << ": nothing below the ground";
      if (std::isfinite(lowest_foot)) {
        EXPECT_NEAR(lowest_foot, 0.0, tolerance);
        EXPECT_GT(c.rest_root_height, 0.0);
        EXPECT_GT(c.leg_length, 0.0);
      } else {
        EXPECT_NEAR(lowest, 0.0, tolerance) << plan_name(plan) << ": the body rests on the ground";
        EXPECT_EQ(c.leg_length, 0.0);
      }
      EXPECT_GT(c.body_length, 0.0);
    }
  }
}

TEST(ZooCreature, CrouchingLowersTheBody) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed = 0; seed < 10; ++seed) {
      CreatureOptions options = sample_creature_options(plan, seed);
      options.rest_pose = RestPose::TPose;
      const Creature standing = make_creature(plan, seed, options);
      options.rest_pose = RestPose::Crouched;
      const Creature crouched = make_creature(plan, seed, options);
      if (standing.limbs_of(LimbKind::Leg).empty()) continue;
      EXPECT_LT(crouched.rest_root_height / crouched.leg_length, standing.rest_root_height / standing.leg_length)
          << plan_name(plan) << " seed " << seed;
      // Bent legs: some leg joint sits off the straight line from hip to foot.
      const RestPositions rest = rest_positions(crouched.skeleton);
      const Limb& leg = *crouched.limbs_of(LimbKind::Leg).front();
      const Vec3 hip = rest.joints[leg.joints.front()];
      const Vec3 axis = (rest.joints[leg.joints.back()] - hip).normalized();
      double bend = 0.0;
      for (int j : leg.joints) {
        const Vec3 d = rest.joints[j] - hip;
        bend = std::max(bend, (d - axis * d.dot(axis)).norm());
      }
      EXPECT_GT(bend, 0.05 * crouched.leg_length) << plan_name(plan) << " seed " << seed;
    }
  }
}

// The feet stand under the body in every rest pose: the root's ground
// projection is inside the support polygon, a crouch bends the knees forward
// without pushing the feet ahead of the body (a creature leaning back).
TEST(ZooCreature, FeetStandUnderTheBody) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (RestPose pose : kAllPoses) {
      for (uint64_t seed = 0; seed < 20; ++seed) {
        CreatureOptions options = sample_creature_options(plan, seed);
        options.rest_pose = pose;
        const Creature c = make_creature(plan, seed, options);
        const std::vector<const Limb*> legs = c.limbs_of(LimbKind::Leg);
        if (legs.empty()) continue;
        const RestPositions rest = rest_positions(c.skeleton);
        const double size = c.skeleton.diameter();
        const Vec3 root = rest.joints[0];
        Vec3 centroid = Vec3::Zero();
        for (const Limb* leg : legs) centroid += rest.joints[leg->joints.back()];
        centroid /= static_cast<double>(legs.size());
        const double ahead = (centroid.z() - root.z()) / size;  // feet ahead of the root, diameters
        const double front = (rest.joints[legs.front()->joints.back()].z() - root.z()) / size;
        const double hind = (rest.joints[legs.back()->joints.back()].z() - root.z()) / size;
        const bool crouched = pose == RestPose::Crouched;
        const std::string where = plan_name(plan) + " pose " + std::to_string(static_cast<int>(pose)) + " seed " +
                                  std::to_string(seed) + ": feet " + std::to_string(ahead) + " diameters ahead";
        EXPECT_NEAR(centroid.x(), root.x(), 1e-9 * size) << where;
        switch (moves_like(plan)) {  // an ungulate stands as a quadruped, a crab as a spider, ...
          case BodyPlan::Biped:
            // Straight legs put the ankle under the hip and the tip (the ball
            // of a flat foot) a foot length ahead; a crouch stands on it.
            EXPECT_LE(std::abs(ahead), crouched ? 0.05 : 0.12) << where;
            break;
          case BodyPlan::Bird:
            EXPECT_LE(std::abs(ahead), 0.05) << where;
            break;
          case BodyPlan::Quadruped:
          case BodyPlan::Dragon:
            // The root is the hips: the hind feet under (a crouch: behind)
            // them, the front feet well ahead, under the chest.
            EXPECT_LE(hind, crouched ? 0.0 : 0.12) << where;
            EXPECT_GT(front, 0.1) << where;
            EXPECT_GT(ahead, 0.05) << where;
            EXPECT_LT(ahead, 0.35) << where;
            if (crouched) {  // each foot under its hip or shoulder
              for (const Limb* leg : legs) {
                const double off = rest.joints[leg->joints.back()].z() - rest.joints[leg->joints.front()].z();
                EXPECT_LE(std::abs(off), 0.02 * size) << where;
              }
            }
            break;
          default:  // arthropods: the root in the middle of the legs
            EXPECT_LE(std::abs(ahead), 0.1) << where;
            EXPECT_GT(front, 0.05) << where;
            EXPECT_LT(hind, -0.05) << where;
            break;
        }
      }
    }
  }
}

TEST(ZooCreature, ArmsAndWingsFollowTheRestPose) {
  for (BodyPlan plan : {BodyPlan::Biped, BodyPlan::Bird, BodyPlan::Dragon}) {
    for (uint64_t seed = 0; seed < 10; ++seed) {
      CreatureOptions options = sample_creature_options(plan, seed);
      for (RestPose pose : {RestPose::TPose, RestPose::APose}) {
        options.rest_pose = pose;
        const Creature c = make_creature(plan, seed, options);
        const RestPositions rest = rest_positions(c.skeleton);
        for (LimbKind kind : {LimbKind::Arm, LimbKind::Wing}) {
          for (const Limb* limb : c.limbs_of(kind)) {
            const Vec3 base = rest.joints[limb->joints[limb->joints.size() - 2]];
            const Vec3 tip = rest.joints[limb->joints.back()];
            const Vec3 along = (tip - base).normalized();
            if (pose == RestPose::TPose) {
              EXPECT_NEAR(along.y(), 0.0, 1e-9) << plan_name(plan) << ": horizontal in the T-pose";
            } else {
              EXPECT_LT(along.y(), -0.2) << plan_name(plan) << ": drooping in the A-pose";
            }
            EXPECT_GT(std::abs(along.x()), 0.5) << plan_name(plan) << ": spread sideways";
          }
        }
      }
    }
  }
}

// Right limb of the same kind and pair as `left`.
const Limb* counterpart(const Creature& c, const Limb& left) {
  for (const Limb& limb : c.limbs) {
    if (limb.kind == left.kind && limb.pair == left.pair && limb.side == Side::Right) return &limb;
  }
  return nullptr;
}

TEST(ZooCreature, LeftAndRightMirrorExactly) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      const Creature c = make_creature(plan, seed);
      const Skeleton& s = c.skeleton;
      int left_limbs = 0, right_limbs = 0;
      for (const Limb& limb : c.limbs) {
        left_limbs += limb.side == Side::Left;
        right_limbs += limb.side == Side::Right;
        if (limb.side != Side::Left) continue;
        const Limb* right = counterpart(c, limb);
        ASSERT_NE(right, nullptr) << plan_name(plan) << " " << limb_kind_name(limb.kind) << " pair " << limb.pair;
        ASSERT_EQ(right->joints.size(), limb.joints.size());
        for (size_t k = 0; k < limb.joints.size(); ++k) {
          const Vec3& l = s.offsets[limb.joints[k]];
          const Vec3& r = s.offsets[right->joints[k]];
          EXPECT_EQ(l.x(), -r.x()) << s.names[limb.joints[k]];
          EXPECT_EQ(l.y(), r.y()) << s.names[limb.joints[k]];
          EXPECT_EQ(l.z(), r.z()) << s.names[limb.joints[k]];
          if (c.options.naming != NamingStyle::Numbered) {
            EXPECT_EQ(mirrored_canonical_name(canonical_joint_name(s.names[limb.joints[k]])),
                      canonical_joint_name(s.names[right->joints[k]]));
          }
        }
        if (limb.kind == LimbKind::Leg) {
          EXPECT_EQ(limb.rest_foot.x(), -right->rest_foot.x());
          EXPECT_EQ(limb.rest_foot.y(), right->rest_foot.y());
          EXPECT_EQ(limb.rest_foot.z(), right->rest_foot.z());
        }
      }
      EXPECT_EQ(left_limbs, right_limbs) << plan_name(plan);
    }
  }
}

// Words a canonical name of a limb's joints may carry, by kind.
bool names_its_kind(LimbKind kind, const std::string& canonical) {
  auto has = [&](const char* word) { return canonical.find(word) != std::string::npos; };
  switch (kind) {
    // (a primate walks on its arms: their words name its front legs)
    case LimbKind::Leg:
      return has("leg") || has("foot") || has("toe") || has("coxa") || has("shoulder") || has("hoof") || has("arm") ||
             has("hand");
    case LimbKind::Arm: return has("arm") || has("hand") || has("shoulder") || has("claw");
    case LimbKind::Wing: return has("wing");
    case LimbKind::Fin: return has("fin");
    case LimbKind::Tail: return has("tail") || has("spine");
    case LimbKind::Neck: return has("neck");
    case LimbKind::Head: return has("head");
    case LimbKind::Spine: return has("spine");
    case LimbKind::Antenna: return has("antenna") || has("palp");
    case LimbKind::Jaw: return has("jaw") || has("mandible") || has("fang");
    case LimbKind::Trunk: return has("trunk");
  }
  return false;
}

TEST(ZooCreature, CanonicalNamesCarryMeaningAndSide) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed = 0; seed < 8; ++seed) {
      for (NamingStyle style : {NamingStyle::Mixamo, NamingStyle::Blender, NamingStyle::Game, NamingStyle::Biped3ds,
                                NamingStyle::Maya, NamingStyle::Truebones}) {
        CreatureOptions options = sample_creature_options(plan, seed);
        options.naming = style;
        const Creature c = make_creature(plan, seed, options);
        const Skeleton& s = c.skeleton;
        std::vector<Side> limb_side(static_cast<size_t>(s.joint_count()), Side::None);
        std::vector<bool> in_limb(static_cast<size_t>(s.joint_count()), false);
        for (const Limb& limb : c.limbs) {
          for (int j : limb.joints) {
            limb_side[j] = limb.side;
            in_limb[j] = true;
            const std::string canonical = canonical_joint_name(s.names[j]);
            EXPECT_TRUE(names_its_kind(limb.kind, canonical))
                << plan_name(plan) << " " << limb_kind_name(limb.kind) << ": '" << s.names[j] << "' -> '" << canonical << "'";
          }
        }
        for (int j = 1; j < s.joint_count(); ++j) {  // joints off the chains (a bird's side toes): their parent's side
          if (!in_limb[j]) limb_side[j] = limb_side[s.parents[j]];
        }
        for (int j = 0; j < s.joint_count(); ++j) {
          const std::string canonical = canonical_joint_name(s.names[j]);
          EXPECT_EQ(canonical.find("joint"), std::string::npos) << s.names[j] << " -> " << canonical;
          EXPECT_EQ(joint_side(s.names[j]), limb_side[j]) << plan_name(plan) << " '" << s.names[j] << "'";
          if (limb_side[j] == Side::Left) {
            EXPECT_EQ(canonical.rfind("left ", 0), 0u) << s.names[j];
          } else if (limb_side[j] == Side::Right) {
            EXPECT_EQ(canonical.rfind("right ", 0), 0u) << s.names[j];
          }
        }
        const std::string root = canonical_joint_name(s.names[0]);
        EXPECT_TRUE(root == "hips" || root == "chest") << s.names[0] << " -> " << root;
      }
    }
  }
}

TEST(ZooCreature, LimbMetadataMatchesTheSkeleton) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      const Creature c = make_creature(plan, seed);
      const Skeleton& s = c.skeleton;
      const RestPositions rest = rest_positions(s);
      const double tolerance = 1e-9 * s.diameter();
      std::set<int> seen;
      for (const Limb& limb : c.limbs) {
        ASSERT_FALSE(limb.joints.empty());
        EXPECT_NE(limb.joints.front(), 0) << "the root belongs to no limb";
        for (size_t k = 1; k < limb.joints.size(); ++k) {
          EXPECT_EQ(s.parents[limb.joints[k]], limb.joints[k - 1]) << plan_name(plan) << " " << limb_kind_name(limb.kind);
        }
        for (int j : limb.joints) EXPECT_TRUE(seen.insert(j).second) << "joint " << s.names[j] << " in two limbs";
        if (limb.kind == LimbKind::Leg) {
          EXPECT_LT((limb.rest_foot - rest.joints[limb.joints.back()]).norm(), tolerance) << plan_name(plan);
          EXPECT_NE(limb.side, Side::None);
        } else {
          EXPECT_EQ(limb.rest_foot, Vec3::Zero());
        }
      }
      // Legs first, front to back, left before right.
      const std::vector<const Limb*> legs = c.limbs_of(LimbKind::Leg);
      for (size_t l = 0; l < legs.size(); ++l) {
        EXPECT_EQ(&c.limbs[l], legs[l]) << plan_name(plan) << ": legs come first";
        EXPECT_EQ(legs[l]->pair, static_cast<int>(l / 2));
        EXPECT_EQ(legs[l]->side, l % 2 == 0 ? Side::Left : Side::Right);
        if (l >= 2 && legs[l]->side == Side::Left) {
          EXPECT_LT(legs[l]->rest_foot.z(), legs[l - 2]->rest_foot.z()) << plan_name(plan) << " seed " << seed;
        }
      }
      // Spine: the root, then a parent chain.
      ASSERT_FALSE(c.spine.empty());
      EXPECT_EQ(c.spine.front(), 0);
      for (size_t k = 1; k < c.spine.size(); ++k) EXPECT_EQ(s.parents[c.spine[k]], c.spine[k - 1]);
      // End sites only on leaves, one per leaf.
      std::vector<int> end_sites(static_cast<size_t>(s.joint_count()), 0);
      for (const EndSite& site : s.end_sites) ++end_sites[site.parent];
      const auto children = s.children_lists();
      for (int j = 0; j < s.joint_count(); ++j) EXPECT_EQ(end_sites[j], children[j].empty() ? 1 : 0) << s.names[j];
    }
  }
}

TEST(ZooCreature, FacesPlusZWithItsLeftAtPlusX) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      const Creature c = make_creature(plan, seed);
      const RestPositions rest = rest_positions(c.skeleton);
      const std::vector<const Limb*> heads = c.limbs_of(LimbKind::Head);
      ASSERT_EQ(heads.size(), 1u) << plan_name(plan);
      const double head_z = rest.joints[heads.front()->joints.back()].z();
      EXPECT_GE(head_z, 0.0) << plan_name(plan);
      for (const Limb* tail : c.limbs_of(LimbKind::Tail)) {
        EXPECT_GT(head_z, rest.joints[tail->joints.back()].z()) << plan_name(plan) << " seed " << seed;
      }
      for (const Limb& limb : c.limbs) {
        for (int j : limb.joints) {
          const double x = rest.joints[j].x();
          const std::string& name = c.skeleton.names[j];
          if (limb.side == Side::Left) {
            EXPECT_GT(x, 0.0) << plan_name(plan) << " " << name;
          } else if (limb.side == Side::Right) {
            EXPECT_LT(x, 0.0) << plan_name(plan) << " " << name;
          } else {
            EXPECT_EQ(x, 0.0) << plan_name(plan) << " " << name;
          }
        }
      }
    }
  }
}

TEST(ZooCreature, SpeciesAndProportions) {
  const std::set<std::string> quadrupeds = {"dog", "cat", "horse", "wolf", "bear"};
  for (BodyPlan plan : kAllBodyPlans) {
    std::set<std::string> species;
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      const Creature c = make_creature(plan, seed);
      species.insert(c.species);
      EXPECT_TRUE(c.units_per_meter == 1.0 || c.units_per_meter == 100.0);
      const double meters = 1.0 / c.units_per_meter;
      switch (plan) {
        case BodyPlan::Biped:
          EXPECT_EQ(c.species, "person");
          EXPECT_GT(c.rest_root_height * meters, 0.5);
          EXPECT_LT(c.rest_root_height * meters, 1.3);
          EXPECT_EQ(c.limbs_of(LimbKind::Leg).size(), 2u);
          EXPECT_EQ(c.limbs_of(LimbKind::Arm).size(), 2u);
          break;
        case BodyPlan::Quadruped:
          EXPECT_EQ(quadrupeds.count(c.species), 1u) << c.species;
          EXPECT_EQ(c.limbs_of(LimbKind::Leg).size(), 4u);
          break;
        case BodyPlan::Hexapod:
          EXPECT_TRUE(c.species == "ant" || c.species == "beetle") << c.species;
          EXPECT_EQ(c.limbs_of(LimbKind::Leg).size(), 6u);
          EXPECT_EQ(c.limbs_of(LimbKind::Antenna).size(), 2u);
          break;
        case BodyPlan::Spider:
          EXPECT_EQ(c.species, "spider");
          EXPECT_EQ(c.limbs_of(LimbKind::Leg).size(), 8u);
          break;
        case BodyPlan::Snake:
          EXPECT_EQ(c.species, "snake");
          EXPECT_TRUE(c.limbs_of(LimbKind::Leg).empty());
          EXPECT_GE(c.skeleton.joint_count(), 20);
          EXPECT_EQ(c.rest_root_height, 0.0);
          break;
        case BodyPlan::Bird:
          EXPECT_EQ(c.species, "bird");
          EXPECT_EQ(c.limbs_of(LimbKind::Leg).size(), 2u);
          EXPECT_EQ(c.limbs_of(LimbKind::Wing).size(), 2u);
          break;
        case BodyPlan::Fish:
          EXPECT_EQ(c.species, "fish");
          EXPECT_TRUE(c.limbs_of(LimbKind::Leg).empty());
          EXPECT_GE(c.limbs_of(LimbKind::Fin).size(), 4u);
          break;
        case BodyPlan::Dragon:
          EXPECT_EQ(c.species, "dragon");
          EXPECT_EQ(c.limbs_of(LimbKind::Leg).size(), 4u);
          EXPECT_EQ(c.limbs_of(LimbKind::Wing).size(), 2u);
          EXPECT_GE(c.limbs_of(LimbKind::Neck).front()->joints.size(), 6u);
          EXPECT_GE(c.limbs_of(LimbKind::Tail).front()->joints.size(), 8u);
          break;
        case BodyPlan::Centipede:
          EXPECT_EQ(c.species, "centipede");
          EXPECT_GE(c.limbs_of(LimbKind::Leg).size(), 24u);
          EXPECT_LE(c.limbs_of(LimbKind::Leg).size(), 40u);
          EXPECT_GE(c.limbs_of(LimbKind::Leg).front()->joints.size(), 3u);  // 2 or 3 bones
          break;
      }
    }
    if (plan == BodyPlan::Quadruped) {
      EXPECT_GE(species.size(), 4u);
    } else if (plan == BodyPlan::Hexapod) {
      EXPECT_EQ(species.size(), 2u);
    }
  }
}

}  // namespace
}  // namespace nec::zoo
