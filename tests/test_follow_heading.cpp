// Heading following on motion whose truth is known: a zoo walk that drifts off
// its source's heading is turned back onto it, a walk turned away rigidly comes
// back to the source exactly (up to where it stands), a body turned away from
// its path and a path bent away from its body are each steered back, turns of
// the source are taken over, a body's own sway is kept, and nothing below the
// root changes.
#include "nec/fitting/follow_heading.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"
#include "nec/corpus/segment.h"
#include "nec/fitting/transfer_check.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace nec {
namespace {

// A 5-s zoo walk turning at `turn_rate` degrees per second (+ = left), +Y up, facing +Z at frame 0.
Clip zoo_walk(zoo::BodyPlan plan, double turn_rate) {
  const zoo::Creature creature = zoo::make_creature(plan, 5);
  zoo::MotionSpec spec;
  spec.action = zoo::Action::Walk;
  spec.speed = zoo::typical_speed(creature, zoo::Action::Walk);
  spec.turn_rate = turn_rate;
  spec.seconds = 5.0;
  return preprocess(Clip{creature.skeleton, zoo::synthesize_motion(creature, spec).motion, {}}, "walk.bvh").clip;
}

double largest_heading_difference(const Clip& a, const Clip& b) {
  const std::vector<double> ha = measure_kinematics(a).heading, hb = measure_kinematics(b).heading;
  double largest = 0.0;
  for (size_t t = 0; t < ha.size(); ++t) largest = std::max(largest, std::abs(ha[t] - hb[t]));
  return largest;
}

void expect_same_below_the_root(const Motion& a, const Motion& b) {
  for (int t = 0; t < a.frame_count; ++t) {
    for (int j = 1; j < a.joint_count; ++j) {
      ASSERT_TRUE(a.rotation(t, j).coeffs() == b.rotation(t, j).coeffs()) << "frame " << t << " joint " << j;
      ASSERT_TRUE(a.translation(t, j) == b.translation(t, j)) << "frame " << t << " joint " << j;
    }
  }
}

TEST(FollowHeading, AWalkThatDriftsIsTurnedBackOntoItsSourcesHeading) {
  for (const zoo::BodyPlan plan : {zoo::BodyPlan::Biped, zoo::BodyPlan::Quadruped, zoo::BodyPlan::Hexapod}) {
    const Clip source = zoo_walk(plan, 0.0);
    Clip output = zoo_walk(plan, -8.0);  // the same walk drifting right by 40° over its 5 s
    const Motion drifted = output.motion;
    const MotionMeasurements before = measure_motion(output);
    const HeadingReport report = follow_heading(source, output.skeleton, output.motion);
    const MotionMeasurements after = measure_motion(output), wanted = measure_motion(source);
    std::printf("%-9s heading change %.1f -> %.1f (source %.1f), largest difference %.1f -> %.1f deg, "
                "turned %.1f on average, %.1f at most; speed %.3f -> %.3f; skate %.3f -> %.3f\n",
                std::string(zoo::body_plan_name(plan)).c_str(), before.heading_change, after.heading_change,
                wanted.heading_change, largest_heading_difference(source, Clip{output.skeleton, drifted, {}}),
                largest_heading_difference(source, output), report.mean_turn, report.max_turn, before.speed,
                after.speed, before.gait.skate, after.gait.skate);
    EXPECT_LT(before.heading_change, -30.0);
    EXPECT_NEAR(after.heading_change, wanted.heading_change, 3.0);
    EXPECT_LT(largest_heading_difference(source, output), 3.5);
    EXPECT_NEAR(report.max_turn, 40.0, 6.0);
    // The path bends with the body: the walk goes where the source went (a curved quadruped's facing,
    // from its hips and shoulders, and its root's path are 3° apart).
    EXPECT_NEAR(after.travel_direction, wanted.travel_direction, 4.0);
    EXPECT_NEAR(after.speed, before.speed, 1e-3 * before.speed);
    // Turning the body at 8°/s swings its planted feet a little (the foot lock pins them afterwards).
    EXPECT_LT(after.gait.skate, before.gait.skate + 0.06);
    expect_same_below_the_root(output.motion, drifted);
  }
}

TEST(FollowHeading, TheSourcesTurnsAreTakenOver) {
  const Clip source = zoo_walk(zoo::BodyPlan::Quadruped, 30.0);
  Clip output = zoo_walk(zoo::BodyPlan::Quadruped, 0.0);
  follow_heading(source, output.skeleton, output.motion);
  EXPECT_NEAR(measure_motion(output).heading_change, measure_motion(source).heading_change, 5.0);
  EXPECT_LT(largest_heading_difference(source, output), 8.0);
}

TEST(FollowHeading, AWalkTurnedAwayRigidlyComesBackToItsSource) {
  const Clip source = zoo_walk(zoo::BodyPlan::Biped, 10.0);
  Clip output = source;
  transform_clip(output, axis_rotation(1, 25.0), 1.0, Vec3::Zero());
  const HeadingReport report = follow_heading(source, output.skeleton, output.motion);
  EXPECT_NEAR(report.mean_turn, 25.0, 1e-6);
  EXPECT_NEAR(report.max_turn, 25.0, 1e-6);
  // Turned back about its first root position: every joint is where the source's is, shifted by one offset.
  const Pose a = forward_kinematics(source.skeleton, source.motion), b = forward_kinematics(output.skeleton, output.motion);
  const Vec3 shift = b.position(0, 0) - a.position(0, 0);
  for (size_t i = 0; i < a.positions.size(); ++i) ASSERT_LT((b.positions[i] - a.positions[i] - shift).norm(), 1e-9);
}

// The walk with its body turned by `body_degrees` and its path bent by `path_degrees`, both growing
// linearly from 0 at frame 0 to the given angle at the last frame (+ = left).
Clip bent(const Clip& walk, double body_degrees, double path_degrees) {
  Clip out = walk;
  const int frames = walk.motion.frame_count;
  for (int t = 0; t < frames; ++t) {
    const double share = static_cast<double>(t) / (frames - 1);
    out.motion.rotation(t, 0) = axis_rotation(1, share * body_degrees) * walk.motion.rotation(t, 0);
    if (t > 0) {
      out.motion.translation(t, 0) =
          out.motion.translation(t - 1, 0) +
          axis_rotation(1, share * path_degrees) * (walk.motion.translation(t, 0) - walk.motion.translation(t - 1, 0));
    }
  }
  return out;
}

double largest_root_distance(const Clip& a, const Clip& b) {
  double largest = 0.0;
  for (int t = 0; t < a.motion.frame_count; ++t) {
    largest = std::max(largest, (a.motion.translation(t, 0) - b.motion.translation(t, 0)).norm());
  }
  return largest / a.skeleton.diameter();
}

TEST(FollowHeading, BodyAndPathAreSteeredEachOnItsOwn) {
  const Clip source = zoo_walk(zoo::BodyPlan::Biped, 0.0);
  // A body that turns away while its path goes straight on (decoded human walks do), and a path that bends
  // away under a body that keeps facing ahead.
  for (const auto& [body, path] : std::vector<std::pair<double, double>>{{-30.0, 0.0}, {0.0, -30.0}}) {
    Clip output = bent(source, body, path);
    const double path_off = largest_root_distance(source, output);
    const double facing_off = largest_heading_difference(source, output);
    const HeadingReport report = follow_heading(source, output.skeleton, output.motion);
    std::printf("body %+.0f, path %+.0f: root off by %.3f -> %.4f sizes, facing by %.1f -> %.2f deg; turned body "
                "%.1f, path %.1f at most\n",
                body, path, path_off, largest_root_distance(source, output), facing_off,
                largest_heading_difference(source, output), report.max_turn, report.max_path_turn);
    EXPECT_LT(largest_root_distance(source, output), 0.01);
    EXPECT_LT(largest_heading_difference(source, output), 0.5);
    EXPECT_NEAR(report.max_turn, std::abs(body), 1.0);
    EXPECT_NEAR(report.max_path_turn, std::abs(path), 1.0);
  }
}

TEST(FollowHeading, AMotionThatAlreadyFollowsKeepsItsSway) {
  // The same walk: its facing sways step by step and nothing is turned.
  const Clip source = zoo_walk(zoo::BodyPlan::Biped, 0.0);
  Clip output = source;
  const HeadingReport report = follow_heading(source, output.skeleton, output.motion);
  EXPECT_EQ(report.max_turn, 0.0);
  for (int t = 0; t < output.motion.frame_count; ++t) {
    ASSERT_TRUE(output.motion.translation(t, 0) == source.motion.translation(t, 0)) << "frame " << t;
  }
  const std::vector<double> heading = measure_kinematics(source).heading;
  const auto [low, high] = std::minmax_element(heading.begin(), heading.end());
  EXPECT_GT(*high - *low, 1.0) << "the biped's walk should sway";
}

TEST(FollowHeading, MismatchedClipsAndBadOptionsThrow) {
  const Clip source = zoo_walk(zoo::BodyPlan::Biped, 0.0);
  Clip output = source;
  Motion shorter = output.motion.slice(0, output.motion.frame_count - 1);
  EXPECT_THROW(follow_heading(source, output.skeleton, shorter), std::invalid_argument);
  Motion faster = output.motion;
  faster.fps = 60.0;
  EXPECT_THROW(follow_heading(source, output.skeleton, faster), std::invalid_argument);
  const Clip other = zoo_walk(zoo::BodyPlan::Quadruped, 0.0);
  EXPECT_THROW(follow_heading(source, other.skeleton, output.motion), std::invalid_argument);
  HeadingOptions no_window;
  no_window.smoothing_seconds = 0.0;
  EXPECT_THROW(follow_heading(source, output.skeleton, output.motion, no_window), std::invalid_argument);
  HeadingOptions never_still;
  never_still.still_speed = -1.0;
  EXPECT_THROW(follow_heading(source, output.skeleton, output.motion, never_still), std::invalid_argument);
}

}  // namespace
}  // namespace nec
