// Transfer checks on zoo motion whose truth is known: speed, turning, direction,
// foot plants in the gait's rhythm, bone lengths, the distance between clips on
// one skeleton; and what a broken transfer (frozen root, stretched bone) looks
// like.
#include "nec/motion/bvh.h"
#include "nec/corpus/preprocess.h"
#include "nec/fitting/transfer_check.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace nec {
namespace {

struct Walk {
  Clip clip;  // preprocessed: +Y up, frame 0 facing +Z, diameter 1
  zoo::Creature creature;
  zoo::SynthesizedMotion synthesized;
};

Walk walk(zoo::BodyPlan plan, double turn_rate = 0.0) {
  Walk w;
  w.creature = zoo::make_creature(plan, 11);
  zoo::MotionSpec spec;
  spec.action = zoo::Action::Walk;
  spec.speed = zoo::typical_speed(w.creature, zoo::Action::Walk);
  spec.turn_rate = turn_rate;
  spec.seconds = 4.0;
  w.synthesized = zoo::synthesize_motion(w.creature, spec);
  w.clip = preprocess(Clip{w.creature.skeleton, w.synthesized.motion, {}}, "walk.bvh").clip;
  return w;
}

TEST(TransferCheck, WalkingCreaturesTravelForwardAndPlantTheirFeetInTheGaitRhythm) {
  for (const zoo::BodyPlan plan : {zoo::BodyPlan::Biped, zoo::BodyPlan::Quadruped, zoo::BodyPlan::Spider}) {
    const Walk w = walk(plan);
    const MotionMeasurements m = measure_motion(w.clip);
    const double legs = static_cast<double>(w.synthesized.legs.size());
    const double expected_touchdowns = legs * w.synthesized.gait_frequency;
    // Body lengths per second -> body sizes (diameters) per second.
    const double expected_speed =
        w.synthesized.spec.speed * w.creature.body_length / w.creature.skeleton.diameter();
    std::printf("%-9s turn %.1f speed %.3f (spec %.3f) dir %.1f  feet %d/%g  touchdowns/s %.2f (gait %.2f)  contact %.2f"
                "  skate %.3f\n",
                std::string(zoo::body_plan_name(plan)).c_str(), m.heading_change, m.speed, expected_speed, m.travel_direction,
                m.gait.feet, legs, m.gait.touchdowns_per_second, expected_touchdowns, m.gait.contact_fraction,
                m.gait.skate);
    EXPECT_NEAR(m.speed, expected_speed, 0.2 * expected_speed);
    EXPECT_NEAR(m.travel_direction, 0.0, 10.0);
    EXPECT_NEAR(m.heading_change, 0.0, 5.0);
    EXPECT_GE(m.gait.feet, legs);
    EXPECT_NEAR(m.gait.touchdowns_per_second, expected_touchdowns, 0.3 * expected_touchdowns);
    EXPECT_GT(m.gait.contact_fraction, 0.2);
    EXPECT_LT(m.gait.contact_fraction, 0.95);
    EXPECT_LT(m.bone_length_change, 1e-9);
  }
}

TEST(TransferCheck, TurningWalkChangesHeadingByTheSpecifiedAngle) {
  const Walk w = walk(zoo::BodyPlan::Quadruped, 30.0);
  const double expected = zoo::heading_change_degrees(w.synthesized.spec);
  const MotionMeasurements m = measure_motion(w.clip);
  std::printf("heading change %.1f (spec %.1f), direction %.1f\n", m.heading_change, expected, m.travel_direction);
  EXPECT_NEAR(m.heading_change, expected, 0.15 * std::abs(expected));
  EXPECT_NEAR(m.travel_direction, 0.0, 10.0);  // still forward, relative to the turning body
}

TEST(TransferCheck, AClipCheckedAgainstItselfMatches) {
  const Walk w = walk(zoo::BodyPlan::Biped);
  const TransferCheck check = check_transfer(w.clip, w.clip);
  EXPECT_DOUBLE_EQ(check.speed_ratio, 1.0);
  EXPECT_DOUBLE_EQ(check.heading_difference, 0.0);
  EXPECT_DOUBLE_EQ(check.direction_difference, 0.0);
  EXPECT_DOUBLE_EQ(check.joint_distance, 0.0);
  EXPECT_DOUBLE_EQ(check.floor_difference, 0.0);
  // Joint distance needs one skeleton.
  EXPECT_TRUE(std::isnan(check_transfer(w.clip, walk(zoo::BodyPlan::Quadruped).clip).joint_distance));
}

TEST(TransferCheck, AFrozenRootAndAStretchedBoneShow) {
  const Walk w = walk(zoo::BodyPlan::Biped);
  Clip broken = w.clip;
  for (int t = 0; t < broken.motion.frame_count; ++t) broken.motion.translation(t, 0) = w.clip.motion.translation(0, 0);
  const int joint = broken.skeleton.leaves().front();
  const Vec3 bone = broken.motion.translation(5, joint);
  broken.motion.translation(5, joint) = bone * (1.0 + 0.1 / bone.norm());  // 0.1 body sizes longer
  const TransferCheck check = check_transfer(w.clip, broken);
  EXPECT_LT(check.speed_ratio, 0.05);
  EXPECT_LT(check.output.distance, 1e-9);
  EXPECT_TRUE(std::isnan(check.output.travel_direction));
  EXPECT_TRUE(std::isnan(check.direction_difference));
  EXPECT_NEAR(check.output.bone_length_change, 0.1, 1e-9);
  EXPECT_LT(check.output.gait.touchdowns_per_second, check.source.gait.touchdowns_per_second);
  // Every joint of the frozen clip is off by the distance the root travelled (one bone in one frame aside).
  double travelled = 0.0;
  for (int t = 0; t < w.clip.motion.frame_count; ++t) {
    travelled += (w.clip.motion.translation(t, 0) - w.clip.motion.translation(0, 0)).norm();
  }
  travelled /= w.clip.motion.frame_count * w.clip.skeleton.diameter();
  EXPECT_GT(travelled, 0.5);
  EXPECT_NEAR(check.joint_distance, travelled, 1e-3);
}

// A transfer that floats in one second of its clip: that window's lowest joint, not the others'.
TEST(TransferCheck, ABodyAboveTheFloorShowsInItsWindow) {
  const Walk w = walk(zoo::BodyPlan::Quadruped);
  const double size = w.clip.skeleton.diameter();
  const MotionMeasurements standing = measure_motion(w.clip);
  const int window = static_cast<int>(std::lround(kFloorWindowSeconds * w.clip.motion.fps));
  ASSERT_GE(w.clip.motion.frame_count, 2 * window);
  ASSERT_EQ(standing.lowest_heights.size(), static_cast<size_t>((w.clip.motion.frame_count + window - 1) / window));
  for (double height : standing.lowest_heights) EXPECT_NEAR(height, 0.0, kFloorTolerance);  // the zoo stands on y = 0
  Clip floating = w.clip;
  for (int t = window; t < 2 * window; ++t) floating.motion.translation(t, 0).y() += 0.2 * size;
  const TransferCheck check = check_transfer(w.clip, floating);
  EXPECT_NEAR(check.floor_difference, 0.2, 1e-9);
  EXPECT_NEAR(check.output.lowest_heights[1] - standing.lowest_heights[1], 0.2, 1e-9);
  EXPECT_DOUBLE_EQ(check.output.lowest_heights[0], standing.lowest_heights[0]);
}

// A body that outruns its legs: the planted feet slide, which foot skate shows and touchdowns lose.
TEST(TransferCheck, FeetThatSlideShowAsFootSkate) {
  const Walk w = walk(zoo::BodyPlan::Quadruped);
  Clip sliding = w.clip;
  testing::stretch_root_travel(sliding.motion, 1.8);
  const TransferCheck check = check_transfer(w.clip, sliding);
  std::printf("skate %.3f -> %.3f sizes/s, touchdowns/s %.2f -> %.2f\n", check.source.gait.skate,
              check.output.gait.skate, check.source.gait.touchdowns_per_second, check.output.gait.touchdowns_per_second);
  EXPECT_GT(check.output.gait.skate, 2.0 * check.source.gait.skate);
  EXPECT_LT(check.output.gait.touchdowns_per_second, 0.5 * check.source.gait.touchdowns_per_second);
}

// A person walking (Bandai): forward, although the head leans behind the hips
// (it once turned the facing around).
TEST(TransferCheck, ARealPersonWalksForward) {
  const std::string file = testing::shared_data_dir() + "/bandai/set1/data/dataset-1_walk_normal_001.bvh";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " not found";
  const MotionMeasurements m = measure_motion(preprocess(read_bvh(file), file).clip);
  std::printf("bandai walk: speed %.2f sizes/s, direction %.1f deg, %.2f touchdowns/s\n", m.speed, m.travel_direction,
              m.gait.touchdowns_per_second);
  EXPECT_NEAR(m.travel_direction, 0.0, 15.0);
  EXPECT_GT(m.gait.touchdowns_per_second, 1.0);  // about two steps per second
  EXPECT_LT(m.gait.touchdowns_per_second, 3.0);
}

TEST(TransferCheck, RejectsAClipWithoutFrames) {
  Clip empty;
  empty.skeleton = walk(zoo::BodyPlan::Biped).clip.skeleton;
  empty.motion = Motion::rest(empty.skeleton, 0, 30.0);
  EXPECT_THROW(measure_motion(empty), std::invalid_argument);
}

}  // namespace
}  // namespace nec
