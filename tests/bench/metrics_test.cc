#include "rotorguard/bench/metrics.h"

#include <cmath>

#include <gtest/gtest.h>

namespace rotorguard::bench {
namespace {

TEST(TrackingError, RmseAndPaperEq37OnAHandMadeLog) {
  // 1 s at error 0.3 m then 3 s at error 0.1 m: integral = 0.09 + 0.03 = 0.12 over 4 s.
  TrackingErrorAccumulator acc;
  for (int i = 0; i < 100; ++i) acc.Add(0.01, Vector3(0.3, 0, 0), Vector3::Zero());
  for (int i = 0; i < 300; ++i) acc.Add(0.01, Vector3(0, 0.06, 0.08), Vector3::Zero());
  EXPECT_NEAR(acc.duration(), 4.0, 1e-12);
  EXPECT_NEAR(acc.rmse(), std::sqrt(0.12 / 4.0), 1e-12);
  EXPECT_NEAR(acc.rmse_eq37(), std::sqrt(0.12) / 4.0, 1e-12);
  EXPECT_NEAR(acc.max_error(), 0.3, 1e-15);
}

TEST(TrackingError, EmptyIsZeroNotNan) {
  const TrackingErrorAccumulator acc;
  EXPECT_EQ(acc.rmse(), 0.0);
  EXPECT_EQ(acc.rmse_eq37(), 0.0);
}

}  // namespace
}  // namespace rotorguard::bench
