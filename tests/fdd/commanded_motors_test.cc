// The motors as commanded against eq. (6)'s closed form: a command acts its delay after its
// instant, and each motor then follows it through the first-order lag.
#include "rotorguard/fdd/commanded_motors.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace rotorguard::fdd
