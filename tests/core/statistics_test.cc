// Quantiles against hand-made samples and numpy's default (type 7).
#include "rotorguard/core/statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "test_util.h"

namespace rotorguard {
namespace {

TEST(Percentile, InterpolatesBetweenTheClosestRanksOfTheSortedSample) {
  std::vector<double> v;
  for (int k = 101; k >= 1; --k) v.push_back(k % 2 ? k : 102 - k);  // every value 1..101 once
  EXPECT_EQ(Percentile(v, 0.0), 1.0);
  EXPECT_EQ(Percentile(v, 0.5), 51.0);
  EXPECT_EQ(Percentile(v, 0.99), 100.0);
  EXPECT_EQ(Percentile(v, 1.0), 101.0);
  EXPECT_DOUBLE_EQ(Percentile(v, 0.995), 100.5);
  EXPECT_EQ(Percentile({}, 0.5), 0.0);
  EXPECT_EQ(Percentile({4.0, 1.0}, 0.5), 2.5) << "the mean of the middle two";
  EXPECT_EQ(Percentile({3.0, 1.0, 4.0, 2.0}, 0.25), 1.75);  // np.percentile([1, 2, 3, 4], 25)
  EXPECT_EQ(Percentile({7.0}, 0.99), 7.0);
}

TEST(Percentile, TakesAFractionNotAPercentage) {
  RG_EXPECT_THROW_WITH(Percentile({1.0, 2.0}, 99.0), std::invalid_argument,
                       "p = 99 is invalid; expected a fraction in [0, 1]");
  EXPECT_THROW(Percentile({1.0}, -0.1), std::invalid_argument);
  EXPECT_THROW(Percentile({1.0}, std::nan("")), std::invalid_argument);
}

// The mean of a hand-made sample, and 0 for none (as Percentile's empty sample).
TEST(Mean, IsTheSumOverTheCount) {
  EXPECT_EQ(Mean({1.0, 2.0, 6.0}), 3.0);
  EXPECT_EQ(Mean({-0.5}), -0.5);
  EXPECT_EQ(Mean({}), 0.0);
}

}  // namespace
}  // namespace rotorguard
