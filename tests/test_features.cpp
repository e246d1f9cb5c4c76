// The feature tensor Θ and its inverse.
#include "nec/motion/bvh.h"
#include "nec/motion/features.h"
#include "nec/motion/kinematics.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace nec {
namespace {

TEST(Features, LayoutOfRootAndJoints) {
  std::mt19937 rng(41);
  const Skeleton s = testing::random_skeleton(rng, 6);
  const Motion m = testing::random_motion(rng, s, 3);
  const Features f = encode_features(s, m);
  ASSERT_EQ(f.data.size(), 3u * 6 * 9);
  // Non-root joints carry no displacement.
  for (int t = 0; t < 3; ++t) {
    for (int j = 1; j < 6; ++j) {
      for (int k = 0; k < 3; ++k) EXPECT_EQ(f.at(t, j, k), 0.0f);
    }
  }
  // Frame 0 root holds the height only.
  EXPECT_NEAR(f.at(0, 0, 0), 0.0f, 1e-6);
  EXPECT_NEAR(f.at(0, 0, 1), m.translation(0, 0).y(), 1e-6);
  // The displacement is expressed in the heading frame: its length is kept.
  const double moved = (m.translation(1, 0) - m.translation(0, 0)).norm();
  const Vec3 delta(f.at(1, 0, 0), f.at(1, 0, 1), f.at(1, 0, 2));
  EXPECT_NEAR(delta.norm(), moved, 1e-5);
}

// Θ of a hand-made clip, every channel written out: a root turned 90° about +Y (facing +X) that steps 1 along
// world +Z, and a child bent 90° about X. A channel swapped in both encode and decode would pass a round trip;
// not this.
TEST(Features, GoldenValuesOfAHandMadeClip) {
  Skeleton s;
  s.add_joint("root", -1, Vec3(0, 0, 0), ChannelLayout::position_rotations(EulerOrder::ZXY));
  s.add_joint("child", 0, Vec3(0, 1, 0), ChannelLayout::rotations(EulerOrder::ZXY));
  Motion m = Motion::rest(s, 2, 30.0);
  for (int t = 0; t < 2; ++t) {
    m.rotation(t, 0) = axis_rotation(1, 90.0);
    m.rotation(t, 1) = axis_rotation(0, 90.0);
  }
  m.translation(0, 0) = Vec3(1.0, 0.9, 2.0);
  m.translation(1, 0) = Vec3(1.0, 0.9, 3.0);
  const Features f = encode_features(s, m);
  // Root: frame 0 holds (0, height, 0); frame 1 the step, in the heading frame: world +Z is the body's -X.
  // rot6D = the first two columns of R_y(90°) = [[0,0,1],[0,1,0],[-1,0,0]]: (r00, r10, r20, r01, r11, r21).
  // Child: R_x(90°) = [[1,0,0],[0,0,-1],[0,1,0]] -> (1, 0, 0, 0, 0, 1), no displacement.
  const float expected[2][2][9] = {
      {{0.0f, 0.9f, 0.0f, 0.0f, 0.0f, -1.0f, 0.0f, 1.0f, 0.0f}, {0, 0, 0, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f}},
      {{-1.0f, 0.0f, 0.0f, 0.0f, 0.0f, -1.0f, 0.0f, 1.0f, 0.0f}, {0, 0, 0, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f}}};
  double largest = 0.0;
  for (int t = 0; t < 2; ++t) {
    for (int j = 0; j < 2; ++j) {
      for (int k = 0; k < 9; ++k) {
        largest = std::max(largest, static_cast<double>(std::abs(f.at(t, j, k) - expected[t][j][k])));
        EXPECT_NEAR(f.at(t, j, k), expected[t][j][k], 1e-6) << "frame " << t << " joint " << j << " channel " << k;
      }
    }
  }
  std::printf("largest difference from the hand-computed Θ: %.3g\n", largest);
  EXPECT_EQ(f.start_xz[0], 1.0);
  EXPECT_EQ(f.start_xz[1], 2.0);
}

TEST(Features, InvariantToWorldYaw) {
  std::mt19937 rng(43);
  const Skeleton s = testing::random_skeleton(rng, 5);
  Motion m = testing::random_motion(rng, s, 6);
  const Features before = encode_features(s, m);
  const Quat yaw = axis_rotation(1, 57.0);
  for (int t = 0; t < m.frame_count; ++t) {
    m.rotation(t, 0) = yaw * m.rotation(t, 0);
    m.translation(t, 0) = yaw * m.translation(t, 0);
  }
  const Features after = encode_features(s, m);
  for (int t = 1; t < m.frame_count; ++t) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(before.at(t, 0, k), after.at(t, 0, k), 1e-5);
  }
}

