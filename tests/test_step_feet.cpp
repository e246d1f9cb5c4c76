// Stepping after a source, on zoo walks whose gait is known: a target whose legs hold still while its body
// travels (feet gliding, as decoded transfers come out) steps in the source's cadence, in the order of its
// body plan; a target that already steps, or the source of a standing motion, changes nothing.
#include "nec/fitting/step_feet.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"
#include "nec/fitting/transfer_check.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace nec {
namespace {

Clip synthesized_clip(zoo::BodyPlan plan, zoo::Action action, zoo::SynthesizedMotion* synthesized = nullptr) {
  const zoo::Creature creature = zoo::make_creature(plan, 11);
  zoo::MotionSpec spec;
  spec.action = action;
  spec.speed = action == zoo::Action::Idle ? 0.0 : zoo::typical_speed(creature, action);
  spec.seconds = 4.0;
  zoo::SynthesizedMotion made = zoo::synthesize_motion(creature, spec);
  Clip clip = preprocess(Clip{creature.skeleton, made.motion, {}}, "clip.bvh").clip;
  if (synthesized != nullptr) *synthesized = std::move(made);
  return clip;
}

// The walk with every joint but the root held at its rest (the clip's mean pose after preprocessing): the
// body travels, the feet glide with it.
Clip gliding(Clip clip) {
  for (int t = 0; t < clip.motion.frame_count; ++t) {
    for (int j = 1; j < clip.motion.joint_count; ++j) clip.motion.rotation(t, j) = Quat::Identity();
  }
  return clip;
}

// A leaf that touches down (by the transfer check's contact rule): its touchdown frames, and where it sits
// on the body (mean offset from the root; preprocessing faces the walk along +Z, so +X is left).
struct Foot {
  std::vector<int> touchdowns;
  double left = 0.0, forward = 0.0;
};

std::vector<Foot> feet_of(const Clip& clip) {
  std::vector<Vec3> positions;
  joint_positions(clip.skeleton, clip.motion, positions);
  const int frames = clip.motion.frame_count, joints = clip.motion.joint_count;
  const double floor = lowest_height(positions);
  std::vector<Foot> out;
  for (const int leaf : clip.skeleton.leaves()) {
    Foot foot;
    foot.touchdowns = touchdown_frames(
        contact_frames(positions, joints, leaf, floor, clip.skeleton.diameter(), clip.motion.fps));
    if (foot.touchdowns.empty()) continue;
    for (int t = 0; t < frames; ++t) {
      const Vec3 offset = positions[static_cast<size_t>(t) * joints + leaf] - positions[static_cast<size_t>(t) * joints];
      foot.left += offset.x() / frames;
      foot.forward += offset.z() / frames;
    }
    out.push_back(std::move(foot));
  }
  return out;
}

// The first touchdown of `foot` at or after frame t.
int touchdown_from(const Foot& foot, int t) {
  const auto found = std::lower_bound(foot.touchdowns.begin(), foot.touchdowns.end(), t);
  return found == foot.touchdowns.end() ? std::numeric_limits<int>::max() : *found;
}

TEST(StepFeet, GlidingFeetStepInTheSourcesCadence) {
  zoo::SynthesizedMotion biped;
  const Clip source = synthesized_clip(zoo::BodyPlan::Biped, zoo::Action::Walk, &biped);
  const MotionMeasurements source_measured = measure_motion(source);
  // Not the hexapod: its sprawled legs miss their pins at its walking speed by up to a quarter of its size
  // (docs/tokenizer.md, Stepping).
  for (const zoo::BodyPlan plan : {zoo::BodyPlan::Biped, zoo::BodyPlan::Quadruped}) {
    zoo::SynthesizedMotion walk;
    Clip target = gliding(synthesized_clip(plan, zoo::Action::Walk, &walk));
    ASSERT_EQ(target.motion.frame_count, source.motion.frame_count);
    const Motion glided = target.motion;
    const MotionMeasurements before = measure_motion(target);
    const StepReport report = step_after(source, target.skeleton, target.motion);
    const MotionMeasurements after = measure_motion(target);
    const int legs = static_cast<int>(walk.legs.size());
    std::printf("%-9s feet %d, plants %d, strides/s %.2f (gait %.2f), duty %.2f, miss %.4f; touchdowns/s per foot "
                "%.2f -> %.2f (source %.2f), skate %.3f -> %.3f\n",
                std::string(zoo::body_plan_name(plan)).c_str(), report.feet, report.plants,
                report.strides_per_second, biped.gait_frequency, report.duty, report.max_miss,
                before.gait.touchdowns_per_foot_second, after.gait.touchdowns_per_foot_second,
                source_measured.gait.touchdowns_per_foot_second, before.gait.skate, after.gait.skate);
    EXPECT_LT(before.gait.touchdowns_per_second, 0.2 * legs * biped.gait_frequency) << "the glide has no steps";
    EXPECT_EQ(report.feet, legs);
    EXPECT_NEAR(report.source_strides_per_second, biped.gait_frequency, 0.1 * biped.gait_frequency);
    // Each foot steps at the target's cadence (the total grows with the number of feet), which is the
    // source's unless the legs could not reach at it.
    EXPECT_GE(report.strides_per_second, report.source_strides_per_second);
    EXPECT_EQ(after.gait.feet, legs);
    EXPECT_NEAR(after.gait.touchdowns_per_foot_second, report.strides_per_second, 0.3 * report.strides_per_second);
    EXPECT_LT(after.gait.skate, 0.6 * before.gait.skate);
    // Legs held straight in the glide cannot reach all of a pin at a plant's ends.
    EXPECT_LT(report.max_miss, 0.12);
    EXPECT_LT(after.bone_length_change, 1e-9);
    for (int t = 0; t < target.motion.frame_count; ++t) {
      ASSERT_TRUE(target.motion.translation(t, 0) == glided.translation(t, 0));
      ASSERT_TRUE(target.motion.rotation(t, 0).coeffs() == glided.rotation(t, 0).coeffs());
    }
  }
}

TEST(StepFeet, LegsThatReachKeepTheSourcesCadence) {
  // A running person's cadence is more than the gliding quadruped needs to reach its pins at its walking speed.
  zoo::SynthesizedMotion run;
  const Clip source = synthesized_clip(zoo::BodyPlan::Biped, zoo::Action::Run, &run);
  Clip target = gliding(synthesized_clip(zoo::BodyPlan::Quadruped, zoo::Action::Walk));
  const StepReport report = step_after(source, target.skeleton, target.motion);
  const MotionMeasurements after = measure_motion(target);
  std::printf("strides/s %.2f (source %.2f, gait %.2f), touchdowns/s per foot %.2f, miss %.4f\n",
              report.strides_per_second, report.source_strides_per_second, run.gait_frequency,
              after.gait.touchdowns_per_foot_second, report.max_miss);
  EXPECT_NEAR(report.source_strides_per_second, run.gait_frequency, 0.1 * run.gait_frequency);
  EXPECT_EQ(report.strides_per_second, report.source_strides_per_second);
  EXPECT_EQ(report.feet, 4);
  EXPECT_NEAR(after.gait.touchdowns_per_foot_second, report.strides_per_second, 0.3 * report.strides_per_second);
  EXPECT_LT(report.max_miss, 0.03);
}

TEST(StepFeet, FeetComeDownInTheOrderOfTheirBodyPlan) {
  // The quadruped walks left hind, left fore, right hind, right fore, a quarter stride apart, its left hind
  // coming down with the source's left foot (a run: its cadence is the one the quadruped steps at).
  const Clip source = synthesized_clip(zoo::BodyPlan::Biped, zoo::Action::Run);
  Clip target = gliding(synthesized_clip(zoo::BodyPlan::Quadruped, zoo::Action::Walk));
  const StepReport report = step_after(source, target.skeleton, target.motion);
  ASSERT_EQ(report.feet, 4);
  std::vector<Foot> feet = feet_of(target);
  ASSERT_EQ(feet.size(), 4u);
  // Left before right, hind before fore.
  std::sort(feet.begin(), feet.end(), [](const Foot& a, const Foot& b) {
    return (a.left > 0) != (b.left > 0) ? a.left > 0 : a.forward < b.forward;
  });
  const std::vector<Foot> source_feet = feet_of(source);
  ASSERT_EQ(source_feet.size(), 2u);
  const Foot& source_left = source_feet[0].left > 0 ? source_feet[0] : source_feet[1];
  const double stride = target.motion.fps / report.strides_per_second;
  const int start = touchdown_from(source_left, 20);
  EXPECT_LE(std::abs(touchdown_from(feet[0], start - 2) - start), 2) << "left hind with the source's left foot";
  for (size_t k = 1; k < feet.size(); ++k) {
    const int expected = start + static_cast<int>(std::lround(k * stride / 4.0));
    EXPECT_NEAR(touchdown_from(feet[k], start + 1), expected, 0.1 * stride + 2) << "foot " << k;
  }
}

TEST(StepFeet, AWalkThatStepsAndAStandingSourceChangeNothing) {
  const Clip walk = synthesized_clip(zoo::BodyPlan::Biped, zoo::Action::Walk);
  Clip stepping = synthesized_clip(zoo::BodyPlan::Quadruped, zoo::Action::Walk);
  const Motion before = stepping.motion;
  EXPECT_EQ(step_after(walk, stepping.skeleton, stepping.motion).feet, 0);
  Clip glide = gliding(stepping);
  const Motion glided = glide.motion;
  const Clip standing = synthesized_clip(zoo::BodyPlan::Biped, zoo::Action::Idle);
  const StepReport report = step_after(standing, glide.skeleton, glide.motion);
  EXPECT_EQ(report.feet, 0);
  EXPECT_EQ(report.strides_per_second, 0.0);
  for (size_t i = 0; i < before.rotations.size(); ++i) {
    ASSERT_TRUE(stepping.motion.rotations[i].coeffs() == before.rotations[i].coeffs());
    ASSERT_TRUE(glide.motion.rotations[i].coeffs() == glided.rotations[i].coeffs());
  }
}

TEST(StepFeet, RejectsClipsThatDoNotMatch) {
  const Clip walk = synthesized_clip(zoo::BodyPlan::Biped, zoo::Action::Walk);
  Clip target = synthesized_clip(zoo::BodyPlan::Quadruped, zoo::Action::Walk);
  Clip shorter = walk;
  shorter.motion.frame_count -= 1;
  shorter.motion.rotations.resize(static_cast<size_t>(shorter.motion.frame_count) * shorter.motion.joint_count);
  shorter.motion.translations.resize(static_cast<size_t>(shorter.motion.frame_count) * shorter.motion.joint_count);
  EXPECT_THROW(step_after(shorter, target.skeleton, target.motion), std::invalid_argument);
  StepOptions bad;
  bad.midline = 1.0;
  EXPECT_THROW(step_after(walk, target.skeleton, target.motion, bad), std::invalid_argument);
}

}  // namespace
}  // namespace nec
