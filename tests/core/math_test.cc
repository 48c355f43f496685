#include "rotorguard/core/math.h"

#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/core/rng.h"

namespace rotorguard {
namespace {

// The exponential against Eigen's angle-axis rotation, on both sides of the series' threshold
// (0.05 rad) and down to zero: the matrices agree to a few units of rounding (a dropped series term would leave 1e-12).
TEST(ExpSO3, MatchesAngleAxisOnBothSidesOfTheSeriesThreshold) {
  Rng rng(3);
  for (const double angle : {0.0, 1e-9, 1e-4, 0.01, 0.0499, 0.05, 0.0501, 0.3, 1.0, 3.0}) {
    for (int k = 0; k < 20; ++k) {
      const Vector3 axis = Vector3(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)).normalized();
      const Matrix3 truth = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
      EXPECT_LT((ExpSO3(angle * axis) - truth).cwiseAbs().maxCoeff(), 2e-15) << "angle " << angle;
    }
  }
}

}  // namespace
}  // namespace rotorguard