TEST(Features, TurnToHeadingTurnsTheWholeMotionAboutItsStart) {
  std::mt19937 rng(44);
  const Skeleton s = testing::random_skeleton(rng, 5);
  Motion m = testing::random_motion(rng, s, 6);
  const Features original = encode_features(s, m);
  const double start = heading_angle(Quat(m.rotation(0, 0)));
  for (int t : {0, 4}) {
    const double expected = heading_angle(Quat(m.rotation(t, 0)));
    EXPECT_LE(std::abs(root_heading(original, t)), M_PI);
    EXPECT_NEAR(std::remainder(root_heading(original, t) - expected, 2.0 * M_PI), 0.0, 1e-6) << "frame " << t;
  }
  EXPECT_THROW(root_heading(original, 6), std::out_of_range);

  // Turned to its own heading: nothing changes.
  Features same = original;
  EXPECT_NEAR(turn_to_heading(same, start), 0.0, 1e-6);
  for (size_t k = 0; k < same.data.size(); ++k) EXPECT_NEAR(same.data[k], original.data[k], 1e-6) << k;

  // The same motion turned 57 degrees about +Y (around the origin, where it
  // starts) turns back to the original features, every frame and joint.
  const Quat yaw = axis_rotation(1, 57.0);
  for (int t = 0; t < m.frame_count; ++t) {
    m.rotation(t, 0) = yaw * m.rotation(t, 0);
    m.translation(t, 0) = yaw * m.translation(t, 0);
  }
  Features turned = encode_features(s, m);
  EXPECT_NEAR(std::remainder(root_heading(turned, 0) - start - 57.0 * M_PI / 180.0, 2.0 * M_PI), 0.0, 1e-5);
  EXPECT_NEAR(turn_to_heading(turned, start), -57.0 * M_PI / 180.0, 1e-5);
  for (size_t k = 0; k < turned.data.size(); ++k) EXPECT_NEAR(turned.data[k], original.data[k], 1e-5) << k;
}

TEST(Features, TurnBodyTurnsTheBodyAroundTheRootButKeepsItsPath) {
  std::mt19937 rng(45);
  const Skeleton s = testing::random_skeleton(rng, 5);
  const Motion m = testing::random_motion(rng, s, 6);
  Features f = encode_features(s, m);
  const double start = root_heading(f, 0);
  turn_body(f, 0.4);
  EXPECT_NEAR(std::remainder(root_heading(f, 0) - start - 0.4, 2.0 * M_PI), 0.0, 1e-5);
  const Pose a = forward_kinematics(s, m);
  const Pose b = forward_kinematics(s, decode_features(s, f));
  const Quat turn = axis_rotation(1, 0.4 * 180.0 / M_PI);
  for (int t = 0; t < m.frame_count; ++t) {
    EXPECT_LT((b.position(t, 0) - a.position(t, 0)).norm(), 1e-5) << "the root's path, frame " << t;
    for (int j = 1; j < s.joint_count(); ++j) {
      const Vec3 expected = turn * (a.position(t, j) - a.position(t, 0));
      EXPECT_LT((b.position(t, j) - b.position(t, 0) - expected).norm(), 1e-5) << "frame " << t << " joint " << j;
    }
  }
}

void expect_inverse(const Skeleton& s, const Motion& m, double tolerance) {
  const Motion back = decode_features(s, encode_features(s, m));
  const Pose a = forward_kinematics(s, m);
  const Pose b = forward_kinematics(s, back);
  const double diff = testing::max_position_difference(a.positions, b.positions) / std::max(s.diameter(), 1e-9);
  EXPECT_LT(diff, tolerance) << "max position difference / diameter = " << diff;
}

TEST(Features, DecodeInvertsEncodeOnRandomMotion) {
  std::mt19937 rng(47);
  for (int trial = 0; trial < 5; ++trial) {
    const Skeleton s = testing::random_skeleton(rng, 4 + 6 * trial);
    expect_inverse(s, testing::random_motion(rng, s, 50), 1e-5);
  }
}

TEST(Features, DecodeInvertsEncodeOnLongRealClip) {
  // Thousands of frames of integrated float displacements stay within 1e-4 diameters.
  Clip clip = read_bvh(testing::cmu_bvh_dir() + "/01_01.bvh");
  // Joints with position channels only at the root, as after preprocessing.
  expect_inverse(clip.skeleton, clip.motion, 1e-4);
}

}  // namespace
}  // namespace nec
