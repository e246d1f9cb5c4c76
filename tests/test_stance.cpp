// The stance from the skeleton alone (corpus/stance.h), without a network: the frames that carry a bind pose
// onto given bone directions, and take_stance's bookkeeping (positions kept, the file given back exactly).
#include "nec/corpus/preprocess.h"
#include "nec/corpus/rest_pose.h"
#include "nec/corpus/stance.h"
#include "nec/motion/kinematics.h"
#include "nec/motion/rotations.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace nec {
namespace {

// A skeleton in the pose of `motion`'s frame `frame`, with world-aligned joint frames there.
Skeleton posed_skeleton(const Skeleton& skeleton, const Motion& motion, int frame) {
  const Clip clip{skeleton, motion.slice(frame, frame + 1), {}, ""};
  return reexpress_joint_frames(clip, pose_frames(clip, 0)).skeleton;
}

double worst(const std::vector<double>& values) {
  return values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
}

// Gives every bone the direction it has in `stance` (a test double for the network).
class KnownStance : public StancePredictor {
 public:
  explicit KnownStance(std::vector<Vec3> directions) : directions_(std::move(directions)) {}
  std::vector<Vec3> bone_directions(const Skeleton&, const std::vector<std::string>&) const override {
    return directions_;
  }

 private:
  std::vector<Vec3> directions_;
};

// Gives every bone its bind direction turned by `turn`.
class TurnedBind : public StancePredictor {
 public:
  explicit TurnedBind(Quat turn) : turn_(turn) {}
  std::vector<Vec3> bone_directions(const Skeleton& bind, const std::vector<std::string>&) const override {
    std::vector<Vec3> out = unit_bones(bind);
    for (Vec3& d : out) d = turn_ * d;
    return out;
  }

 private:
  Quat turn_;
};

TEST(Stance, FramesCarryAnyPoseOntoTheGivenBoneDirections) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    const Skeleton stance = testing::random_skeleton(rng, 12 + 4 * trial);
    const Motion motion = testing::random_motion(rng, stance, 3);
    const Skeleton bind = posed_skeleton(stance, motion, 2);
    ASSERT_GT(worst(bone_direction_errors(bind, stance)), 5.0) << "the pose should differ from the stance";
    const std::vector<Quat> frames = stance_frames(bind, unit_bones(stance));
    // A joint's children keep their layout between two poses of one rig, so one rigid turn meets them all; only
    // children in (nearly) one line, whose turn about that line is left to the parent, may miss by a little.
    std::vector<double> errors = bone_direction_errors(reexpress_skeleton(bind, frames), stance);
    std::sort(errors.begin(), errors.end());
    EXPECT_LT(errors[errors.size() / 2], 1e-4) << trial;
    EXPECT_LT(errors[errors.size() * 9 / 10], 1e-4) << trial;
    EXPECT_LT(errors.back(), 5.0) << trial;
  }
}

TEST(Stance, ARigidlyTurnedBodyTurnsBackWholeWithoutTwist) {
  // The whole body turned as one: every joint, leaves and one-child joints included, gets the same turn back,
  // since where the children leave the turn about a bone free the parent's rotation decides it.
  const zoo::Creature creature = zoo::make_creature(zoo::BodyPlan::Biped, 3);
  Motion turned = Motion::rest(creature.skeleton, 1, 30.0);
  const Quat turn = axis_rotation(0, 35.0) * axis_rotation(1, 70.0);
  turned.rotation(0, 0) = turn * turned.rotation(0, 0);
  const Skeleton bind = posed_skeleton(creature.skeleton, turned, 0);
  // The zoo's rest has world-aligned joint frames: its offsets are the stance's bones.
  const std::vector<Quat> frames = stance_frames(bind, unit_bones(creature.skeleton));
  for (size_t j = 0; j < frames.size(); ++j) {
    EXPECT_LT(geodesic_distance(frames[j], turn.conjugate()), 1e-6) << creature.skeleton.names[j];
  }
}

