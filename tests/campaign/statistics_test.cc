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

}  // namespace
}  // namespace rotorguard::campaign
