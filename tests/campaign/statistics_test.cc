// Statistics of campaigns and benchmarks against closed forms and hand-made samples.
#include "rotorguard/campaign/statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "test_util.h"

namespace rotorguard::campaign {
namespace {

TEST(WilsonInterval, MatchesTheClosedFormAtKnownPoints) {
  // 0 of 10: [0, z^2 / (n + z^2)] = [0, 0.2775]; 10 of 10 mirrors it; 5 of 10: 0.5 -+ 0.2866.
  EXPECT_NEAR(WilsonInterval(0, 10).first, 0.0, 1e-12);
  EXPECT_NEAR(WilsonInterval(0, 10).second, 0.27753, 1e-4);
  EXPECT_NEAR(WilsonInterval(10, 10).first, 1.0 - 0.27753, 1e-4);
  EXPECT_NEAR(WilsonInterval(5, 10).first, 0.23659, 1e-4);
  EXPECT_NEAR(WilsonInterval(5, 10).second, 0.76341, 1e-4);
}

// Hand-made samples (unsorted on input) against numpy.percentile's default (linear, type 7):
// 1..101 shuffled lands on ranks exactly; the others interpolate.
TEST(McNemarExactP, IsTheTwoSidedBinomialTailOfTheDiscordantPairs) {
  // Closed forms: 1 vs 9 discordant pairs, 2 (1 + 10) / 2^10; 2 vs 10, 2 (1 + 12 + 66) / 2^12.
  EXPECT_NEAR(McNemarExactP(1, 9), 22.0 / 1024.0, 1e-14);
  EXPECT_NEAR(McNemarExactP(10, 2), 158.0 / 4096.0, 1e-14);
  EXPECT_EQ(McNemarExactP(0, 0), 1.0);
  EXPECT_EQ(McNemarExactP(5, 5), 1.0);  // an even split: the doubled tail exceeds 1
  EXPECT_NEAR(McNemarExactP(0, 7), 2.0 / 128.0, 1e-15);
  // Thousands of pairs: finite, symmetric, and tiny for a lopsided split.
  EXPECT_EQ(McNemarExactP(1200, 1500), McNemarExactP(1500, 1200));
  EXPECT_GT(McNemarExactP(1200, 1500), 0.0);
  EXPECT_LT(McNemarExactP(1200, 1500), 1e-7);
  EXPECT_THROW(McNemarExactP(-1, 3), std::invalid_argument);
}

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

}  // namespace
}  // namespace rotorguard::campaign
