// Joint-frame conventions: re-expression keeps every position, the canonical rest is the same for every
// authoring convention, and preprocessing is exact in both directions on every rig family.
#include "nec/motion/bvh.h"
#include "nec/motion/features.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"
#include "nec/corpus/rest_pose.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace nec {
namespace {

using testing::largest_rotation_difference;
using testing::max_position_difference;

std::vector<Vec3> world_positions(const Clip& clip) {
  std::vector<Vec3> positions;
  joint_positions(clip.skeleton, clip.motion, positions);
  const std::vector<Vec3> sites = end_site_positions(clip.skeleton, forward_kinematics(clip.skeleton, clip.motion));
  positions.insert(positions.end(), sites.begin(), sites.end());
  return positions;
}

double largest_offset_difference(const Skeleton& a, const Skeleton& b) {
  double worst = 0.0;
  for (int j = 0; j < a.joint_count(); ++j) worst = std::max(worst, (a.offsets[j] - b.offsets[j]).norm());
  for (size_t e = 0; e < a.end_sites.size(); ++e) worst = std::max(worst, (a.end_sites[e].offset - b.end_sites[e].offset).norm());
  return worst;
}

Clip random_clip(uint64_t seed, int joints, int frames) {
  std::mt19937 rng(static_cast<unsigned>(seed));
  Clip clip;
  clip.skeleton = testing::random_skeleton(rng, joints);
  clip.motion = testing::random_motion(rng, clip.skeleton, frames);
  return clip;
}

// One walk (or the plan's first action) of a zoo creature of every body plan.
std::vector<Clip> zoo_clips() {
  std::vector<Clip> clips;
  for (zoo::BodyPlan plan : zoo::kAllBodyPlans) {
    const zoo::Creature creature = zoo::make_creature(plan, 11);
    zoo::MotionSpec spec;
    spec.action = zoo::supports_action(plan, zoo::Action::Walk) ? zoo::Action::Walk : zoo::supported_actions(plan)[0];
    spec.seconds = 1.5;
    spec.turn_rate = zoo::is_locomotion(spec.action) ? 20.0 : 0.0;
    spec.speed = zoo::is_locomotion(spec.action) ? 0.5 * zoo::typical_speed(creature, spec.action) : 0.0;
    clips.push_back({creature.skeleton, zoo::synthesize_motion(creature, spec).motion, {}});
  }
  return clips;
}

// Real files of every source the corpus has: CMU (assimp-testmodels), Bandai and the MANN dog when ../shared is there.
std::vector<std::string> real_files() {
  std::vector<std::string> files;
  const std::vector<std::string> cmu = testing::bvh_files_under(testing::cmu_bvh_dir());
  if (!cmu.empty()) files.push_back(cmu.front());
  const std::string shared = testing::shared_data_dir();
  if (!shared.empty()) {
    files.push_back(shared + "/bandai/set1/data/dataset-1_walk_normal_001.bvh");
    files.push_back(shared + "/mann_dog/D1_001_KAN01_001.bvh");
  }
  return files;
}

TEST(RestPose, ReexpressingKeepsEveryPositionAndInvertsExactly) {
  const Clip clip = random_clip(1, 12, 9);
  std::mt19937 rng(5);
  std::vector<Quat> frames;
  for (int j = 0; j < clip.skeleton.joint_count(); ++j) frames.push_back(testing::random_rotation(rng));
  const Clip other = reexpress_joint_frames(clip, frames);
  EXPECT_LT(max_position_difference(world_positions(clip), world_positions(other)), 1e-9);
  EXPECT_GT(largest_rotation_difference(clip.motion, other.motion), 0.1);  // it did change the rotations
  const Clip back = reexpress_joint_frames(other, inverse_frames(frames));
  EXPECT_LT(largest_rotation_difference(clip.motion, back.motion), 1e-7);
  EXPECT_LT(largest_offset_difference(clip.skeleton, back.skeleton), 1e-12);
  EXPECT_THROW(reexpress_joint_frames(clip, std::vector<Quat>(3, Quat::Identity())), std::invalid_argument);
}

TEST(RestPose, BonesAlongXPutsEveryJointsFirstBoneOnItsX) {
  for (const Clip& clip : zoo_clips()) {
    SplitMix64 rng(1);
    const Clip maya = reorient_joint_axes(clip, JointAxes::BonesAlongX, rng);
    EXPECT_LT(max_position_difference(world_positions(clip), world_positions(maya)), 1e-9);
    const Skeleton& s = maya.skeleton;
    for (int j = 0; j < s.joint_count(); ++j) {
      const std::vector<int> children = s.children(j);
      if (children.empty() || s.offsets[children[0]].norm() < 1e-9) continue;
      const Vec3& bone = s.offsets[children[0]];
      EXPECT_NEAR(bone.x(), bone.norm(), 1e-9) << s.names[children[0]];
    }
  }
}

// A pose held still while the root turns: the mean pose is that pose, so every local rotation becomes
// identity except the root's, which keeps the turn.
TEST(RestPose, TheCanonicalRestOfAHeldPoseIsThatPose) {
  Clip clip = random_clip(2, 10, 1);
  const Motion held = clip.motion;
  const int frames = 20;
  clip.motion = Motion::rest(clip.skeleton, frames, 30.0);
  for (int t = 0; t < frames; ++t) {
    for (int j = 0; j < clip.skeleton.joint_count(); ++j) clip.motion.rotation(t, j) = held.rotation(0, j);
    clip.motion.rotation(t, 0) = (axis_rotation(1, 9.0 * t) * held.rotation(0, 0)).normalized();
  }
  const Clip canonical = reexpress_joint_frames(clip, mean_pose_frames(clip));
  for (int t = 0; t < frames; ++t) {
    EXPECT_LT(geodesic_distance(canonical.motion.rotation(t, 0), axis_rotation(1, 9.0 * t)), 1e-9) << t;
    for (int j = 1; j < clip.skeleton.joint_count(); ++j) {
      EXPECT_LT(geodesic_distance(canonical.motion.rotation(t, j), Quat::Identity()), 1e-9) << t << " " << j;
    }
  }
  // The rest offsets are the held pose's bones in world axes (facing as frame 0 does).
  const Pose pose = forward_kinematics(clip.skeleton, clip.motion.slice(0, 1));
  for (int j = 1; j < clip.skeleton.joint_count(); ++j) {
    const Vec3 bone = pose.position(0, j) - pose.position(0, clip.skeleton.parents[j]);
    EXPECT_LT((canonical.skeleton.offsets[j] - bone).norm(), 1e-9) << j;
  }
}

TEST(RestPose, TheCanonicalRestDoesNotDependOnTheJointFrames) {
  std::vector<Clip> clips = zoo_clips();
  clips.push_back(random_clip(3, 15, 30));
  for (const Clip& clip : clips) {
    const Clip canonical = reexpress_joint_frames(clip, mean_pose_frames(clip));
    for (JointAxes axes : {JointAxes::BonesAlongX, JointAxes::Random}) {
      SplitMix64 rng(7);
      const Clip other = reorient_joint_axes(clip, axes, rng);
      const Clip other_canonical = reexpress_joint_frames(other, mean_pose_frames(other));
      EXPECT_LT(largest_rotation_difference(canonical.motion, other_canonical.motion), 1e-6) << clip.skeleton.names[0];
      EXPECT_LT(largest_offset_difference(canonical.skeleton, other_canonical.skeleton), 1e-9);
    }
  }
}

// A clip canonicalized on its own and added to a rig-wide mean counts as its authored frames.
TEST(RestPose, MeanFramesAddUpInTheAuthoredFrames) {
  const Clip a = random_clip(4, 8, 12);
  Clip b = a;
  b.motion = testing::random_motion(*std::make_unique<std::mt19937>(9), a.skeleton, 7);
  MeanPoseFrames authored(a.skeleton);
  authored.add(a.motion);
  authored.add(b.motion);
  const std::vector<Quat> b_frames = mean_pose_frames(b);
  MeanPoseFrames mixed(a.skeleton);
  mixed.add(a.motion);
  mixed.add(reexpress_joint_frames(b, b_frames).motion, b_frames);
  const std::vector<Quat> x = authored.frames(), y = mixed.frames();
  for (size_t j = 0; j < x.size(); ++j) EXPECT_LT(geodesic_distance(x[j], y[j]), 1e-9) << j;
}

// Preprocessing the same file as authored, with every bone along +X and with random joint frames gives the same
// normalized clip, and denormalize gives each its own file back.
TEST(RestPose, PreprocessingIsTheSameForEveryConventionAndInvertsToTheFile) {
  std::vector<std::pair<std::string, Clip>> sources;
  for (const Clip& clip : zoo_clips()) sources.emplace_back("zoo " + clip.skeleton.names.back(), clip);
  for (const std::string& file : real_files()) {
    Clip clip = read_bvh(file);
    clip.motion = clip.motion.slice(0, std::min(clip.motion.frame_count, 90));
    sources.emplace_back(file, clip);
  }
  ASSERT_GE(sources.size(), 10u);
  PreprocessOptions options;
  options.target_fps = 0.0;  // keep the file's frames, so that denormalize gives them back
  for (const auto& [name, authored] : sources) {
    const PreparedClip reference = preprocess(authored, name, options);
    ASSERT_TRUE(reference.report.accepted()) << name << ": " << reference.report.rejection;
    const Features features = encode_features(reference.clip.skeleton, reference.clip.motion);
    for (JointAxes axes : {JointAxes::BonesAlongX, JointAxes::Random}) {
      SplitMix64 rng(13);
      const Clip converted = reorient_joint_axes(authored, axes, rng);
      const PreparedClip prepared = preprocess(converted, name, options);
      ASSERT_TRUE(prepared.report.accepted()) << name;
      const Features other = encode_features(prepared.clip.skeleton, prepared.clip.motion);
      ASSERT_EQ(other.data.size(), features.data.size());
      double worst = 0.0;
      for (size_t i = 0; i < other.data.size(); ++i) worst = std::max(worst, double(std::abs(other.data[i] - features.data[i])));
      EXPECT_LT(worst, 1e-4) << name;
      EXPECT_LT(largest_offset_difference(prepared.clip.skeleton, reference.clip.skeleton), 1e-9) << name;

      // Back to the converted file's own bones and rotations (the root's offset and dummy roots aside; constant
      // position channels are folded into offsets).
      const Clip back = denormalize(prepared.clip, prepared.normalization);
      if (back.skeleton.joint_count() != converted.skeleton.joint_count()) continue;  // a merged dummy root
      const double size = converted.skeleton.diameter();
      for (int j = 1; j < back.skeleton.joint_count(); ++j) {
        EXPECT_LT((back.skeleton.offsets[j] - converted.motion.translation(0, j)).norm(), 1e-5 * size) << name << " " << j;
      }
      double rotation = 0.0;
      for (int t = 0; t < back.motion.frame_count; ++t) {
        for (int j = 1; j < back.motion.joint_count; ++j) {
          rotation = std::max(rotation, geodesic_distance(back.motion.rotation(t, j), converted.motion.rotation(t, j)));
        }
      }
      EXPECT_LT(rotation, 1e-6) << name;
      EXPECT_LT(max_position_difference(world_positions(back), world_positions(converted)), 1e-6 * size) << name;
    }
  }
}

}  // namespace
}  // namespace nec
