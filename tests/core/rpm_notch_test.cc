// The notches against their closed forms: a notch removes a tone at its centre, passes DC and far
// tones unchanged, halves the power half a width away; a bank fed a rotor's speed removes its
// harmonics where sampling aliases them, and stays bounded when the speeds it follows are noisy.
#include "rotorguard/core/rpm_notch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/filters.h"
#include "rotorguard/core/rng.h"
#include "test_util.h"

namespace rotorguard {
namespace {

/// The steady amplitude of a unit tone at f through a notch at `centre` of width `width`, at fs.
double NotchGain(double f, double centre, double width, double fs) {
  Notch2<4> notch;
  notch.SetCentre(centre, width, fs);
  double peak = 0.0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    const double x = std::sin(2.0 * std::numbers::pi * f * k / fs);
    const double y = notch.Step(Eigen::Vector4d::Constant(x))[0];
    if (k > n / 2) peak = std::max(peak, std::abs(y));
  }
  return peak;
}

TEST(Notch2, RemovesItsCentrePassesDcAndHalvesThePowerHalfAWidthAway) {
  const double fs = 333.0;
  EXPECT_LT(NotchGain(74.0, 74.0, 20.0, fs), 1e-3);
  // The -3 dB edges lie exactly a width apart, about the centre though not symmetrically: half a
  // width away the gain is 1/sqrt(2) to 2 %.
  EXPECT_NEAR(NotchGain(84.0, 74.0, 20.0, fs), 1.0 / std::sqrt(2.0), 0.02);
  EXPECT_NEAR(NotchGain(5.0, 74.0, 20.0, fs), 1.0, 0.01);
  Notch2<4> notch;
  notch.SetCentre(74.0, 20.0, fs);
  Eigen::Vector4d y;
  for (int k = 0; k < 2000; ++k) y = notch.Step(Eigen::Vector4d(1.0, -2.0, 3.0, 0.5));
  EXPECT_NEAR(y[1], -2.0, 1e-12) << "unit gain at DC";
  RG_EXPECT_THROW_WITH(notch.SetCentre(170.0, 20.0, fs), std::invalid_argument, "below Nyquist");
}

TEST(RpmNotchBank, RemovesARotorsHarmonicsWhereTheyAliasAndStaysBoundedOnNoisySpeeds) {
  RpmNotchOptions o;
  o.sample_rate_hz = 333.0;
  RpmNotchBank<4> bank(1, o);
  // A rotor at 1500 rad/s: 238.7 Hz, aliased to 94.3 Hz; its blade pass at 477.5 Hz to 144.5 Hz.
  const double omega = 1500.0, fs = o.sample_rate_hz;
  const double f1 = AliasedFrequency(omega / (2.0 * std::numbers::pi), fs);
  const double f2 = AliasedFrequency(2.0 * omega / (2.0 * std::numbers::pi), fs);
  ASSERT_NEAR(f1, 94.3, 0.1);
  ASSERT_NEAR(f2, 144.5, 0.1);
  bank.OnRotorSpeeds(0, RotorVector::Constant(1, omega));
  double peak = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double t = k / fs;
    // What the IMU samples: the rotor's tone and its blade pass, and the flight's slow motion.
    const double x = std::cos(omega * t) + std::cos(2.0 * omega * t + 0.3);
    const double y = bank.Filter(Eigen::Vector4d::Constant(x + 0.5 * std::sin(2.0 * t)))[0];
    if (k > 10000) peak = std::max(peak, std::abs(y - 0.5 * std::sin(2.0 * t)));
  }
  EXPECT_LT(peak, 0.02) << "the tones gone, the slow motion kept";
  // Speeds noisy sample by sample near Nyquist (a 24-rotor assembly hovering at 1030 rad/s put
  // notches there): the output stays within the input's bounds times the notches' overshoot.
  RpmNotchBank<4> noisy(24, o);
  Rng rng(3);
  double largest = 0.0;
  for (int k = 0; k < 20000; ++k) {
    RotorVector speeds(24);
    for (int i = 0; i < 24; ++i) speeds[i] = 1030.0 + 10.0 * rng.Normal();
    noisy.OnRotorSpeeds(static_cast<TimeNs>(k) * 1'000'000, speeds);
    if (k % 3 == 0) {
      const double y = noisy.Filter(Eigen::Vector4d::Constant(rng.Normal()))[0];
      largest = std::max(largest, std::abs(y));
    }
  }
  EXPECT_LT(largest, 10.0);
}

}  // namespace
}  // namespace rotorguard