TEST(Stance, TakingTheStanceKeepsPositionsAndGivesTheFileBack) {
  const zoo::Creature creature = zoo::make_creature(zoo::BodyPlan::Quadruped, 2);
  zoo::MotionSpec spec;
  spec.action = zoo::Action::Walk;
  spec.seconds = 1.0;
  spec.speed = 0.5 * zoo::typical_speed(creature, spec.action);
  const Clip authored{creature.skeleton, zoo::synthesize_motion(creature, spec).motion, {}, ""};
  PreprocessOptions options;
  options.target_fps = 0.0;
  const PreparedClip prepared = preprocess(authored, "walk.bvh", options);
  ASSERT_TRUE(prepared.report.accepted());
  const PreparedClip stood = take_stance(prepared, TurnedBind(axis_rotation(0, 40.0)));

  // The rest is the stance asked for: every bone of frame 0 turned by 40 degrees about +X.
  const Skeleton bind = reexpress_joint_frames(prepared.clip, pose_frames(prepared.clip, 0)).skeleton;
  const std::vector<Vec3> bind_bones = unit_bones(bind), stood_bones = unit_bones(stood.clip.skeleton);
  for (int j = 1; j < bind.joint_count(); ++j) {
    if (bind_bones[j].isZero()) continue;
    EXPECT_LT((axis_rotation(0, 40.0) * bind_bones[j] - stood_bones[j]).norm(), 1e-6) << j;
  }
  // The same motion in other joint frames.
  std::vector<Vec3> before, after;
  joint_positions(prepared.clip.skeleton, prepared.clip.motion, before);
  joint_positions(stood.clip.skeleton, stood.clip.motion, after);
  EXPECT_LT(testing::max_position_difference(before, after), 1e-9);
  // And back to the file's own offsets and rotations.
  const Clip back = denormalize(stood.clip, stood.normalization);
  EXPECT_LT(testing::largest_rotation_difference(back.motion, authored.motion), 1e-6);
  for (int j = 1; j < back.skeleton.joint_count(); ++j) {
    EXPECT_LT((back.skeleton.offsets[j] - authored.skeleton.offsets[j]).norm(), 1e-6 * creature.skeleton.diameter());
  }
  EXPECT_NE(std::find(stood.report.changes.begin(), stood.report.changes.end(),
                      "rest: the stance predicted from the skeleton in its frame-0 pose"),
            stood.report.changes.end());
}

TEST(Stance, AOneFrameRigInAnyPoseTakesTheStanceItIsGiven) {
  // Two one-frame files of one rig, posed differently: given the stance's directions, both end with the same
  // rest, which is not true of the mean pose (each file's own frame).
  const zoo::Creature creature = zoo::make_creature(zoo::BodyPlan::Biped, 5);
  const Skeleton& skeleton = creature.skeleton;
  std::mt19937 rng(9);
  Motion a = Motion::rest(skeleton, 1, 30.0), b = testing::random_motion(rng, skeleton, 1);
  b.rotation(0, 0) = Quat::Identity();  // both face where the rig faces
  b.translation(0, 0) = a.translation(0, 0);
  PreprocessOptions options;
  options.target_fps = 0.0;
  options.min_frames = 1;
  const PreparedClip first = preprocess({skeleton, a, {}, ""}, "a.bvh", options);
  const PreparedClip second = preprocess({skeleton, b, {}, ""}, "b.bvh", options);
  ASSERT_TRUE(first.report.accepted() && second.report.accepted());
  ASSERT_GT(worst(bone_direction_errors(first.clip.skeleton, second.clip.skeleton)), 10.0);
  const KnownStance stance(unit_bones(first.clip.skeleton));
  const PreparedClip stood = take_stance(second, stance);
  EXPECT_LT(worst(bone_direction_errors(stood.clip.skeleton, first.clip.skeleton)), 0.1);
}

TEST(Stance, BadInputIsRefused) {
  const zoo::Creature creature = zoo::make_creature(zoo::BodyPlan::Biped, 1);
  EXPECT_THROW(stance_frames(creature.skeleton, {Vec3::UnitY()}), std::invalid_argument);
  PreprocessOptions options;
  options.min_frames = 1;
  PreparedClip kept = preprocess({creature.skeleton, Motion::rest(creature.skeleton, 1, 30.0), {}, ""}, "a.bvh", options);
  ASSERT_TRUE(kept.report.accepted());
  kept.normalization.rest_frames.clear();  // prepared with --keep-rest
  EXPECT_THROW(take_stance(kept, TurnedBind(Quat::Identity())), std::invalid_argument);
}

}  // namespace
}  // namespace nec
