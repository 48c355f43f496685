#include "rotorguard/core/filters.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace rotorguard {
namespace {

/// Steady-state amplitude of the filter's response to a unit sine at `f_hz`.
double Gain(double f_hz, double cutoff_hz, double rate_hz) {
  LowPass2<1> lp(cutoff_hz, rate_hz);
  double peak = 0.0;
  const int n = static_cast<int>(20.0 * rate_hz / std::min(f_hz, cutoff_hz)) + 2000;
  for (int k = 0; k < n; ++k) {
    const double y = lp.Step(Eigen::Matrix<double, 1, 1>(std::sin(2.0 * std::numbers::pi * f_hz * k / rate_hz)))[0];
    if (k > n / 2) peak = std::max(peak, std::abs(y));
  }
  return peak;
}

TEST(LowPass2, UnitDcGainAndButterworthMagnitude) {
  LowPass2<3> lp(20.0, 333.0);
  Eigen::Vector3d y;
  for (int k = 0; k < 500; ++k) y = lp.Step(Eigen::Vector3d(1.0, -2.0, 3.0));
  EXPECT_NEAR(y.x(), 1.0, 1e-9);
  EXPECT_NEAR(y.z(), 3.0, 1e-9);
  // |H| = 1/sqrt(2) at the cut-off (pre-warped bilinear transform), 1/sqrt(1 + (f/fc)^4) below.
  EXPECT_NEAR(Gain(20.0, 20.0, 333.0), 1.0 / std::sqrt(2.0), 0.01);
  EXPECT_NEAR(Gain(5.0, 20.0, 333.0), 1.0 / std::sqrt(1.0 + std::pow(0.25, 4)), 0.01);
  EXPECT_LT(Gain(100.0, 20.0, 333.0), 0.06);
}

TEST(LowPass2, RejectsCutoffsAboveNyquist) {
  EXPECT_THROW(LowPass2<1>(200.0, 333.0), std::invalid_argument);
  EXPECT_THROW(LowPass2<1>(0.0, 333.0), std::invalid_argument);
}

TEST(FilteredDerivative, RecoversTheSlopeOfARampWithIrregularSamples) {
  FilteredDerivative<3> d(20.0, 333.0);
  Eigen::Vector3d y;
  double t = 0.0;
  for (int k = 0; k < 1000; ++k) {
    const double dt = (k % 3 == 2) ? 0.004 : 0.003;  // a 333 Hz sensor polled at 1 kHz
    t += dt;
    y = d.Step(Eigen::Vector3d(2.0 * t, -t, 0.5), dt);
  }
  EXPECT_NEAR(y.x(), 2.0, 1e-6);
  EXPECT_NEAR(y.y(), -1.0, 1e-6);
  EXPECT_NEAR(y.z(), 0.0, 1e-9);
}

}  // namespace
}  // namespace rotorguard
