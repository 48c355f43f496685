#include "rotorguard/core/stopwatch.h"

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"

namespace rotorguard {
namespace {

// Laps split the time without losing any: the laps of an inner watch add up to no more than an
// outer watch started before it and read after it (steady_clock never runs backwards).
TEST(Stopwatch, LapsAreNonNegativeAndAddUpToAtMostTheWhole) {
  const Stopwatch outer;
  Stopwatch inner;
  double laps = 0.0;
  volatile double sink = 0.0;
  for (int k = 0; k < 100; ++k) {
    for (int i = 0; i < 1000; ++i) sink = sink + 1.0;
    const double lap = inner.Restart();
    EXPECT_GE(lap, 0.0);
    laps += lap;
  }
  laps += inner.seconds();
  EXPECT_GT(laps, 0.0);
  EXPECT_LE(laps, outer.seconds());
  EXPECT_GE(outer.milliseconds(), 1e3 * laps);
}

TEST(BrokenRule, GivesTheValidationMessageOrNothing) {
  EXPECT_FALSE(BrokenRule([] {}).has_value());
  const auto broken = BrokenRule([] { ThrowValidation("Options", "rate_hz", -1, "> 0"); });
  ASSERT_TRUE(broken.has_value());
  EXPECT_EQ(*broken, "Options::rate_hz = -1 is invalid; expected > 0");
  // Other exceptions are not a broken rule: they pass through.
  EXPECT_THROW(BrokenRule([] { throw std::runtime_error("disk full"); }), std::runtime_error);
}

}  // namespace
}  // namespace rotorguard
