// Order statistics.
#include "nec/motion/statistics.h"

#include <gtest/gtest.h>

namespace nec {
namespace {

TEST(Statistics, MedianOfOddAndEvenCounts) {
  EXPECT_EQ(median({}), 0.0);
  EXPECT_EQ(median({4.0}), 4.0);
  EXPECT_EQ(median({3.0, -1.0, 2.0}), 2.0);
  EXPECT_EQ(median({3.0, 1.0, 2.0, 10.0}), 2.5);  // the mean of the two middle values, not either one
  EXPECT_EQ(median({5.0, 5.0, 1.0, 9.0, 5.0, 0.0}), 5.0);
}

}  // namespace
}  // namespace nec
