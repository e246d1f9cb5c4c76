// Forward kinematics against a direct 4x4-matrix implementation.
#include "nec/motion/kinematics.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace nec {
namespace {

// Reference FK: accumulate homogeneous transforms from the root down each path.
std::vector<Vec3> reference_positions(const Skeleton& s, const Motion& m) {
  std::vector<Vec3> out;
  for (int t = 0; t < m.frame_count; ++t) {
    for (int j = 0; j < s.joint_count(); ++j) {
      Eigen::Matrix4d transform = Eigen::Matrix4d::Identity();
      auto chain = s.path_to_root(j);
      for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
        Eigen::Matrix4d local = Eigen::Matrix4d::Identity();
        local.topLeftCorner<3, 3>() = m.rotation(t, *it).toRotationMatrix();
        local.topRightCorner<3, 1>() = m.translation(t, *it);
        transform = transform * local;
      }
      out.push_back(transform.topRightCorner<3, 1>());
    }
  }
  return out;
}

TEST(Kinematics, MatchesMatrixReferenceOnRandomTrees) {
  std::mt19937 rng(29);
  for (int trial = 0; trial < 10; ++trial) {
    const Skeleton s = testing::random_skeleton(rng, 2 + 7 * trial);
    const Motion m = testing::random_motion(rng, s, 4);
    const Pose pose = forward_kinematics(s, m);
    const double diff = testing::max_position_difference(pose.positions, reference_positions(s, m));
    EXPECT_LT(diff, 1e-10) << "trial " << trial << " max diff " << diff;
    std::vector<Vec3> positions;
    joint_positions(s, m, positions);
    EXPECT_EQ(testing::max_position_difference(positions, pose.positions), 0.0);
  }
}

TEST(Kinematics, RestPoseIsTheSumOfOffsets) {
  std::mt19937 rng(31);
  const Skeleton s = testing::random_skeleton(rng, 15);
  const Motion m = Motion::rest(s, 1, 30.0);
  const Pose pose = forward_kinematics(s, m);
  for (int j = 1; j < s.joint_count(); ++j) {
    const Vec3 expected = pose.position(0, s.parents[j]) + s.offsets[j];
    EXPECT_LT((pose.position(0, j) - expected).norm(), 1e-12);
  }
}

TEST(Kinematics, BoneLengthsArePreserved) {
  std::mt19937 rng(37);
  const Skeleton s = testing::random_skeleton(rng, 20);
  const Motion m = testing::random_motion(rng, s, 10);
  const Pose pose = forward_kinematics(s, m);
  for (int t = 0; t < m.frame_count; ++t) {
    for (int j = 1; j < s.joint_count(); ++j) {
      const double length = (pose.position(t, j) - pose.position(t, s.parents[j])).norm();
      EXPECT_NEAR(length, s.offsets[j].norm(), 1e-10);
    }
  }
}

}  // namespace
}  // namespace nec
