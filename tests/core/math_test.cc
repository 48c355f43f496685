#include "rotorguard/core/math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

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

// The logarithm inverts Eigen's angle-axis rotation (the shortest arc, also for a quaternion
// with w < 0), from zero to just below pi.
TEST(LogSO3, InvertsTheAngleAxisRotation) {
  Rng rng(5);
  for (const double angle : {0.0, 1e-9, 1e-6, 1e-3, 0.3, 2.0, 3.14}) {
    for (int k = 0; k < 20; ++k) {
      const Vector3 axis = Vector3(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)).normalized();
      Quaternion q(Eigen::AngleAxisd(angle, axis));
      if (k % 2) q.coeffs() = -q.coeffs();  // the same rotation
      EXPECT_LT((LogSO3(q) - angle * axis).norm(), 1e-13) << "angle " << angle;
    }
  }
}

// The inverse right Jacobian against central differences of Log(Exp(θ) Exp(δ)) in δ, on both
// sides of the series' threshold and up to 3 rad; the differences' error is O(h²) ≈ 1e-10.
TEST(InverseRightJacobianSO3, MatchesFiniteDifferencesOfTheLogarithm) {
  Rng rng(6);
  const double h = 1e-5;
  for (const double angle : {0.0, 1e-6, 0.03, 0.0499, 0.0501, 0.5, 2.0, 3.0}) {
    for (int k = 0; k < 10; ++k) {
      const Vector3 theta = angle * Vector3(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)).normalized();
      const Quaternion q(ExpSO3(theta));
      Matrix3 numeric;
      for (int j = 0; j < 3; ++j) {
        const Vector3 d = h * Vector3::Unit(j);
        numeric.col(j) = (LogSO3(q * Quaternion(ExpSO3(d))) - LogSO3(q * Quaternion(ExpSO3(-d)))) / (2.0 * h);
      }
      EXPECT_LT((InverseRightJacobianSO3(theta) - numeric).cwiseAbs().maxCoeff(), 1e-8) << "angle " << angle;
    }
  }
}

// The vector form against the matrix it stands for, on both sides of the series' threshold.
TEST(ExpSO3Times, EqualsTheMatrixTimesTheVector) {
  Rng rng(4);
  for (const double angle : {0.0, 1e-6, 0.03, 0.0501, 0.7, 3.0}) {
    for (int k = 0; k < 20; ++k) {
      const Vector3 axis = Vector3(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)).normalized();
      const Vector3 v(rng.Uniform(-5, 5), rng.Uniform(-5, 5), rng.Uniform(-5, 5));
      const Vector3 truth = Eigen::AngleAxisd(angle, axis).toRotationMatrix() * v;
      EXPECT_LT((ExpSO3Times(angle * axis, v) - truth).cwiseAbs().maxCoeff(), 1e-14) << "angle " << angle;
    }
  }
}

// Against the C library's sin and cos (the truth, correctly rounded in practice) across whole
// turns, at the quarter turns and the eighths where the reduction changes sides, and for u
// outside [0, 1): within 2 eps max(1, angle) (a coefficient of the wrong sign leaves 1e-7 or more).
TEST(SinCosOfTurns, MatchesTheLibraryWithinTwoEpsilon) {
  Rng rng(5);
  std::vector<double> turns;
  for (int k = 0; k < 20000; ++k) turns.push_back(rng.Uniform());
  for (int q = -8; q <= 16; ++q) {
    for (const double d : {-1e-12, 0.0, 1e-12}) turns.push_back(q / 8.0 + d);
  }
  for (const double u : {-3.7, 12.3, 1e6 + 0.1}) turns.push_back(u);
  for (const double u : turns) {
    double s = 0.0, c = 0.0;
    SinCosOfTurns(u, &s, &c);
    const double angle = 2.0 * std::numbers::pi * (u - std::floor(u));
    // The angle itself carries a rounding of 2 pi times up to 1: compare with its own ulp as the scale.
    const double ulp = 2.0 * std::numeric_limits<double>::epsilon();
    EXPECT_NEAR(s, std::sin(angle), ulp * std::max(1.0, angle)) << "u = " << u;
    EXPECT_NEAR(c, std::cos(angle), ulp * std::max(1.0, angle)) << "u = " << u;
  }
}

}  // namespace
}  // namespace rotorguard
