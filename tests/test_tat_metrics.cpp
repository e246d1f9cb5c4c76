// How much vertical motion a decoded clip keeps.
#include "nec/tat/metrics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace nec {
namespace {

using tat::HeightRangeKept;

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
