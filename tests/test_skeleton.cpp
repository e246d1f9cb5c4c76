// Skeleton tree helpers and channel layouts.
#include "nec/motion/skeleton.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace nec {
namespace {

// root -> spine -> head ; root -> leg_l -> foot_l ; root -> leg_r
Skeleton small_tree() {
  Skeleton s;
  const auto layout = ChannelLayout::rotations(EulerOrder::ZXY);
  s.add_joint("root", -1, Vec3::Zero(), ChannelLayout::position_rotations(EulerOrder::ZXY));
  s.add_joint("spine", 0, Vec3(0, 1, 0), layout);
  s.add_joint("head", 1, Vec3(0, 0.5, 0), layout);
  s.add_joint("leg_l", 0, Vec3(0.2, -1, 0), layout);
  s.add_joint("foot_l", 3, Vec3(0, -1, 0), layout);
  s.add_joint("leg_r", 0, Vec3(-0.2, -1, 0), layout);
  s.end_sites.push_back({2, Vec3(0, 0.3, 0)});
  return s;
}

TEST(Skeleton, TreeHelpers) {
  const Skeleton s = small_tree();
  EXPECT_NO_THROW(s.validate());
  EXPECT_EQ(s.children(0), (std::vector<int>{1, 3, 5}));
  EXPECT_EQ(s.depth(4), 2);
  EXPECT_EQ(s.path_to_root(4), (std::vector<int>{4, 3, 0}));
  EXPECT_EQ(s.lowest_common_ancestor(2, 4), 0);
  EXPECT_EQ(s.lowest_common_ancestor(1, 2), 1);
  EXPECT_EQ(s.path(2, 4), (std::vector<int>{2, 1, 0, 3, 4}));
  EXPECT_EQ(s.leaves(), (std::vector<int>{2, 4, 5}));
  EXPECT_EQ(s.find("foot_l"), 4);
  EXPECT_EQ(s.find("nope"), -1);
  // Longest chain: root-spine-head-end = 1 + 0.5 + 0.3; legs: sqrt(1.04) + 1.
  EXPECT_NEAR(s.diameter(), std::sqrt(1.04) + 1.0, 1e-12);
}

TEST(Skeleton, LcaAgreesWithBruteForceOnRandomTrees) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Skeleton s = testing::random_skeleton(rng, 2 + trial * 3);
    for (int a = 0; a < s.joint_count(); ++a) {
      const auto ancestors_a = s.path_to_root(a);
      for (int b = 0; b < s.joint_count(); ++b) {
        const auto ancestors_b = s.path_to_root(b);
        // Brute force: the deepest joint on both root paths.
        int expected = 0;
        for (int x : ancestors_a) {
          if (std::find(ancestors_b.begin(), ancestors_b.end(), x) != ancestors_b.end()) {
            expected = x;
            break;
          }
        }
        ASSERT_EQ(s.lowest_common_ancestor(a, b), expected);
        const auto p = s.path(a, b);
        ASSERT_EQ(p.front(), a);
        ASSERT_EQ(p.back(), b);
        ASSERT_EQ(static_cast<int>(p.size()), s.depth(a) + s.depth(b) - 2 * s.depth(expected) + 1);
      }
    }
  }
}

TEST(Skeleton, ValidateRejectsBrokenTrees) {
  Skeleton s = small_tree();
  s.names[3] = "spine";
  EXPECT_THROW(s.validate(), std::invalid_argument);
  s = small_tree();
  s.parents[2] = 4;  // parent after child
  EXPECT_THROW(s.validate(), std::invalid_argument);
  EXPECT_THROW(Skeleton().validate(), std::invalid_argument);
}

TEST(ChannelLayout, EulerOrderAndReorder) {
  ChannelLayout layout = ChannelLayout::position_rotations(EulerOrder::ZXY);
  EXPECT_EQ(layout.count, 6);
  EXPECT_TRUE(layout.has_position());
  EXPECT_EQ(layout.euler_order(), EulerOrder::ZXY);
  const ChannelLayout reordered = layout.with_euler_order(EulerOrder::XYZ);
  EXPECT_EQ(reordered.euler_order(), EulerOrder::XYZ);
  EXPECT_EQ(reordered.channels[0], Channel::Xposition);
  // Two rotation channels: missing axes follow in X, Y, Z order.
  ChannelLayout partial;
  partial.push(Channel::Yrotation);
  partial.push(Channel::Xrotation);
  EXPECT_EQ(partial.euler_order(), EulerOrder::YXZ);
}

}  // namespace
}  // namespace nec
