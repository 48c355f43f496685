// The motors as commanded against eq. (6)'s closed form: a command acts its delay after its
// instant, and each motor then follows it through the first-order lag.
#include "rotorguard/fdd/commanded_motors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "rotorguard/core/rng.h"

namespace rotorguard::fdd {
namespace {

TEST(CommandedMotors, ACommandActsItsDelayLaterThroughTheMotorLag) {
  const double sigma = 0.03, delay = 0.0037;
  CommandedMotors motors(2, sigma, delay);
  motors.Start(0, RotorVector::Constant(2, 1.0));
  motors.OnCommand(2'000'000, RotorVector::Constant(2, 3.0));  // at 2 ms, acts at 5.7 ms
  for (TimeNs t = 1'000'000; t <= 60'000'000; t += 1'300'000) {  // an ESC's irregular samples
    const double s = ToSeconds(t), acts = 0.002 + delay;
    const double expected = s <= acts ? 1.0 : 3.0 - 2.0 * std::exp(-(s - acts) / sigma);
    EXPECT_NEAR(motors.AdvanceTo(t)[0], expected, 1e-12) << "t = " << s;
  }
  // A second command acts after the first, in order; an older one than the newest is ignored.
  motors.OnCommand(70'000'000, RotorVector::Constant(2, 0.0));
  motors.OnCommand(65'000'000, RotorVector::Constant(2, 9.0));
  const double before = motors.AdvanceTo(73'700'000)[1];
  EXPECT_NEAR(motors.AdvanceTo(90'000'000)[1], before * std::exp(-0.0163 / sigma), 1e-12);
}

TEST(CommandedMotors, RejectsANonPositiveTimeConstantOrANegativeDelay) {
  EXPECT_THROW(CommandedMotors(4, 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(CommandedMotors(4, 0.03, -0.001), std::invalid_argument);
  EXPECT_THROW(CommandedMotors(0, 0.03, 0.0), std::invalid_argument);
}

// The healthy thrust floor against eq. (6)'s exact solution for piecewise-constant commands: over
// 200 random command sequences and motors up to three times slower than the floor's time
// constant, no motor is ever below the floor of any window ending on it; and the floor is tight:
// the fastest motor under the lowest command sits on it.
TEST(HealthyThrustFloor, NoHealthyMotorFallsBelowItAndTheFastestUnderTheLowestCommandSitsOnIt) {
  Rng rng(11);
  const double step = 2.5e-4, sigma_min = 0.02;
  int checks = 0;
  for (int sequence = 0; sequence < 200; ++sequence) {
    const double sigma = sigma_min * rng.Uniform(1.0, 3.0);
    // The command in force over each step, held for 1-40 steps at a time.
    std::vector<double> u;
    while (u.size() < 400) {
      const double level = rng.Uniform(0.0, 10.0);
      const int hold = 1 + static_cast<int>(rng.Uniform(0.0, 40.0));
      for (int k = 0; k < hold; ++k) u.push_back(level);
    }
    u.resize(400);
    std::vector<double> thrust(u.size() + 1);
    thrust[0] = rng.Uniform(0.0, 10.0);
    for (std::size_t k = 0; k < u.size(); ++k) thrust[k + 1] = u[k] + (thrust[k] - u[k]) * std::exp(-step / sigma);
    for (int check = 0; check < 50; ++check) {
      const auto end = static_cast<std::size_t>(rng.Uniform(41.0, 400.0));
      const auto window = static_cast<std::size_t>(rng.Uniform(1.0, 40.0));
      const double lowest = *std::min_element(u.begin() + static_cast<std::ptrdiff_t>(end - window),
                                              u.begin() + static_cast<std::ptrdiff_t>(end));
      const double floor = HealthyThrustFloor(thrust[end - window], lowest, static_cast<double>(window) * step, sigma_min);
      ASSERT_GE(thrust[end], floor - 1e-12) << "sequence " << sequence << ", window " << window;
      ++checks;
    }
  }
  EXPECT_EQ(checks, 200 * 50);
  // Tight: the fastest motor, from 8 N under a constant 2 N command for 5 ms, and one below the
  // command (which rises: the floor is where it started).
  EXPECT_NEAR(HealthyThrustFloor(8.0, 2.0, 0.005, sigma_min), 2.0 + 6.0 * std::exp(-0.25), 1e-12);
  EXPECT_DOUBLE_EQ(HealthyThrustFloor(1.0, 2.0, 0.005, sigma_min), 1.0);
}

TEST(RotorHistory, TheLowestValueInForceOverAnIntervalIncludesTheOneAtItsStart) {
  RotorHistory history(2, 4);
  RotorVector lowest = RotorVector::Constant(2, -1.0);
  EXPECT_FALSE(history.LowestOver(0, 10, &lowest));  // nothing kept
  history.Push(10, (RotorVector(2) << 5.0, 1.0).finished());
  history.Push(20, (RotorVector(2) << 3.0, 4.0).finished());
  history.Push(30, (RotorVector(2) << 6.0, 6.0).finished());
  EXPECT_FALSE(history.LowestOver(5, 40, &lowest));  // reaches before the oldest kept
  EXPECT_EQ(lowest, RotorVector::Constant(2, -1.0));  // untouched
  ASSERT_TRUE(history.LowestOver(25, 40, &lowest));  // 20's is in force at 25
  EXPECT_EQ(lowest, (RotorVector(2) << 3.0, 4.0).finished());
  ASSERT_TRUE(history.LowestOver(10, 25, &lowest));  // 30's is after the interval
  EXPECT_EQ(lowest, (RotorVector(2) << 3.0, 1.0).finished());
  ASSERT_TRUE(history.LowestOver(30, 30, &lowest));
  EXPECT_EQ(lowest, RotorVector::Constant(2, 6.0));
  history.Push(25, RotorVector::Constant(2, 0.0));  // older than the latest: ignored
  history.Push(30, RotorVector::Constant(2, 7.0));  // the same instant: replaces
  ASSERT_TRUE(history.LowestOver(30, 35, &lowest));
  EXPECT_EQ(lowest, RotorVector::Constant(2, 7.0));
  history.Push(40, RotorVector::Constant(2, 8.0));
  history.Push(50, RotorVector::Constant(2, 9.0));  // full: 10's drops out
  EXPECT_FALSE(history.LowestOver(15, 50, &lowest));
  ASSERT_TRUE(history.LowestOver(20, 50, &lowest));
  EXPECT_EQ(lowest, (RotorVector(2) << 3.0, 4.0).finished());
  EXPECT_FALSE(history.LatestAtOrBefore(15));
  ASSERT_TRUE(history.LatestAtOrBefore(45));
  EXPECT_EQ(history.time(*history.LatestAtOrBefore(45)), 40);
  EXPECT_EQ(history.values(*history.LatestAtOrBefore(50)), RotorVector::Constant(2, 9.0));
  EXPECT_EQ(history.newest_time(), 50);
  EXPECT_THROW(RotorHistory(2, 1), std::invalid_argument);
}

}  // namespace
}  // namespace rotorguard::fdd
