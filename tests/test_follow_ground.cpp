// Ground following on motion whose truth is known: a zoo walk sunk into or
// lifted off the floor comes back to its source's standing level, a slow
// drift of the height is taken out while the body's bounce within a step
// stays, settling brings a sunk or hovering body to the floor and leaves a
// flight alone, and nothing but the root's height changes.
#include "nec/fitting/follow_ground.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

namespace nec {
namespace {

// A 4-s zoo walk, +Y up, standing on y = 0.
Clip zoo_walk(zoo::BodyPlan plan) {
  const zoo::Creature creature = zoo::make_creature(plan, 3);
  zoo::MotionSpec spec;
  spec.action = zoo::Action::Walk;
  spec.speed = zoo::typical_speed(creature, zoo::Action::Walk);
  spec.seconds = 4.0;
  return preprocess(Clip{creature.skeleton, zoo::synthesize_motion(creature, spec).motion, {}}, "walk.bvh").clip;
}

// Height of the lowest joint per frame, body sizes.
std::vector<double> lowest(const Clip& clip) {
  std::vector<Vec3> positions;
  joint_positions(clip.skeleton, clip.motion, positions);
  std::vector<double> out = lowest_joint_heights(positions, clip.motion.joint_count);
  for (double& h : out) h /= clip.skeleton.diameter();
  return out;
}

// Adds `lift(t)` body sizes to the root's height.
void lift(Clip& clip, const std::function<double(int)>& amount) {
  for (int t = 0; t < clip.motion.frame_count; ++t) clip.motion.translation(t, 0).y() += amount(t) * clip.skeleton.diameter();
}

void expect_only_root_height_changed(const Motion& a, const Motion& b) {
  for (int t = 0; t < a.frame_count; ++t) {
    EXPECT_EQ(a.translation(t, 0).x(), b.translation(t, 0).x());
    EXPECT_EQ(a.translation(t, 0).z(), b.translation(t, 0).z());
    for (int j = 0; j < a.joint_count; ++j) ASSERT_TRUE(a.rotation(t, j).coeffs() == b.rotation(t, j).coeffs());
  }
}

TEST(FollowGround, ASunkOrLiftedWalkStandsWhereItsSourceStands) {
  for (const zoo::BodyPlan plan : {zoo::BodyPlan::Biped, zoo::BodyPlan::Quadruped, zoo::BodyPlan::Hexapod}) {
    const Clip source = zoo_walk(plan);
    for (const double offset : {-0.2, 0.08}) {
      Clip output = source;
      lift(output, [&](int) { return offset; });
      const Motion before = output.motion;
      const GroundReport report = follow_ground(source, output.skeleton, output.motion);
      EXPECT_NEAR(report.mean_shift, std::abs(offset), 1e-3);
      const std::vector<double> want = lowest(source), got = lowest(output);
      double largest = 0;
      for (size_t t = 0; t < want.size(); ++t) largest = std::max(largest, std::abs(want[t] - got[t]));
      std::printf("plan %d offset %+.2f: largest height difference after %.2g body sizes\n", static_cast<int>(plan),
                  offset, largest);
      EXPECT_LT(largest, 1e-3);
      expect_only_root_height_changed(before, output.motion);
    }
  }
}

TEST(FollowGround, ASlowDriftGoesAndTheStepsBounceStays) {
  const Clip source = zoo_walk(zoo::BodyPlan::Biped);
  Clip output = source;
  const int frames = output.motion.frame_count;
  lift(output, [&](int t) { return 0.1 * t / (frames - 1); });  // drifts up by 0.1 body sizes over 4 s
  follow_ground(source, output.skeleton, output.motion);
  // The root's own bounce (its height minus a straight line through it) is the source's.
  double largest = 0;
  for (int t = 0; t < frames; ++t) {
    largest = std::max(largest, std::abs(output.motion.translation(t, 0).y() - source.motion.translation(t, 0).y()));
  }
  std::printf("largest root height difference after a drift: %.3g body sizes\n", largest / source.skeleton.diameter());
  // What stays is the standing level's lag: the lowest height over a centred 1-s window of a rising body is
  // the one half a window back, 0.1 / 4 s x 0.5 s = 0.0125 body sizes here (uncorrected, the drift reaches 0.1).
  EXPECT_LT(largest / source.skeleton.diameter(), 0.015);
}

TEST(FollowGround, SettlingFindsTheFloorAndLeavesAFlightAlone) {
  const Clip walk = zoo_walk(zoo::BodyPlan::Quadruped);
  Clip sunk = walk, flying = walk;
  lift(sunk, [](int) { return -0.05; });
  lift(flying, [](int) { return 0.5; });
  const std::vector<double> walk_heights = lowest(walk);
  const double standing = *std::min_element(walk_heights.begin(), walk_heights.end());
  const GroundReport settled = settle_on_ground(sunk.skeleton, sunk.motion);
  const GroundReport flight = settle_on_ground(flying.skeleton, flying.motion);
  const std::vector<double> heights = lowest(sunk);
  std::printf("walk stands at %.4f body sizes; sunk by 0.05, settled: lowest %.4f, shift %.4f\n", standing,
              *std::min_element(heights.begin(), heights.end()), settled.mean_shift);
  EXPECT_NEAR(*std::min_element(heights.begin(), heights.end()), 0.0, 2e-3);
  EXPECT_NEAR(settled.mean_shift, 0.05 + standing, 2e-3);
  EXPECT_EQ(flight.max_shift, 0.0);

  GroundOptions bad;
  bad.window_seconds = 0.0;
  EXPECT_THROW(settle_on_ground(walk.skeleton, sunk.motion, bad), std::invalid_argument);
  Clip short_clip = walk;
  short_clip.motion.frame_count = 3;
  EXPECT_THROW(follow_ground(short_clip, sunk.skeleton, sunk.motion), std::invalid_argument);
}

}  // namespace
}  // namespace nec
