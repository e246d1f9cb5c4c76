// How much of the joints' turning and of the vertical motion a decoded clip keeps.
#include "nec/tat/metrics.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

namespace nec {
namespace {

using tat::HeightRangeKept;
using tat::ReconstructionMetrics;

// Θ (1, T, 3, 9) of a root, a joint turning about X by degrees[t] at frame t, and a padding joint; the root
// turns about Y by root_degrees at every frame.
at::Tensor turning_clip(const std::vector<double>& degrees, double root_degrees = 0.0) {
  const int64_t t = static_cast<int64_t>(degrees.size());
  at::Tensor f = torch::zeros({1, t, 3, 9});
  const auto set = [&](int64_t frame, int64_t joint, double angle, bool about_y) {
    const double c = std::cos(angle * M_PI / 180.0), s = std::sin(angle * M_PI / 180.0);
    // rot6D: the first two columns of the rotation matrix.
    const std::vector<double> six = about_y ? std::vector<double>{c, 0, -s, 0, 1, 0} : std::vector<double>{1, 0, 0, 0, c, s};
    for (int k = 0; k < 6; ++k) f[0][frame][joint][3 + k] = six[static_cast<size_t>(k)];
  };
  for (int64_t frame = 0; frame < t; ++frame) {
    set(frame, 0, root_degrees, true);
    set(frame, 1, degrees[static_cast<size_t>(frame)], false);
    set(frame, 2, 90.0, false);  // padding: never counted
  }
  return f;
}

double turning_kept(const at::Tensor& prediction, const at::Tensor& truth) {
  ReconstructionMetrics m;
  const at::Tensor parents = torch::tensor({-1L, 0L, 1L}).view({1, 3});
  const at::Tensor offsets = torch::tensor({0.0f, 0.0f, 0.0f, 0.0f, 0.3f, 0.0f, 0.0f, 0.3f, 0.0f}).view({1, 3, 3});
  const at::Tensor joints = torch::tensor({true, true, false}).view({1, 3});
  m.add(prediction, truth, parents, offsets, joints, torch::ones({1, truth.size(1)}, torch::kBool));
  return m.pose_turn_kept();
}

TEST(ReconstructionMetrics, TurningKeptIsZeroForAStillBodyAndOneForTheRealMotion) {
  const at::Tensor wave = turning_clip({0, 20, 40, 60, 40, 20});
  EXPECT_NEAR(turning_kept(wave, wave), 1.0, 1e-6);
  EXPECT_NEAR(turning_kept(turning_clip({0, 0, 0, 0, 0, 0}), wave), 0.0, 1e-6);
  EXPECT_NEAR(turning_kept(turning_clip({0, 10, 20, 30, 20, 10}), wave), 0.5, 1e-6);
  // The root's own turning is its heading and lean, not the pose: a turning root keeps nothing.
  EXPECT_NEAR(turning_kept(turning_clip({0, 0, 0, 0, 0, 0}, 45.0), wave), 0.0, 1e-6);
  EXPECT_EQ(ReconstructionMetrics{}.pose_turn_kept(), 0.0);  // nothing added yet
}

// Θ of a one-joint clip whose root stands at heights[t] (Δy per frame; frame 0 holds the height).
Features clip_at_heights(const std::vector<double>& heights) {
  Features f;
  f.frame_count = static_cast<int>(heights.size());
  f.joint_count = 1;
  f.data.assign(heights.size() * kFeatureSize, 0.0f);
  for (int t = 0; t < f.frame_count; ++t) {
    f.at(t, 0, 1) = static_cast<float>(t == 0 ? heights[0] : heights[t] - heights[t - 1]);
    f.at(t, 0, 3) = 1.0f;
    f.at(t, 0, 7) = 1.0f;
  }
  return f;
}

TEST(HeightRangeKept, RootHeightsSumTheRises) {
  const std::vector<double> heights{0.5, 0.55, 0.9, 0.4, 0.5};
  const std::vector<double> back = root_heights(clip_at_heights(heights));
  ASSERT_EQ(back.size(), heights.size());
  for (size_t t = 0; t < heights.size(); ++t) EXPECT_NEAR(back[t], heights[t], 1e-6);
  EXPECT_EQ(root_heights(clip_at_heights(heights), 2).size(), 2u);
  EXPECT_THROW(root_heights(clip_at_heights(heights), 6), std::out_of_range);
}

TEST(HeightRangeKept, RatioOfRangesOverClipsThatMoveVertically) {
  const Features jump = clip_at_heights({0.5, 0.5, 0.7, 0.9, 0.6, 0.5});  // range 0.4
  HeightRangeKept kept;
  kept.add(jump, jump);                                                  // all of it: 1
  kept.add(clip_at_heights({0.45, 0.45, 0.45, 0.45, 0.45, 0.45}), jump);  // stood still: 0
  kept.add(clip_at_heights({0.5, 0.5, 0.6, 0.6, 0.5, 0.5}), jump);        // a quarter
  ASSERT_EQ(kept.ratios.size(), 3u);
  EXPECT_NEAR(kept.ratios[0], 1.0, 1e-6);
  EXPECT_NEAR(kept.ratios[1], 0.0, 1e-6);
  EXPECT_NEAR(kept.ratios[2], 0.25, 1e-6);
  EXPECT_NEAR(kept.median(), 0.25, 1e-6);
  // A walk's bob (range 0.02 < min_range) is not counted, whatever comes back.
  kept.add(clip_at_heights({0.5, 0.5, 0.9, 0.5, 0.5, 0.5}), clip_at_heights({0.5, 0.51, 0.52, 0.51, 0.5, 0.5}));
  EXPECT_EQ(kept.ratios.size(), 3u);
  // Only the frames both clips have are compared.
  HeightRangeKept shorter;
  shorter.add(clip_at_heights({0.5, 0.5, 0.7}), jump);
  ASSERT_EQ(shorter.ratios.size(), 1u);
  EXPECT_NEAR(shorter.ratios[0], 1.0, 1e-6);
  EXPECT_EQ(HeightRangeKept{}.median(), 0.0);
}

}  // namespace
}  // namespace nec
