// Summary statistics (common/statistics.h): the quantile's rank rule, which the median shares.
#include "svbtdf/common/statistics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace svbtdf::common {
namespace {

TEST(Quantile, IsTheValueOfRankFloorQnAndTheMaximumAtOne) {
  const std::vector<double> values = {5, 1, 4, 2, 3};  // sorted: 1 2 3 4 5
  EXPECT_EQ(Quantile(values, 0.0), 1);
  EXPECT_EQ(Quantile(values, 0.5), 3);   // rank 2
  EXPECT_EQ(Quantile(values, 0.9), 5);   // rank 4
  EXPECT_EQ(Quantile(values, 1.0), 5);
  EXPECT_EQ(Quantile(values, 7.0), 5);   // clamped
  EXPECT_TRUE(std::isnan(Quantile({}, 0.5)));
}

TEST(Median, IsTheUpperMedianOfAnEvenCount) {
  EXPECT_EQ(Median({4, 1, 3, 2}), 3);
  EXPECT_EQ(Median({2, 1, 3}), 2);
  EXPECT_TRUE(std::isnan(Median({})));
}

}  // namespace
}  // namespace svbtdf::common
