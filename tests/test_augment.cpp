// Rig augmentation keeps the motion of the joints it keeps.
#include "nec/corpus/augment.h"
#include "nec/motion/bvh.h"
#include "nec/motion/kinematics.h"
#include "nec/motion/names.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace nec {
namespace {

Clip cmu_clip() {
  Clip clip = read_bvh(testing::cmu_bvh_dir() + "/01_01.bvh");
  clip.motion = clip.motion.slice(0, 60);
  return clip;
}

std::vector<std::string> canonical(const Skeleton& s) {
  std::vector<std::string> out;
  for (const auto& n : s.names) out.push_back(canonical_joint_name(n));
  return out;
}

// Largest FK position difference over the joints both clips share (by name).
double shared_joint_difference(const Clip& a, const Clip& b) {
  const Pose pa = forward_kinematics(a.skeleton, a.motion);
  const Pose pb = forward_kinematics(b.skeleton, b.motion);
  double worst = 0.0;
  for (int j = 0; j < a.skeleton.joint_count(); ++j) {
    const int k = b.skeleton.find(a.skeleton.names[j]);
    if (k < 0) continue;
    for (int t = 0; t < a.motion.frame_count; ++t) worst = std::max(worst, (pa.position(t, j) - pb.position(t, k)).norm());
  }
  return worst;
}

TEST(Augment, RestPoseResetKeepsPositions) {
  const Clip clip = cmu_clip();
  SplitMix64 rng(1);
  for (int trial = 0; trial < 3; ++trial) {
    const Clip reset = reset_rest_pose(clip, rng);
    const double diff = shared_joint_difference(clip, reset);
    EXPECT_LT(diff, 1e-9 * clip.skeleton.diameter()) << "max diff " << diff;
    // The rest pose really changed: some offsets point elsewhere.
    double moved = 0.0;
    for (int j = 1; j < clip.skeleton.joint_count(); ++j) {
      moved = std::max(moved, (reset.skeleton.offsets[j] - clip.skeleton.offsets[j]).norm());
    }
    EXPECT_GT(moved, 0.01 * clip.skeleton.diameter());
  }
  // The reference frame itself becomes the identity pose (except the root).
  const Clip at5 = reset_rest_pose_to_frame(clip, 5);
  for (int j = 1; j < clip.skeleton.joint_count(); ++j) {
    EXPECT_LT(geodesic_distance(at5.motion.rotation(5, j), Quat::Identity()), 1e-9);
  }
}

TEST(Augment, RestPoseResetOnRandomTrees) {
  std::mt19937 rigs(2);  // test trees (test_support)
  SplitMix64 rng(2);      // augmentation draws
  for (int trial = 0; trial < 5; ++trial) {
    Clip clip{testing::random_skeleton(rigs, 10 + trial * 5), {}, {}};
    clip.motion = testing::random_motion(rigs, clip.skeleton, 8);
    EXPECT_LT(shared_joint_difference(clip, reset_rest_pose(clip, rng)), 1e-9);
  }
}

TEST(Augment, BoneLengthsScaleSymmetricallyByPart) {
  const Clip clip = cmu_clip();
  const auto names = canonical(clip.skeleton);
  SplitMix64 rng(3);
  const Clip scaled = scale_bone_lengths(clip, names, rng);
  const auto parts = body_parts(clip.skeleton, names);
  const int left_leg = clip.skeleton.find("LeftLeg");
  const int right_leg = clip.skeleton.find("RightLeg");
  ASSERT_EQ(parts[left_leg], "leg");
  const auto ratio = [&](int j) { return scaled.skeleton.offsets[j].norm() / clip.skeleton.offsets[j].norm(); };
  EXPECT_NEAR(ratio(left_leg), ratio(right_leg), 1e-12);
  EXPECT_GE(ratio(left_leg), 0.8);
  EXPECT_LE(ratio(left_leg), 1.2);
  EXPECT_NEAR(ratio(clip.skeleton.find("LeftArm")), ratio(clip.skeleton.find("RightArm")), 1e-12);
  // Rotations are untouched; bone lengths in every frame match the new offsets.
  EXPECT_EQ(scaled.motion.rotations.size(), clip.motion.rotations.size());
  const Pose pose = forward_kinematics(scaled.skeleton, scaled.motion);
  for (int j = 1; j < clip.skeleton.joint_count(); ++j) {
    const double length = (pose.position(30, j) - pose.position(30, clip.skeleton.parents[j])).norm();
    EXPECT_NEAR(length, scaled.skeleton.offsets[j].norm(), 1e-9);
  }
}

TEST(Augment, JointRemovalKeepsTheOtherJoints) {
  const Clip clip = cmu_clip();
  const auto removable = removable_joints(clip.skeleton);
  ASSERT_FALSE(removable.empty());
  for (int j : removable) {
    const Clip smaller = remove_joint(clip, j);
    EXPECT_EQ(smaller.skeleton.joint_count(), clip.skeleton.joint_count() - 1);
    EXPECT_LT(shared_joint_difference(clip, smaller), 1e-9 * clip.skeleton.diameter()) << clip.skeleton.names[j];
    EXPECT_NO_THROW(smaller.skeleton.validate());
  }
  SplitMix64 rng(4);
  const Clip fewer = remove_joints(clip, rng, 0.2);
  EXPECT_LT(fewer.skeleton.joint_count(), clip.skeleton.joint_count());
  EXPECT_LT(shared_joint_difference(clip, fewer), 1e-9 * clip.skeleton.diameter());
  // Round trip through BVH still works for the smaller rig.
  const Clip back = parse_bvh(format_bvh(fewer.skeleton, fewer.motion), "fewer.bvh");
  EXPECT_EQ(back.skeleton.names, fewer.skeleton.names);
}

TEST(Augment, ZeroLengthBoneCases) {
  // root -> a (zero offset, only child) -> b ; a merges into root.
  // root -> c -> d (zero offset) ; c's children sit on it, so c can go.
  Skeleton s;
  const auto rot = ChannelLayout::rotations(EulerOrder::XYZ);
  s.add_joint("root", -1, Vec3::Zero(), ChannelLayout::position_rotations(EulerOrder::XYZ));
  s.add_joint("a", 0, Vec3::Zero(), rot);
  s.add_joint("b", 1, Vec3(1, 0, 0), rot);
  s.add_joint("c", 2, Vec3(0, 1, 0), rot);
  s.add_joint("d", 3, Vec3::Zero(), rot);
  s.add_joint("e", 4, Vec3(0, 0, 1), rot);
  std::mt19937 rng(5);
  Clip clip{s, testing::random_motion(rng, s, 6), {}};
  const auto removable = removable_joints(s);
  EXPECT_NE(std::find(removable.begin(), removable.end(), 1), removable.end());
  EXPECT_NE(std::find(removable.begin(), removable.end(), 3), removable.end());
  EXPECT_EQ(std::find(removable.begin(), removable.end(), 2), removable.end());
  for (int j : {1, 3, 4, 5}) EXPECT_LT(shared_joint_difference(clip, remove_joint(clip, j)), 1e-9) << j;
  EXPECT_THROW(remove_joint(clip, 2), std::invalid_argument);
}

TEST(Augment, SubdivisionKeepsPositionsExactly) {
  const Clip clip = cmu_clip();
  const int forearm = clip.skeleton.find("LeftForeArm");
  const Clip finer = subdivide_bone(clip, forearm, 0.4);
  ASSERT_EQ(finer.skeleton.joint_count(), clip.skeleton.joint_count() + 1);
  const int inserted = finer.skeleton.find("LeftForeArm_sub");
  ASSERT_GE(inserted, 0);
  EXPECT_EQ(finer.skeleton.parents[finer.skeleton.find("LeftForeArm")], inserted);
  EXPECT_LT(inserted, finer.skeleton.find("LeftForeArm"));  // listed before its child
  EXPECT_LT(shared_joint_difference(clip, finer), 1e-9 * clip.skeleton.diameter());
  // The inserted joint lies on the bone, 40% of the way.
  const Pose a = forward_kinematics(clip.skeleton, clip.motion);
  const Pose b = forward_kinematics(finer.skeleton, finer.motion);
  const int arm = clip.skeleton.parents[forearm];
  const Vec3 expected = a.position(7, arm) + 0.4 * (a.position(7, forearm) - a.position(7, arm));
  EXPECT_LT((b.position(7, inserted) - expected).norm(), 1e-9 * clip.skeleton.diameter());
  SplitMix64 rng(6);
  const Clip many = subdivide_bones(clip, rng, 0.2);
  EXPECT_GT(many.skeleton.joint_count(), clip.skeleton.joint_count());
  EXPECT_LT(shared_joint_difference(clip, many), 1e-9 * clip.skeleton.diameter());
}

TEST(Augment, SameSeedSameRig) {
  const Clip clip = cmu_clip();
  const auto names = canonical(clip.skeleton);
  for (AugmentKind kind : {AugmentKind::RestPose, AugmentKind::BoneLength, AugmentKind::JointRemoval,
                           AugmentKind::Subdivision}) {
    SplitMix64 a(9), b(9);
    const Clip x = augment(clip, kind, names, a);
    const Clip y = augment(clip, kind, names, b);
    EXPECT_EQ(x.skeleton.names, y.skeleton.names);
    EXPECT_EQ(x.skeleton.offsets, y.skeleton.offsets);
  }
}

}  // namespace
}  // namespace nec
