// Foot locking on motion whose truth is known: zoo walks whose bodies outrun
// their legs (the feet slide) get their plants back; a hand-built leg is
// pinned exactly, fades in and out, and nothing else moves.
#include "nec/fitting/foot_lock.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"
#include "nec/fitting/transfer_check.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace nec {
namespace {

// A walk whose root goes `outrun` times as far as the legs carry it: the planted feet slide.
Clip sliding_walk(zoo::BodyPlan plan, double outrun, zoo::SynthesizedMotion& synthesized) {
  const zoo::Creature creature = zoo::make_creature(plan, 11);
  zoo::MotionSpec spec;
  spec.action = zoo::Action::Walk;
  spec.speed = zoo::typical_speed(creature, zoo::Action::Walk);
  spec.seconds = 4.0;
  synthesized = zoo::synthesize_motion(creature, spec);
  Clip clip = preprocess(Clip{creature.skeleton, synthesized.motion, {}}, "walk.bvh").clip;
  testing::stretch_root_travel(clip.motion, outrun);
  return clip;
}

TEST(FootLock, WalksWhoseFeetSlideGetTheirPlantsBack) {
  for (const zoo::BodyPlan plan : {zoo::BodyPlan::Biped, zoo::BodyPlan::Quadruped, zoo::BodyPlan::Spider}) {
    zoo::SynthesizedMotion synthesized;
    Clip clip = sliding_walk(plan, 1.8, synthesized);
    const MotionMeasurements before = measure_motion(clip);
    const Motion slid = clip.motion;
    const FootLockReport report = lock_feet(clip.skeleton, clip.motion);
    const MotionMeasurements after = measure_motion(clip);
    const double legs = static_cast<double>(synthesized.legs.size());
    const double expected_touchdowns = legs * synthesized.gait_frequency;
    std::printf("%-9s feet %d, %d plants, slide %.3f sizes/s, miss %.4f; touchdowns/s %.2f -> %.2f (gait %.2f), "
                "skate %.3f -> %.3f\n",
                std::string(zoo::body_plan_name(plan)).c_str(), report.feet, report.planted_spans, report.mean_slide,
                report.max_miss, before.gait.touchdowns_per_second, after.gait.touchdowns_per_second,
                expected_touchdowns, before.gait.skate, after.gait.skate);
    EXPECT_LT(before.gait.touchdowns_per_second, 0.5 * expected_touchdowns) << "the slide should hide the plants";
    EXPECT_EQ(report.feet, static_cast<int>(legs));
    EXPECT_NEAR(after.gait.touchdowns_per_second, expected_touchdowns, 0.3 * expected_touchdowns);
    EXPECT_LT(after.gait.skate, 0.6 * before.gait.skate);
    // Legs cannot reach all of a pin that the body outran by 80 %: the ends of the plants fall short.
    EXPECT_LT(report.max_miss, 0.2);
    EXPECT_LT(after.bone_length_change, 1e-9);
    // The body goes where it went.
    EXPECT_NEAR(after.speed, before.speed, 1e-12);
    for (int t = 0; t < clip.motion.frame_count; ++t) {
      ASSERT_TRUE(clip.motion.translation(t, 0) == slid.translation(t, 0));
      ASSERT_TRUE(clip.motion.rotation(t, 0).coeffs() == slid.rotation(t, 0).coeffs());
    }
  }
}

TEST(FootLock, AWalkWhoseFeetArePlantedStaysNearlyAsItIs) {
  zoo::SynthesizedMotion synthesized;
  Clip clip = sliding_walk(zoo::BodyPlan::Quadruped, 1.0, synthesized);
  const Pose before = forward_kinematics(clip.skeleton, clip.motion);
  lock_feet(clip.skeleton, clip.motion);
  const Pose after = forward_kinematics(clip.skeleton, clip.motion);
  double largest = 0.0;
  for (size_t i = 0; i < before.positions.size(); ++i) {
    largest = std::max(largest, (before.positions[i] - after.positions[i]).norm());
  }
  EXPECT_LT(largest / clip.skeleton.diameter(), 0.03);  // a slower pin's fade moved feet by 0.09
}

// Hips, and one leg per side: upper leg, lower leg (the knee), foot, toe (the leaf). Diameter 2.
Skeleton two_legs() {
  Skeleton s;
  const ChannelLayout rotations = ChannelLayout::rotations(EulerOrder::ZXY);
  s.add_joint("Hips", -1, Vec3::Zero(), ChannelLayout::position_rotations(EulerOrder::ZXY));
  for (const double side : {1.0, -1.0}) {
    const int upper = s.add_joint(side > 0 ? "LeftUpLeg" : "RightUpLeg", 0, Vec3(0.1 * side, 0.0, 0.0), rotations);
    const int lower = s.add_joint(side > 0 ? "LeftLeg" : "RightLeg", upper, Vec3(0.0, -0.45, 0.0), rotations);
    const int foot = s.add_joint(side > 0 ? "LeftFoot" : "RightFoot", lower, Vec3(0.0, -0.45, 0.0), rotations);
    s.add_joint(side > 0 ? "LeftToe" : "RightToe", foot, Vec3(0.0, -0.05, 0.1), rotations);
  }
  return s;
}

// The hips move forward 0.004 a frame (0.12 a second at 30 fps); both knees bend by 40°. The left leg hangs
// from the hips, its toe sliding along the floor, during frames [plant_begin, plant_end) and is lifted
// 50° further forward otherwise; the right leg is lifted all along.
Motion hand_walk(const Skeleton& s, int frames, int plant_begin, int plant_end) {
  Motion m = Motion::rest(s, frames, 30.0);
  const auto about_x = [](double degrees) { return Quat(Eigen::AngleAxisd(degrees * M_PI / 180.0, Vec3::UnitX())); };
  for (int t = 0; t < frames; ++t) {
    m.translation(t, 0) = Vec3(0.0, 0.9, 0.004 * t);
    m.rotation(t, s.find("LeftLeg")) = about_x(40.0);
    m.rotation(t, s.find("RightLeg")) = about_x(40.0);
    m.rotation(t, s.find("LeftUpLeg")) = about_x(t >= plant_begin && t < plant_end ? -10.0 : -60.0);
    m.rotation(t, s.find("RightUpLeg")) = about_x(-60.0);
  }
  return m;
}

TEST(FootLock, APlantedFootIsPinnedAtItsMedianPositionAndTheShiftFadesOut) {
  const Skeleton s = two_legs();
  const int frames = 40;
  const Motion slid = hand_walk(s, frames, 8, 32);
  // The toe jumps down at frame 8 and up at 32: the speed there (centred differences) is no plant's.
  const int begin = 9, end = 31;
  Motion locked = slid;
  FootLockOptions options;
  options.blend_frames = 4;
  const FootLockReport report = lock_feet(s, locked, options);
  EXPECT_EQ(report.feet, 1);
  EXPECT_EQ(report.planted_spans, 1);
  EXPECT_NEAR(report.mean_slide, 0.12 / s.diameter(), 1e-9);
  EXPECT_LT(report.max_miss, 1e-9);

  const int toe = s.find("LeftToe");
  const Pose before = forward_kinematics(s, slid), after = forward_kinematics(s, locked);
  // The toe slides at a constant speed: its median position is its mean, halfway.
  const Vec3 pin = 0.5 * (before.position(begin, toe) + before.position(end - 1, toe));
  for (int t = begin; t < end; ++t) EXPECT_LT((after.position(t, toe) - pin).norm(), 1e-9) << "frame " << t;
  // Fading: 4/5 of the shift at the plant's nearer end one frame out, 1/5 four frames out, nothing five out.
  for (const auto& [t, weight] : std::vector<std::pair<int, double>>{
           {begin - 1, 0.8}, {begin - 4, 0.2}, {end, 0.8}, {end + 3, 0.2}}) {
    const Vec3 shift = pin - before.position(t < begin ? begin : end - 1, toe);
    const Vec3 wanted = before.position(t, toe) + weight * shift;
    EXPECT_LT((after.position(t, toe) - wanted).norm(), 1e-9) << "frame " << t;
  }
  for (const int t : {0, begin - 5, end + 4, frames - 1}) {
    for (int j = 0; j < s.joint_count(); ++j) {
      EXPECT_TRUE(locked.rotation(t, j).coeffs() == slid.rotation(t, j).coeffs()) << "frame " << t << " joint " << j;
    }
  }
  // Only the left hip and knee turn; the foot keeps its rotation against the lower leg.
  for (int t = 0; t < frames; ++t) {
    for (const char* name : {"Hips", "LeftFoot", "LeftToe", "RightUpLeg", "RightLeg", "RightFoot", "RightToe"}) {
      const int j = s.find(name);
      EXPECT_TRUE(locked.rotation(t, j).coeffs() == slid.rotation(t, j).coeffs()) << name << " frame " << t;
    }
    for (int j = 0; j < s.joint_count(); ++j) EXPECT_TRUE(locked.translation(t, j) == slid.translation(t, j));
  }
}

TEST(FootLock, FastFeetAndFeetInTheAirAreLeftAlone) {
  const Skeleton s = two_legs();
  Motion lifted = hand_walk(s, 30, 0, 0);  // both legs lifted all along
  const Motion before = lifted;
  // The floor is then the lifted toes' own height: what is lowest is planted if it is slow ...
  FootLockOptions options;
  options.contact_speed = 0.03;  // ... and the hips' 0.12 a second (0.05 sizes/s) is faster than this
  const FootLockReport report = lock_feet(s, lifted, options);
  EXPECT_EQ(report.feet, 0);
  for (size_t i = 0; i < before.rotations.size(); ++i) {
    EXPECT_TRUE(lifted.rotations[i].coeffs() == before.rotations[i].coeffs());
  }
}

TEST(FootLock, RejectsBadOptionsAndAMotionOfAnotherSkeleton) {
  const Skeleton s = two_legs();
  Motion m = hand_walk(s, 10, 0, 10);
  FootLockOptions bad;
  bad.contact_height = 0.0;
  EXPECT_THROW(lock_feet(s, m, bad), std::invalid_argument);
  bad = FootLockOptions{};
  bad.min_plant_frames = 0;
  EXPECT_THROW(lock_feet(s, m, bad), std::invalid_argument);
  Motion other = Motion::rest(s, 10, 30.0);
  other.joint_count = 3;
  EXPECT_THROW(lock_feet(s, other, {}), std::invalid_argument);
}

}  // namespace
}  // namespace nec
