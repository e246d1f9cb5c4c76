// Procedural motion synthesis: determinism, planted feet (slip measured with
// forward kinematics), gait phase patterns measured from foot heights,
// turning and speed, start/stop, flight, secondary motion lag, BVH round
// trips through preprocessing, the IK utilities, and generation speed.
#include "nec/motion/bvh.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"
#include "nec/zoo/motion_synthesis.h"
#include "nec/zoo/zoo.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

namespace nec::zoo {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Slip tolerance: horizontal drift of a planted foot within one stance phase.
constexpr double kSlipTolerance = 0.02;    // x leg length
constexpr double kGroundTolerance = 0.01;  // x leg length: stance feet at y = 0

struct FootStats {
  double max_slip = 0.0;    // largest horizontal drift within one stance phase, file units
  double max_toe_slip = 0.0;  // same for the end site beyond the tip (toe, claw): the foot does not swivel
  double max_height = 0.0;  // largest |y| of a stance foot
  int stance_frames = 0;
  int swing_frames = 0;
  double max_swing_height = 0.0;
};

FootStats foot_stats(const Creature& creature, const SynthesizedMotion& made) {
  const Pose pose = forward_kinematics(creature.skeleton, made.motion);
  FootStats stats;
  for (const LegTrack& leg : made.legs) {
    const int tip = creature.limbs[leg.limb].joints.back();
    Vec3 toe_offset = Vec3::Zero();
    for (const EndSite& site : creature.skeleton.end_sites) {
      if (site.parent == tip) toe_offset = site.offset;
    }
    auto toe = [&](int t) { return Vec3(pose.position(t, tip) + pose.rotation(t, tip) * toe_offset); };
    int start = -1;
    for (int t = 0; t < made.motion.frame_count; ++t) {
      const Vec3& foot = pose.position(t, tip);
      if (!leg.stance[t]) {
        start = -1;
        ++stats.swing_frames;
        stats.max_swing_height = std::max(stats.max_swing_height, foot.y());
        continue;
      }
      ++stats.stance_frames;
      if (start < 0) start = t;
      Vec3 drift = foot - pose.position(start, tip);
      drift.y() = 0.0;
      stats.max_slip = std::max(stats.max_slip, drift.norm());
      Vec3 toe_drift = toe(t) - toe(start);
      toe_drift.y() = 0.0;
      stats.max_toe_slip = std::max(stats.max_toe_slip, toe_drift.norm());
      stats.max_height = std::max(stats.max_height, std::abs(foot.y()));
    }
  }
  return stats;
}

bool has_legs(BodyPlan plan) { return plan != BodyPlan::Snake && plan != BodyPlan::Fish; }

MotionSpec spec_for(const Creature& creature, Action action, double speed_ratio, double turn, uint64_t seed) {
  MotionSpec spec;
  spec.action = action;
  spec.speed = typical_speed(creature, action) * speed_ratio;
  spec.turn_rate = turn;
  spec.seed = seed;
  return spec;
}

// Horizontal heading of a rotation (radians about +Y, + = left).
double yaw_of(const Quat& q) { return heading_angle(q); }

// ---- IK utilities ----------------------------------------------------------

TEST(ZooIk, TwoBoneReachesWithinReachAndBendsTowardsPole) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 root(u(rng), u(rng), u(rng));
    const double upper = 0.5 + 0.5 * std::abs(u(rng)), lower = 0.5 + 0.5 * std::abs(u(rng));
    Vec3 direction(u(rng), u(rng), u(rng));
    direction.normalize();
    const double distance = std::abs(upper - lower) + 0.05 + (upper + lower - std::abs(upper - lower) - 0.1) * std::abs(u(rng));
    const Vec3 target = root + direction * distance;
    const Vec3 pole = direction.cross(Vec3(u(rng), u(rng), u(rng))).normalized();
    const Vec3 middle = two_bone_middle(root, target, upper, lower, pole);
    worst = std::max({worst, std::abs((middle - root).norm() - upper), std::abs((target - middle).norm() - lower)});
    EXPECT_GT((middle - root).dot(pole), -1e-9) << "bends away from the pole";
  }
  EXPECT_LT(worst, 1e-9) << "largest bone length error " << worst;
}

TEST(ZooIk, FabrikReachesAndKeepsLengths) {
  std::vector<Vec3> chain = {Vec3(0, 0, 0), Vec3(0.3, -0.5, 0.1), Vec3(0.2, -1.0, 0.3), Vec3(0.5, -1.4, 0.2), Vec3(0.6, -1.7, 0.1)};
  std::vector<double> lengths;
  for (size_t i = 0; i + 1 < chain.size(); ++i) lengths.push_back((chain[i + 1] - chain[i]).norm());
  const Vec3 target(0.9, -1.2, 0.4);
  // Start from a squashed guess: FABRIK restores the given lengths.
  for (Vec3& p : chain) p *= 0.5;
  fabrik(chain, lengths, target);
  double length_error = 0.0;
  for (size_t i = 0; i + 1 < chain.size(); ++i) length_error = std::max(length_error, std::abs((chain[i + 1] - chain[i]).norm() - lengths[i]));
  EXPECT_LT((chain.back() - target).norm(), 1e-6);
  EXPECT_LT(length_error, 1e-9) << "largest length error " << length_error;
  EXPECT_LT(chain.front().norm(), 1e-12) << "the root moved";
}

// Positions -> local rotations relative to rest directions that do NOT point
// down (random rest offsets): FK of the result reproduces the positions.
TEST(ZooIk, AimChainReproducesPositionsForAnyRestPose) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    Skeleton s;
    s.add_joint("root", -1, Vec3::Zero(), ChannelLayout::position_rotations(EulerOrder::ZXY));
    std::vector<int> chain;
    int parent = 0;
    for (int k = 0; k < 4; ++k) {
      parent = s.add_joint("j" + std::to_string(k), parent, Vec3(u(rng), u(rng), u(rng)), ChannelLayout::rotations(EulerOrder::ZXY));
      chain.push_back(parent);
    }
    Motion m = Motion::rest(s, 1, 30.0);
    m.rotation(0, 0) = testing::random_rotation(rng);
    // Wanted positions: the chain's own lengths in random directions.
    std::vector<Vec3> wanted = {forward_kinematics(s, m).position(0, chain[0])};
    for (size_t k = 1; k < chain.size(); ++k) {
      wanted.push_back(wanted.back() + Vec3(u(rng), u(rng), u(rng)).normalized() * s.offsets[chain[k]].norm());
    }
    aim_chain(s, chain, wanted, m.rotation(0, 0), &m.rotation(0, 0));
    const Pose pose = forward_kinematics(s, m);
    for (size_t k = 0; k < chain.size(); ++k) worst = std::max(worst, (pose.position(0, chain[k]) - wanted[k]).norm());
  }
  EXPECT_LT(worst, 1e-9) << "largest position error " << worst;
}

// ---- actions, determinism --------------------------------------------------

