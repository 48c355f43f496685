// Statistics of campaigns and benchmarks against closed forms and hand-made samples.
#include "rotorguard/campaign/statistics.h"

#include <gtest/gtest.h>

#include <vector>

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

// Nearest rank on a hand-made sample (unsorted on input): 1..101 shuffled.
TEST(Percentile, NearestRankOfTheSortedSample) {
  std::vector<double> v;
  for (int k = 101; k >= 1; --k) v.push_back(k % 2 ? k : 102 - k);  // every value 1..101 once
  EXPECT_EQ(Percentile(v, 0.0), 1.0);
  EXPECT_EQ(Percentile(v, 0.5), 51.0);
  EXPECT_EQ(Percentile(v, 0.99), 100.0);
  EXPECT_EQ(Percentile(v, 1.0), 101.0);
  EXPECT_EQ(Percentile({}, 0.5), 0.0);
  EXPECT_EQ(Percentile({4.0, 1.0}, 0.5), 4.0) << "index round(0.5) = 1";
}

}  // namespace
}  // namespace rotorguard::campaign