TEST(ZooMotion, ActionNamesRoundTripAndPlansSupportTheirSignatureActions) {
  for (Action action : kAllActions) {
    Action parsed;
    ASSERT_TRUE(parse_action(action_name(action), parsed));
    EXPECT_EQ(parsed, action);
  }
  Action unused;
  EXPECT_FALSE(parse_action("moonwalk", unused));
  EXPECT_TRUE(supports_action(BodyPlan::Snake, Action::Slither));
  EXPECT_TRUE(supports_action(BodyPlan::Fish, Action::Swim));
  EXPECT_TRUE(supports_action(BodyPlan::Bird, Action::TakeOff));
  EXPECT_TRUE(supports_action(BodyPlan::Dragon, Action::Glide));
  EXPECT_TRUE(supports_action(BodyPlan::Quadruped, Action::Gallop));
  EXPECT_FALSE(supports_action(BodyPlan::Fish, Action::Walk));
  EXPECT_FALSE(supports_action(BodyPlan::Snake, Action::Fly));
  const Creature fish = make_creature(BodyPlan::Fish, 1);
  EXPECT_THROW(synthesize_motion(fish, spec_for(fish, Action::Walk, 1.0, 0.0, 0)), std::invalid_argument);
  MotionSpec bad;
  bad.seconds = -1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(ZooMotion, SameSpecGivesIdenticalBvhText) {
  for (BodyPlan plan : kAllBodyPlans) {
    const Creature creature = make_creature(plan, 5);
    const Action action = supported_actions(plan)[1];
    MotionSpec spec = spec_for(creature, action, 1.2, 25.0, 77);
    spec.start_from_still = true;
    const std::string a = format_bvh(creature.skeleton, synthesize_motion(creature, spec).motion);
    const std::string b = format_bvh(creature.skeleton, synthesize_motion(creature, spec).motion);
    EXPECT_EQ(a, b) << body_plan_name(plan);
    spec.seed = 78;
    const std::string c = format_bvh(creature.skeleton, synthesize_motion(creature, spec).motion);
    EXPECT_NE(a, c) << body_plan_name(plan) << ": the style seed changes nothing";
  }
}

// ---- planted feet ----------------------------------------------------------

// Every legged plan, every rest pose, every action with feet on the ground,
// turning and starting/stopping: stance feet stay put and on the ground.
TEST(ZooMotion, StanceFeetArePlantedAndOnTheGround) {
  double worst_slip = 0.0, worst_height = 0.0, worst_toe = 0.0;
  std::string worst_case;
  int clips = 0;
  for (BodyPlan plan : kAllBodyPlans) {
    if (!has_legs(plan)) continue;
    for (RestPose rest : {RestPose::TPose, RestPose::APose, RestPose::Crouched}) {
      for (uint64_t seed : {1, 2}) {
        CreatureOptions options = sample_creature_options(plan, seed);
        options.rest_pose = rest;
        const Creature creature = make_creature(plan, seed, options);
        const double leg = creature.leg_length;
        ASSERT_GT(leg, 0.0);
        for (Action action : supported_actions(plan)) {
          if (action == Action::Fly || action == Action::Glide) continue;
          const double turn = seed == 1 ? 35.0 : -60.0;
          MotionSpec spec = spec_for(creature, action, seed == 1 ? 0.7 : 1.5, turn, seed);
          spec.start_from_still = seed == 1;
          spec.stop_at_end = seed == 2;
          const SynthesizedMotion made = synthesize_motion(creature, spec);
          const FootStats stats = foot_stats(creature, made);
          ++clips;
          EXPECT_GT(stats.stance_frames, 0) << body_plan_name(plan) << " " << action_name(action);
          const double slip = stats.max_slip / leg, height = stats.max_height / leg;
          if (slip > worst_slip || height > worst_height) {
            worst_case = std::string(body_plan_name(plan)) + " " + std::string(action_name(action)) + " rest " +
                         std::to_string(static_cast<int>(rest)) + " seed " + std::to_string(seed);
          }
          worst_slip = std::max(worst_slip, slip);
          worst_toe = std::max(worst_toe, stats.max_toe_slip / leg);
          EXPECT_LT(stats.max_toe_slip / leg, kSlipTolerance) << body_plan_name(plan) << " " << action_name(action)
                                                             << ": the planted foot swivels";
          worst_height = std::max(worst_height, height);
          EXPECT_LT(slip, kSlipTolerance) << body_plan_name(plan) << " " << action_name(action) << " rest "
                                          << static_cast<int>(rest) << ": slip " << slip << " leg lengths";
          EXPECT_LT(height, kGroundTolerance) << body_plan_name(plan) << " " << action_name(action) << " rest "
                                              << static_cast<int>(rest) << ": stance foot at " << height << " leg lengths";
        }
      }
    }
  }
  std::printf("%d clips: largest stance slip %.2e leg lengths (toe end site %.2e), largest stance foot height %.2e leg "
              "lengths (%s)\n",
              clips, worst_slip, worst_toe, worst_height, worst_case.c_str());
}

// A creature built by hand, not by make_creature: numbered joint names and a
// rest pose whose thighs stick out sideways (offsets that do not point down).
Creature hand_built_table_creature() {
  Creature c;
  c.plan = BodyPlan::Quadruped;
  c.species = "table";
  Skeleton& s = c.skeleton;
  const ChannelLayout rotations = ChannelLayout::rotations(EulerOrder::XYZ);
  s.add_joint("joint0", -1, Vec3(0.0, 1.0, 0.0), ChannelLayout::position_rotations(EulerOrder::XYZ));
  const int chest = s.add_joint("joint1", 0, Vec3(0.0, 0.05, 0.8), rotations);
  s.end_sites.push_back({chest, Vec3(0.0, 0.0, 0.2)});
  c.spine = {0, chest};
  c.limbs.push_back({LimbKind::Spine, Side::None, 0, {chest}, Vec3::Zero()});
  int index = 2;
  for (int pair = 0; pair < 2; ++pair) {
    for (Side side : {Side::Left, Side::Right}) {
      const double x = side == Side::Left ? 1.0 : -1.0;
      const int attach = pair == 0 ? chest : 0;
      const double attach_y = pair == 0 ? 1.05 : 1.0;
      const int hip = s.add_joint("joint" + std::to_string(index++), attach, Vec3(0.2 * x, 0.0, 0.0), rotations);
      const int knee = s.add_joint("joint" + std::to_string(index++), hip, Vec3(0.4 * x, 0.1, 0.0), rotations);
      const int foot = s.add_joint("joint" + std::to_string(index++), knee, Vec3(0.0, -(attach_y + 0.1), 0.0), rotations);
      s.end_sites.push_back({foot, Vec3(0.0, 0.0, 0.08)});
      Limb leg{LimbKind::Leg, side, pair, {hip, knee, foot}, Vec3::Zero()};
      c.limbs.push_back(leg);
    }
  }
  s.validate();
  c.rest_root_height = 1.0;
  c.body_length = 1.0;
  c.leg_length = 0.4 + 1.1;
  return c;
}

TEST(ZooMotion, HandBuiltCreatureWithSidewaysRestLegsWalks) {
  const Creature table = hand_built_table_creature();
  for (Action action : {Action::Walk, Action::Trot, Action::Turn, Action::Sit, Action::Jump}) {
    MotionSpec spec = spec_for(table, action, 1.0, 30.0, 3);
    spec.start_from_still = true;
    const SynthesizedMotion made = synthesize_motion(table, spec);
    const FootStats stats = foot_stats(table, made);
    EXPECT_LT(stats.max_slip, kSlipTolerance * table.leg_length) << action_name(action);
    EXPECT_LT(stats.max_height, kGroundTolerance * table.leg_length) << action_name(action);
    if (is_gait(action)) {
      EXPECT_GT(stats.swing_frames, 0) << action_name(action);
    }
    const PreparedClip prepared = preprocess(parse_bvh(format_bvh(table.skeleton, made.motion), "table"), "table");
    EXPECT_TRUE(prepared.report.accepted()) << prepared.report.rejection;
  }
}

// Gaits alternate stance and swing, and swing feet clear the ground.
TEST(ZooMotion, GaitFeetLiftDuringSwing) {
  for (BodyPlan plan : kAllBodyPlans) {
    if (!has_legs(plan)) continue;
    const Creature creature = make_creature(plan, 4);
    for (Action action : supported_actions(plan)) {
      if (!is_gait(action)) continue;
      const SynthesizedMotion made = synthesize_motion(creature, spec_for(creature, action, 1.0, 0.0, 4));
      const FootStats stats = foot_stats(creature, made);
      EXPECT_GT(made.gait_frequency, 0.0);
      EXPECT_GT(stats.swing_frames, 0) << body_plan_name(plan) << " " << action_name(action);
      EXPECT_GT(stats.max_swing_height, 0.03 * creature.leg_length) << body_plan_name(plan) << " " << action_name(action);
      for (const LegTrack& leg : made.legs) {
        int swings = 0;
        for (int t = 1; t < made.motion.frame_count; ++t) swings += leg.stance[t - 1] && !leg.stance[t];
        EXPECT_GE(swings, 2) << body_plan_name(plan) << " " << action_name(action) << ": a leg that never steps";
      }
    }
  }
}

// ---- gait patterns, measured from foot heights -----------------------------

// (T) foot height of each leg (legs in Creature::limbs order).
std::vector<std::vector<double>> foot_heights(const Creature& creature, const SynthesizedMotion& made) {
  const Pose pose = forward_kinematics(creature.skeleton, made.motion);
  std::vector<std::vector<double>> heights;
  for (const LegTrack& leg : made.legs) {
    std::vector<double> h;
    const int tip = creature.limbs[leg.limb].joints.back();
    for (int t = 0; t < made.motion.frame_count; ++t) h.push_back(pose.position(t, tip).y());
    heights.push_back(std::move(h));
  }
  return heights;
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  double ma = 0, mb = 0;
  for (size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
  ma /= a.size();
  mb /= b.size();
  double ab = 0, aa = 0, bb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ab += (a[i] - ma) * (b[i] - mb);
    aa += (a[i] - ma) * (a[i] - ma);
    bb += (b[i] - mb) * (b[i] - mb);
  }
  return ab / std::sqrt(std::max(aa * bb, 1e-300));
}

// Index into the legs of the leg with this pair and side.
int leg_index(const Creature& creature, int pair, Side side) {
  int index = 0;
  for (const Limb& limb : creature.limbs) {
    if (limb.kind != LimbKind::Leg) continue;
    if (limb.pair == pair && limb.side == side) return index;
    ++index;
  }
  return -1;
}

TEST(ZooMotion, HexapodTripodGaitFromFootHeights) {
  const Creature creature = make_creature(BodyPlan::Hexapod, 2);
  const SynthesizedMotion made = synthesize_motion(creature, spec_for(creature, Action::Walk, 1.0, 0.0, 2));
  const auto h = foot_heights(creature, made);
  const int l1 = leg_index(creature, 0, Side::Left), r1 = leg_index(creature, 0, Side::Right);
  const int l2 = leg_index(creature, 1, Side::Left), r2 = leg_index(creature, 1, Side::Right);
  const int l3 = leg_index(creature, 2, Side::Left), r3 = leg_index(creature, 2, Side::Right);
  ASSERT_TRUE(l1 >= 0 && r1 >= 0 && l2 >= 0 && r2 >= 0 && l3 >= 0 && r3 >= 0);
  // Tripod A = L1 R2 L3, tripod B = R1 L2 R3: in phase within, opposite across.
  const double within_a = std::min(correlation(h[l1], h[r2]), correlation(h[l1], h[l3]));
  const double within_b = std::min(correlation(h[r1], h[l2]), correlation(h[r1], h[r3]));
  const double across = std::max({correlation(h[l1], h[r1]), correlation(h[l1], h[l2]), correlation(h[r2], h[r3])});
  std::printf("tripod: within A %.3f, within B %.3f, across %.3f\n", within_a, within_b, across);
  EXPECT_GT(within_a, 0.9);
  EXPECT_GT(within_b, 0.9);
  EXPECT_LT(across, -0.2);
}

TEST(ZooMotion, BipedAlternatesAndQuadrupedTrotsDiagonally) {
  const Creature person = make_creature(BodyPlan::Biped, 3);
  const SynthesizedMotion walk = synthesize_motion(person, spec_for(person, Action::Walk, 1.0, 0.0, 3));
  const auto hb = foot_heights(person, walk);
  const double biped = correlation(hb[leg_index(person, 0, Side::Left)], hb[leg_index(person, 0, Side::Right)]);
  EXPECT_LT(biped, -0.2) << "biped feet correlation " << biped;

  const Creature dog = make_creature(BodyPlan::Quadruped, 3);
  const SynthesizedMotion trot = synthesize_motion(dog, spec_for(dog, Action::Trot, 1.0, 0.0, 3));
  const auto hq = foot_heights(dog, trot);
  const int lf = leg_index(dog, 0, Side::Left), rf = leg_index(dog, 0, Side::Right);
  const int lh = leg_index(dog, 1, Side::Left), rh = leg_index(dog, 1, Side::Right);
  const double diagonal = std::min(correlation(hq[lf], hq[rh]), correlation(hq[rf], hq[lh]));
  const double lateral = std::max(correlation(hq[lf], hq[rf]), correlation(hq[lf], hq[lh]));
  std::printf("biped L/R %.3f; trot diagonal %.3f, lateral %.3f\n", biped, diagonal, lateral);
  EXPECT_GT(diagonal, 0.9);
  EXPECT_LT(lateral, -0.2);
}

// Wave gait: on each side, each leg lifts off shortly after the leg behind it.
void expect_back_to_front_wave(BodyPlan plan, uint64_t seed) {
  const Creature creature = make_creature(plan, seed);
  const SynthesizedMotion made = synthesize_motion(creature, spec_for(creature, Action::Walk, 1.0, 0.0, seed));
  const auto h = foot_heights(creature, made);
  int pairs = 0;
  for (const Limb& limb : creature.limbs) pairs = std::max(pairs, limb.kind == LimbKind::Leg ? limb.pair + 1 : 0);
  const double threshold = 0.02 * creature.leg_length;
  const int settle = made.motion.frame_count / 4;
  const double cycle_frames = made.motion.fps / made.gait_frequency;
  for (Side side : {Side::Left, Side::Right}) {
    // First lift-off of the last leg after settling, then each leg in front of it.
    int previous = -1;
    for (int pair = pairs - 1; pair >= 0; --pair) {
      const int leg = leg_index(creature, pair, side);
      ASSERT_GE(leg, 0);
      const int from = previous < 0 ? settle : previous;
      int lift = -1;
      for (int t = std::max(from, 1); t < made.motion.frame_count; ++t) {
        if (h[leg][t - 1] <= threshold && h[leg][t] > threshold) {
          lift = t;
          break;
        }
      }
      ASSERT_GE(lift, 0) << body_plan_name(plan) << ": pair " << pair << " never lifts";
      if (previous >= 0) {
        EXPECT_LE(lift - previous, 0.5 * cycle_frames + 1)
            << body_plan_name(plan) << ": pair " << pair << " lifts " << (lift - previous)
            << " frames after the leg behind it (cycle " << cycle_frames << " frames)";
      }
      previous = lift;
    }
  }
}

TEST(ZooMotion, SpiderAndCentipedeWaveGaitRunsBackToFront) {
  expect_back_to_front_wave(BodyPlan::Spider, 1);
  expect_back_to_front_wave(BodyPlan::Spider, 6);
  expect_back_to_front_wave(BodyPlan::Centipede, 2);
}

TEST(ZooMotion, GaitPatternTables) {
  const Creature person = make_creature(BodyPlan::Biped, 1);
  const GaitPattern walk = gait_pattern(person, Action::Walk);
  ASSERT_EQ(walk.phases.size(), 2u);
  EXPECT_NEAR(std::abs(walk.phases[0] - walk.phases[1]), 0.5, 1e-12);
  EXPECT_GT(walk.duty_factor, 0.5);  // walking: a double-support phase
  EXPECT_LT(gait_pattern(person, Action::Run).duty_factor, 0.5);  // running: a flight phase
  EXPECT_TRUE(gait_pattern(person, Action::Idle).phases.empty());
}

// ---- trajectory ------------------------------------------------------------

TEST(ZooMotion, TurnRateTurnsTheRightWayAndSpeedIsMet) {
  for (BodyPlan plan : {BodyPlan::Biped, BodyPlan::Quadruped, BodyPlan::Hexapod, BodyPlan::Fish, BodyPlan::Bird}) {
    const Creature creature = make_creature(plan, 9);
    const Action action = plan == BodyPlan::Fish ? Action::Swim : plan == BodyPlan::Bird ? Action::Fly : Action::Walk;
    for (double turn : {-30.0, 0.0, 30.0}) {
      const SynthesizedMotion made = synthesize_motion(creature, spec_for(creature, action, 1.0, turn, 9));
      const Motion& m = made.motion;
      // Heading change of the root trajectory: direction of travel at the start and the end.
      const Vec3 first = m.translation(5, 0) - m.translation(0, 0);
      const Vec3 last = m.translation(m.frame_count - 1, 0) - m.translation(m.frame_count - 6, 0);
      const double change = std::remainder(std::atan2(last.x(), last.z()) - std::atan2(first.x(), first.z()), 2 * kPi) * 180.0 / kPi;
      const double expected = heading_change_degrees(made.spec) * (m.frame_count - 5.5) / m.frame_count;
      EXPECT_NEAR(change, expected, 8.0 + 0.1 * std::abs(expected)) << body_plan_name(plan) << " turn " << turn;
      if (turn > 0) {
        EXPECT_GT(change, 0.0) << "a left turn must turn counter-clockwise (towards +X)";
      } else if (turn < 0) {
        EXPECT_LT(change, 0.0);
      }
      // Mean speed of the root over the clip (path length, horizontal), body lengths per second.
      double path = 0.0;
      for (int t = 1; t < m.frame_count; ++t) {
        Vec3 step = m.translation(t, 0) - m.translation(t - 1, 0);
        step.y() = 0.0;
        path += step.norm();
      }
      const double speed = path / creature.body_length / ((m.frame_count - 1) / m.fps);
      EXPECT_NEAR(speed, made.spec.speed, 0.1 * made.spec.speed + 0.02) << body_plan_name(plan);
    }
  }
}

// Backing up and sidestepping: the root travels the asked way relative to where the body faces, which does not
// turn, and the stance feet stay planted.
TEST(ZooMotion, WalksBackwardAndSidewaysFacingAhead) {
  for (BodyPlan plan : {BodyPlan::Biped, BodyPlan::Quadruped, BodyPlan::Spider}) {
    const Creature creature = make_creature(plan, 5);
    for (double direction : {180.0, 90.0, -90.0}) {
      MotionSpec spec = spec_for(creature, Action::Walk, 0.6, 40.0, 5);
      spec.direction = direction;
      const SynthesizedMotion made = synthesize_motion(creature, spec);
      EXPECT_EQ(made.spec.turn_rate, 0.0) << "backing up and sidestepping go straight";
      const Motion& m = made.motion;
      const Vec3 travel = m.translation(m.frame_count - 1, 0) - m.translation(0, 0);
      const double facing = heading_angle(m.rotation(0, 0));
      const double moved = std::atan2(travel.x(), travel.z());
      const double relative = std::remainder(moved - facing, 2 * kPi) * 180.0 / kPi;
      EXPECT_NEAR(std::remainder(relative - direction, 360.0), 0.0, 20.0)
          << body_plan_name(plan) << " asked " << direction << ", went " << relative;
      EXPECT_GT(std::hypot(travel.x(), travel.z()), 0.3 * made.spec.speed * creature.body_length * spec.seconds);
      EXPECT_NEAR(std::remainder(heading_angle(m.rotation(m.frame_count - 1, 0)) - facing, 2 * kPi), 0.0, 0.2);
      const FootStats stats = foot_stats(creature, made);
      EXPECT_LT(stats.max_slip, 2 * kSlipTolerance * creature.leg_length) << body_plan_name(plan) << " " << direction;
      EXPECT_GT(stats.swing_frames, 0);
    }
  }
  MotionSpec bad;
  bad.direction = 200.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// ---- the plans modelled on users' rigs ---------------------------------------

// A kangaroo hops: both feet leave and land together, and the body flies between hops.
TEST(ZooMotion, HopperHopsWithBothFeetTogether) {
  const Creature creature = make_creature(BodyPlan::Hopper, 3);
  for (Action action : {Action::Walk, Action::Run}) {
    const SynthesizedMotion made = synthesize_motion(creature, spec_for(creature, action, 1.0, 0.0, 3));
    ASSERT_EQ(made.legs.size(), 2u);
    EXPECT_EQ(made.legs[0].stance, made.legs[1].stance) << action_name(action);
    const std::vector<std::vector<double>> heights = foot_heights(creature, made);
    EXPECT_GT(correlation(heights[0], heights[1]), 0.95) << action_name(action);
    const Motion& m = made.motion;
    int airborne = 0;
    double low = m.translation(0, 0).y(), high = low;
    for (int t = 0; t < m.frame_count; ++t) {
      airborne += !made.legs[0].stance[t];
      low = std::min(low, m.translation(t, 0).y());
      high = std::max(high, m.translation(t, 0).y());
    }
    EXPECT_GT(airborne, m.frame_count / 3) << action_name(action) << ": a hop is mostly flight";
    EXPECT_GT(high - low, 0.1 * creature.leg_length) << action_name(action) << ": the body rises between hops";
  }
}

// Feeding: the muzzle (the head's or jaw's end site) goes down to the ground by the forefeet and comes up again,
// for long necks (giraffes, horses) and short ones (bears, dogs: the body tips forward), the feet planted.
TEST(ZooMotion, EatingBringsTheMuzzleToTheGround) {
  for (BodyPlan plan : {BodyPlan::Quadruped, BodyPlan::Ungulate, BodyPlan::Dragon}) {
    for (uint64_t seed = 0; seed < 6; ++seed) {
      const Creature creature = make_creature(plan, seed);
      const int head = creature.limbs_of(LimbKind::Head).at(0)->joints.back();
      // The muzzle: the end site of the head, or of its jaw.
      const Skeleton& s = creature.skeleton;
      const auto muzzle_site = std::find_if(s.end_sites.begin(), s.end_sites.end(), [&](const EndSite& site) {
        return site.parent == head || s.parents[site.parent] == head;
      });
      ASSERT_NE(muzzle_site, s.end_sites.end());
      const SynthesizedMotion made = synthesize_motion(creature, spec_for(creature, Action::Eat, 1.0, 0.0, seed));
      const Pose pose = forward_kinematics(s, made.motion);
      const auto muzzle = [&](int t) {
        return Vec3(pose.position(t, muzzle_site->parent) + pose.rotation(t, muzzle_site->parent) * muzzle_site->offset);
      };
      const int last = made.motion.frame_count - 1;
      const int grazing = made.motion.frame_count / 2;
      const std::string what = creature.species + " seed " + std::to_string(seed);
      EXPECT_LT(muzzle(grazing).y(), 0.12 * creature.leg_length) << what << ": standing " << muzzle(0).y();
      EXPECT_GT(muzzle(grazing).y(), -0.02 * creature.leg_length) << what << ": not through the ground";
      EXPECT_GT(muzzle(0).y(), 3.0 * muzzle(grazing).y()) << what;
      EXPECT_GT(muzzle(last).y(), 0.7 * muzzle(0).y()) << what << ": the head comes up again";
      const double forefeet = pose.position(grazing, creature.limbs_of(LimbKind::Leg).at(0)->joints.back()).z();
      const Vec3 root = made.motion.translation(grazing, 0);
      EXPECT_GT(muzzle(grazing).z() - root.z(), forefeet - root.z() - 0.1 * creature.leg_length)
          << what << ": at or ahead of the forefeet";
      const FootStats stats = foot_stats(creature, made);
      EXPECT_LT(stats.max_slip, kSlipTolerance * creature.leg_length) << what;
      EXPECT_EQ(stats.swing_frames, 0) << what << ": it feeds standing";
    }
  }
}

// Getting up is lying down (sitting down, for plans that do not lie) played backwards: the same poses and foot
// contacts in reverse order, low at first and standing at the end.
TEST(ZooMotion, GettingUpIsLyingDownBackwards) {
  for (BodyPlan plan : kAllBodyPlans) {
    if (!supports_action(plan, Action::GetUp)) {
      EXPECT_FALSE(supports_action(plan, Action::Sit) || supports_action(plan, Action::LieDown)) << body_plan_name(plan);
      continue;
    }
    const Creature creature = make_creature(plan, 8);
    const SynthesizedMotion up = synthesize_motion(creature, spec_for(creature, Action::GetUp, 1.0, 0.0, 8));
    const SynthesizedMotion down =
        synthesize_motion(creature, spec_for(creature, lowering_action(plan), 1.0, 0.0, 8));
    EXPECT_EQ(up.spec.action, Action::GetUp);
    const int last = up.motion.frame_count - 1;
    ASSERT_EQ(last, down.motion.frame_count - 1);
    for (int t = 0; t <= last; t += 7) {
      for (int j = 0; j < creature.skeleton.joint_count(); ++j) {
        EXPECT_TRUE(up.motion.rotation(t, j).isApprox(down.motion.rotation(last - t, j))) << body_plan_name(plan);
      }
      EXPECT_TRUE(up.motion.translation(t, 0).isApprox(down.motion.translation(last - t, 0)));
    }
    EXPECT_LT(up.motion.translation(0, 0).y(), up.motion.translation(last, 0).y() - 0.1 * creature.leg_length)
        << body_plan_name(plan) << ": low at first, standing at the end";
    for (size_t i = 0; i < up.legs.size(); ++i) {
      EXPECT_TRUE(std::equal(up.legs[i].stance.begin(), up.legs[i].stance.end(), down.legs[i].stance.rbegin()));
    }
  }
}

// Height of a joint over a clip: its first frame and its highest.
std::pair<double, double> first_and_highest(const Creature& creature, const SynthesizedMotion& made, int joint) {
  const Pose pose = forward_kinematics(creature.skeleton, made.motion);
  double highest = pose.position(0, joint).y();
  for (int t = 0; t < made.motion.frame_count; ++t) highest = std::max(highest, pose.position(t, joint).y());
  return {pose.position(0, joint).y(), highest};
}

// A crab threatens with its claws raised; an elephant curls its trunk up over its head; a crab walks or runs
// sideways in most of the zoo's walks and runs.
TEST(ZooMotion, CrabRaisesItsClawsAndElephantItsTrunkInAnAttack) {
  for (uint64_t seed : {1, 2, 3}) {
    const Creature crab = make_creature(BodyPlan::Crab, seed);
    const SynthesizedMotion pinch = synthesize_motion(crab, spec_for(crab, Action::Attack, 1.0, 0.0, seed));
    for (const Limb* claw : crab.limbs_of(LimbKind::Arm)) {
      const auto [first, highest] = first_and_highest(crab, pinch, claw->joints.back());
      EXPECT_GT(highest - first, 0.15 * crab.leg_length) << "crab " << seed;
    }
    const Creature elephant = make_creature(BodyPlan::Elephant, seed);
    const Limb& trunk = *elephant.limbs_of(LimbKind::Trunk).at(0);
    const int head = elephant.skeleton.parents[trunk.joints.front()];
    const SynthesizedMotion trumpet = synthesize_motion(elephant, spec_for(elephant, Action::Attack, 1.0, 0.0, seed));
    const auto [tip_first, tip_highest] = first_and_highest(elephant, trumpet, trunk.joints.back());
    const auto [head_first, head_highest] = first_and_highest(elephant, trumpet, head);
    EXPECT_LT(tip_first, head_first) << "the trunk hangs from the head";
    EXPECT_GT(tip_highest, head_first) << "then curls up above it";
  }
  ZooOptions options;
  options.plans = {BodyPlan::Crab};
  int walks = 0, sideways = 0;
  for (int i = 0; i < 20; ++i) {
    const Creature crab = make_creature(BodyPlan::Crab, zoo_creature_seed(options, i));
    for (int k = 0; k < 12; ++k) {
      const MotionSpec spec = zoo_clip_spec(crab, options, k);
      if (spec.action != Action::Walk && spec.action != Action::Run) continue;
      ++walks;
      sideways += std::abs(std::abs(spec.direction) - 90.0) < 1e-9;
    }
  }
  ASSERT_GT(walks, 10);
  EXPECT_GT(sideways, walks / 2);
}

// Manners change the carriage, not the gait: against the same neutral walk, a tired dog and person lower the head
// (the elevation of the line from the chest to the head, in the sagittal plane), a proud one raises it, a cautious
// one lowers the body, an energetic one lifts the feet higher.
TEST(ZooMotion, MannersChangeHowTheBodyIsCarried) {
  for (BodyPlan plan : {BodyPlan::Biped, BodyPlan::Quadruped}) {
    const Creature creature = make_creature(plan, 6);
    const Limb& head_chain = *creature.limbs_of(LimbKind::Head).at(0);
    const int head = head_chain.joints.back();
    int chest = creature.skeleton.parents[head_chain.joints.front()];
    for (const Limb* neck : creature.limbs_of(LimbKind::Neck)) chest = creature.skeleton.parents[neck->joints.front()];
    struct Carriage {
      double head = 0.0, root = 0.0, swing_foot = 0.0;
    };
    const auto carriage = [&](Manner manner) {
      MotionSpec spec = spec_for(creature, Action::Walk, 0.8, 0.0, 6);
      spec.manner = manner;
      const SynthesizedMotion made = synthesize_motion(creature, spec);
      EXPECT_EQ(made.spec.manner, manner);
      const Pose pose = forward_kinematics(creature.skeleton, made.motion);
      Carriage c;
      const int frames = made.motion.frame_count;
      for (int t = 0; t < frames; ++t) {
        const Vec3 line = pose.position(t, head) - pose.position(t, chest);  // the walk goes along +Z
        c.head += std::atan2(line.y(), line.z()) / frames;
        c.root += pose.position(t, 0).y() / frames;
      }
      c.swing_foot = foot_stats(creature, made).max_swing_height;
      return c;
    };
    const Carriage neutral = carriage(Manner::Neutral);
    const double h = creature.leg_length;
    EXPECT_LT(carriage(Manner::Tired).head, neutral.head - 0.1) << body_plan_name(plan);  // radians
    EXPECT_GT(carriage(Manner::Proud).head, neutral.head + 0.05) << body_plan_name(plan);
    EXPECT_LT(carriage(Manner::Cautious).root, neutral.root - 0.05 * h) << body_plan_name(plan);
    EXPECT_GT(carriage(Manner::Energetic).swing_foot, neutral.swing_foot * 1.15) << body_plan_name(plan);
  }
  // Actions that take no manner are made neutral.
  const Creature person = make_creature(BodyPlan::Biped, 6);
  MotionSpec wave = spec_for(person, Action::Wave, 1.0, 0.0, 6);
  wave.manner = Manner::Tired;
  EXPECT_EQ(synthesize_motion(person, wave).spec.manner, Manner::Neutral);
}

TEST(ZooMotion, StartsStillAndStopsStill) {
  const Creature creature = make_creature(BodyPlan::Quadruped, 12);
  MotionSpec spec = spec_for(creature, Action::Trot, 1.0, 20.0, 12);
  spec.start_from_still = true;
  spec.stop_at_end = true;
  const SynthesizedMotion made = synthesize_motion(creature, spec);
  const Motion& m = made.motion;
  const int still = static_cast<int>(0.3 * m.fps);
  auto horizontal = [](Vec3 v) {
    v.y() = 0.0;
    return v.norm();
  };
  EXPECT_LT(horizontal(m.translation(still, 0) - m.translation(0, 0)), 1e-9);
  EXPECT_LT(horizontal(m.translation(m.frame_count - 1, 0) - m.translation(m.frame_count - 1 - still, 0)), 1e-9);
  EXPECT_GT(horizontal(m.translation(m.frame_count / 2, 0) - m.translation(0, 0)), 0.1 * creature.body_length);
  // Standing still at both ends: all feet planted.
  for (const LegTrack& leg : made.legs) {
    for (int t = 0; t < still; ++t) EXPECT_TRUE(leg.stance[t]);
    for (int t = m.frame_count - still; t < m.frame_count; ++t) EXPECT_TRUE(leg.stance[t]);
  }
}

TEST(ZooMotion, FlightIsAirborneAndTakeOffClimbs) {
  for (BodyPlan plan : {BodyPlan::Bird, BodyPlan::Dragon}) {
    const Creature creature = make_creature(plan, 4);
    for (Action action : {Action::Fly, Action::Glide, Action::TakeOff}) {
      const SynthesizedMotion made = synthesize_motion(creature, spec_for(creature, action, 1.0, 0.0, 4));
      const Pose pose = forward_kinematics(creature.skeleton, made.motion);
      auto lowest = [&](int t) {
        double low = pose.position(t, 0).y();
        for (int j = 0; j < creature.skeleton.joint_count(); ++j) low = std::min(low, pose.position(t, j).y());
        return low;
      };
      const int last = made.motion.frame_count - 1;
      if (action == Action::TakeOff) {
        EXPECT_LT(lowest(0), 0.02 * creature.leg_length) << "starts on the ground";
        EXPECT_GT(lowest(last), 0.5 * creature.leg_length) << body_plan_name(plan) << " did not leave the ground";
        EXPECT_GT(made.motion.translation(last, 0).z() - made.motion.translation(0, 0).z(), 0.5 * creature.body_length);
      } else {
        for (int t = 0; t <= last; t += 10) EXPECT_GT(lowest(t), 0.5 * creature.leg_length) << action_name(action);
      }
      for (const LegTrack& leg : made.legs) {
        EXPECT_FALSE(leg.stance[last]) << "feet touch the ground in flight";
      }
    }
  }
}

// Biped gestures, measured with forward kinematics in the creature's frame (it faces +Z, its left is +X).
class BipedGestures : public ::testing::Test {
 protected:
  struct Made {
    Pose pose;
    SynthesizedMotion motion;
  };
  Made make(Action action, Side side, uint64_t seed = 3) const {
    MotionSpec spec = spec_for(person_, action, 1.0, 0.0, seed);
    spec.side = side;
    SynthesizedMotion made = synthesize_motion(person_, spec);
    Pose pose = forward_kinematics(person_.skeleton, made.motion);
    return {std::move(pose), std::move(made)};
  }
  const Limb& limb(LimbKind kind, Side side) const {
    for (const Limb* l : person_.limbs_of(kind)) {
      if (l->side == side) return *l;
    }
    throw std::logic_error("no such limb");
  }
  int hand(Side side) const { return limb(LimbKind::Arm, side).joints.back(); }
  int shoulder(Side side) const { return limb(LimbKind::Arm, side).joints.front(); }
  int foot(Side side) const { return limb(LimbKind::Leg, side).joints.back(); }
  int head() const { return person_.limbs_of(LimbKind::Head).at(0)->joints.back(); }
  // The middle of the clip, where every gesture is held.
  int middle(const Made& m) const { return m.motion.motion.frame_count / 2; }

  const Creature person_ = make_creature(BodyPlan::Biped, 12);
};

TEST_F(BipedGestures, WavingRaisesTheNamedHandAndSwingsIt) {
  const Made right = make(Action::Wave, Side::Right);
  const int t = middle(right);
  EXPECT_GT(right.pose.position(t, hand(Side::Right)).y(), right.pose.position(t, shoulder(Side::Right)).y());
  EXPECT_LT(right.pose.position(t, hand(Side::Left)).y(), right.pose.position(t, shoulder(Side::Left)).y());
  // The raised hand swings from side to side: its lateral range over the held part is a real wave.
  double low = 1e9, high = -1e9;
  for (int f = t - 15; f <= t + 15; ++f) {
    const double x = right.pose.position(f, hand(Side::Right)).x();
    low = std::min(low, x);
    high = std::max(high, x);
  }
  EXPECT_GT(high - low, 0.1 * person_.leg_length);
  // Both hands when no side is named; at the start and end both are down.
  const Made both = make(Action::Wave, Side::None);
  for (Side side : {Side::Left, Side::Right}) {
    EXPECT_GT(both.pose.position(t, hand(side)).y(), both.pose.position(t, shoulder(side)).y());
    EXPECT_LT(both.pose.position(0, hand(side)).y(), both.pose.position(0, shoulder(side)).y());
  }
}

TEST_F(BipedGestures, RaisedHandsArePointingAndClappingHandsGoWhereTheySay) {
  const Made raised = make(Action::RaiseHands, Side::Left);
  const int t = middle(raised);
  EXPECT_GT(raised.pose.position(t, hand(Side::Left)).y(), raised.pose.position(t, head()).y());
  EXPECT_LT(raised.pose.position(t, hand(Side::Right)).y(), raised.pose.position(t, shoulder(Side::Right)).y());

  const Made pointing = make(Action::Point, Side::Right);
  const Vec3 reach = pointing.pose.position(t, hand(Side::Right)) - pointing.pose.position(t, shoulder(Side::Right));
  EXPECT_GT(reach.z(), 2.0 * std::abs(reach.y())) << "the arm points ahead, level";
  EXPECT_GT(reach.z(), 0.3 * person_.leg_length);

  const Made clapping = make(Action::Clap, Side::None);
  double closest = 1e9, widest = 0.0;
  for (int f = t - 20; f <= t + 20; ++f) {
    const double gap = (clapping.pose.position(f, hand(Side::Left)) - clapping.pose.position(f, hand(Side::Right))).norm();
    closest = std::min(closest, gap);
    widest = std::max(widest, gap);
  }
  const double shoulders =
      (clapping.pose.position(0, shoulder(Side::Left)) - clapping.pose.position(0, shoulder(Side::Right))).norm();
  EXPECT_LT(closest, 0.5 * shoulders) << "the hands meet";
  EXPECT_GT(widest, closest + 0.3 * shoulders) << "and part again";
}

TEST_F(BipedGestures, BowCrouchAndKickMoveTheBodyOnPlantedFeet) {
  const Made bow = make(Action::Bow, Side::None);
  const int last = bow.motion.motion.frame_count - 1;
  double lowest_head = 1e9;
  for (int f = 0; f <= last; ++f) lowest_head = std::min(lowest_head, bow.pose.position(f, head()).y());
  const double standing_head = bow.pose.position(0, head()).y();
  EXPECT_LT(lowest_head, standing_head - 0.2 * person_.leg_length) << "the head goes down";
  EXPECT_NEAR(bow.pose.position(last, head()).y(), standing_head, 0.05 * person_.leg_length) << "and up again";
  EXPECT_LT(foot_stats(person_, bow.motion).max_slip, kSlipTolerance * person_.leg_length);

  const Made crouch = make(Action::Crouch, Side::None);
  EXPECT_LT(crouch.pose.position(last, 0).y(), crouch.pose.position(0, 0).y() - 0.2 * person_.leg_length);
  EXPECT_LT(foot_stats(person_, crouch.motion).max_height, kGroundTolerance * person_.leg_length);

  const Made kick = make(Action::Kick, Side::Left);
  double highest = 0.0, furthest = 0.0;
  for (int f = 0; f <= last; ++f) {
    const Vec3 p = kick.pose.position(f, foot(Side::Left)) - kick.pose.position(f, 0);
    highest = std::max(highest, kick.pose.position(f, foot(Side::Left)).y());
    furthest = std::max(furthest, p.z());
  }
  EXPECT_GT(highest, 0.4 * person_.leg_length) << "the kicking foot rises towards hip height";
  EXPECT_GT(furthest, 0.5 * person_.leg_length) << "in front of the body";
  for (const LegTrack& leg : kick.motion.legs) {
    const bool kicking = person_.limbs[leg.limb].side == Side::Left;
    const int stance = static_cast<int>(std::count(leg.stance.begin(), leg.stance.end(), 1));
    if (kicking) {
      EXPECT_LT(stance, last) << "the kicking leg leaves the ground";
    } else {
      EXPECT_EQ(stance, last + 1) << "the standing leg stays planted";
    }
  }
}

// Jumping jacks: the feet hop apart with the hands over the head, and back together; stretching puts both hands
// above the head; dancing lifts each foot in turn and sways the hips from side to side.
TEST_F(BipedGestures, JumpingJacksStretchAndDance) {
  const Made jacks = make(Action::JumpingJacks, Side::None);
  const int last = jacks.motion.motion.frame_count - 1;
  const auto feet_apart = [&](const Made& m, int f) {
    return std::abs(m.pose.position(f, foot(Side::Left)).x() - m.pose.position(f, foot(Side::Right)).x());
  };
  const double together = feet_apart(jacks, 0);
  int spread_frames = 0, overhead_while_spread = 0;
  for (int f = 0; f <= last; ++f) {
    if (feet_apart(jacks, f) < together + 0.4 * person_.leg_length) continue;
    ++spread_frames;
    const bool overhead = jacks.pose.position(f, hand(Side::Left)).y() > jacks.pose.position(f, head()).y() &&
                          jacks.pose.position(f, hand(Side::Right)).y() > jacks.pose.position(f, head()).y();
    overhead_while_spread += overhead;
  }
  EXPECT_GT(spread_frames, 10) << "the feet land apart";
  EXPECT_GT(overhead_while_spread, spread_frames / 2) << "with the hands over the head";
  EXPECT_NEAR(feet_apart(jacks, last), together, 0.05 * person_.leg_length) << "and end together";
  for (const LegTrack& leg : jacks.motion.legs) {
    EXPECT_EQ(leg.stance, jacks.motion.legs.front().stance) << "both feet hop at once";
  }

  const Made stretch = make(Action::Stretch, Side::None);
  const int t = middle(stretch);
  for (Side side : {Side::Left, Side::Right}) {
    EXPECT_GT(stretch.pose.position(t, hand(side)).y(), stretch.pose.position(t, head()).y());
    EXPECT_LT(stretch.pose.position(last, hand(side)).y(), stretch.pose.position(last, shoulder(side)).y());
  }

  const Made dance = make(Action::Dance, Side::None);
  double low = 1e9, high = -1e9;
  for (int f = 0; f <= last; ++f) {
    low = std::min(low, dance.pose.position(f, 0).x());
    high = std::max(high, dance.pose.position(f, 0).x());
  }
  EXPECT_GT(high - low, 0.08 * person_.leg_length) << "the hips sway";
  for (const LegTrack& leg : dance.motion.legs) {
    EXPECT_GT(std::count(leg.stance.begin(), leg.stance.end(), 0), 10) << "each foot steps";
  }
  EXPECT_LT(foot_stats(person_, dance.motion).max_slip, kSlipTolerance * person_.leg_length);
}

// Shaking off: the body rolls quickly from side to side (several times a second), the feet planted.
TEST(ZooMotion, ShakingRollsTheBodyQuicklyOnPlantedFeet) {
  for (BodyPlan plan : {BodyPlan::Quadruped, BodyPlan::Ungulate, BodyPlan::Bird}) {
    const Creature creature = make_creature(plan, 4);
    const SynthesizedMotion made = synthesize_motion(creature, spec_for(creature, Action::Shake, 1.0, 0.0, 4));
    const Motion& m = made.motion;
    int crossings = 0;
    double largest = 0.0, previous = 0.0;
    for (int f = 0; f < m.frame_count; ++f) {
      const Vec3 left = m.rotation(f, 0) * Vec3::UnitX();  // the body's left axis: tilted up or down by a roll
      const double roll = std::asin(std::clamp(left.y(), -1.0, 1.0));
      largest = std::max(largest, std::abs(roll));
      if (f > 0 && (roll > 0.0) != (previous > 0.0) && std::abs(roll - previous) > 1e-6) ++crossings;
      previous = roll;
    }
    EXPECT_GT(largest, 8.0 * kPi / 180.0) << body_plan_name(plan);
    EXPECT_GE(crossings, 6) << body_plan_name(plan) << ": several shakes";
    EXPECT_LT(foot_stats(creature, made).max_slip, kSlipTolerance * creature.leg_length) << body_plan_name(plan);
  }
}

// Tail secondary motion lags: the phase of the tail tip's sway trails the base's.
TEST(ZooMotion, TailSwaysWithPhaseLag) {
  const Creature creature = make_creature(BodyPlan::Dragon, 1);
  const Limb* tail = creature.limbs_of(LimbKind::Tail).at(0);
  ASSERT_GE(tail->joints.size(), 4u);
  const SynthesizedMotion made = synthesize_motion(creature, spec_for(creature, Action::Walk, 1.0, 0.0, 1));
  const Pose pose = forward_kinematics(creature.skeleton, made.motion);
  const double rate = made.gait_frequency;
  auto phase = [&](int joint) {  // phase of the global yaw at the gait frequency
    double s = 0, c = 0;
    for (int t = 0; t < made.motion.frame_count; ++t) {
      const double yaw = yaw_of(pose.rotation(t, joint) * pose.rotation(t, 0).conjugate());
      const double w = 2 * kPi * rate * t / made.motion.fps;
      s += yaw * std::sin(w);
      c += yaw * std::cos(w);
    }
    return std::atan2(c, s);
  };
  // Each joint trails the one before it; the tip trails the base by less than half a cycle.
  double previous = phase(tail->joints[0]), total = 0.0;
  for (size_t k = 1; k < tail->joints.size(); ++k) {
    const double current = phase(tail->joints[k]);
    const double step = std::remainder(previous - current, 2 * kPi);
    EXPECT_GT(step, 0.0) << "tail joint " << k << " leads the joint before it";
    total += step;
    previous = current;
  }
  std::printf("tail sway phase lag base -> tip: %.2f rad over %zu joints\n", total, tail->joints.size());
  EXPECT_GT(total, 0.8);
  EXPECT_LT(total, kPi);
}

// ---- files -----------------------------------------------------------------

// Every action of every plan survives BVH text and the unified preprocessing
// (no rejection, +Y stays up).
TEST(ZooMotion, ClipsSurviveBvhAndPreprocessing) {
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed : {0, 1}) {
      const Creature creature = make_creature(plan, seed);
      EXPECT_GE(creature.skeleton.joint_count(), 7);
      EXPECT_LE(creature.skeleton.joint_count(), 140);
      for (Action action : supported_actions(plan)) {
        MotionSpec spec = spec_for(creature, action, 1.0, seed ? 40.0 : 0.0, seed);
        spec.seconds = 2.0;
        const SynthesizedMotion made = synthesize_motion(creature, spec);
        const std::string name = std::string(body_plan_name(plan)) + "_" + std::string(action_name(action));
        const Clip back = parse_bvh(format_bvh(creature.skeleton, made.motion), name);
        ASSERT_EQ(back.motion.frame_count, made.motion.frame_count);
        const double error = testing::max_position_difference(forward_kinematics(back.skeleton, back.motion).positions,
                                                              forward_kinematics(creature.skeleton, made.motion).positions);
        EXPECT_LT(error, 1e-3 * creature.body_length) << name << ": BVH round trip moved a joint by " << error;
        const PreparedClip prepared = preprocess(back, name);
        EXPECT_TRUE(prepared.report.accepted()) << name << ": " << prepared.report.rejection;
        for (const std::string& change : prepared.report.changes) {
          EXPECT_EQ(change.find("up axis"), std::string::npos) << name << ": " << change;
        }
      }
    }
  }
}

// `nec demo` makes a small zoo: 9 creatures x 4 clips of 4 s at 30 fps.
TEST(ZooMotion, GenerationIsFast) {
  const auto start = std::chrono::steady_clock::now();
  int frames = 0;
  for (int i = 0; i < 9; ++i) {
    const BodyPlan plan = kAllBodyPlans[i];
    const Creature creature = make_creature(plan, 100 + i);
    const std::vector<Action> actions = supported_actions(plan);
    for (int k = 0; k < 4; ++k) {
      const Action action = actions[(k + 1) % actions.size()];
      frames += synthesize_motion(creature, spec_for(creature, action, 1.0, 20.0, k)).motion.frame_count;
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("36 clips (%d frames) in %.3f s\n", frames, seconds);
  EXPECT_EQ(frames, 36 * 120);
  EXPECT_LT(seconds, 10.0);
}

}  // namespace
}  // namespace nec::zoo
