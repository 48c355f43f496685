#include "rotorguard/planning/references.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.h"

namespace rotorguard::planning {
namespace {

using ::rotorguard::testing::MatricesNear;

constexpr double kPi = std::numbers::pi;

// ----- shared checks

/// Step of the central differences: truncation error h^2/6 |f'''| stays below 1e-7 even on the
/// shortest ramps tested (|f'''| ~ 1e3 there), round-off eps |f| / h ~ 1e-9 for |f| <= 10.
constexpr double kFdStep = 1e-5;

/// Sample times spread over [0, t_end] with an irregular step so they rarely land on round numbers.
std::vector<double> SampleTimes(double t_end, double step = 0.0173) {
  std::vector<double> times;
  for (double t = 0.0031; t <= t_end; t += step) times.push_back(t);
  return times;
}

/// Velocity, acceleration and jerk equal the central differences of position, velocity and
/// acceleration at every sample time farther than a few steps from t = 0 and from `breakpoints`
/// (where a derivative may jump).
void ExpectDerivativesMatchFiniteDifferences(const ReferenceTrajectory& ref, double t_end,
                                             const std::vector<double>& breakpoints = {}) {
  const double h = kFdStep;
  double worst[3] = {0.0, 0.0, 0.0};
  double worst_t[3] = {0.0, 0.0, 0.0};
  int checked = 0;
  for (double t : SampleTimes(t_end)) {
    if (t < 3.0 * h) continue;
    const bool near_break = std::any_of(breakpoints.begin(), breakpoints.end(),
                                        [&](double b) { return std::abs(t - b) < 3.0 * h; });
    if (near_break) continue;
    const ReferencePoint r = ref.Evaluate(t);
    const ReferencePoint rp = ref.Evaluate(t + h);
    const ReferencePoint rm = ref.Evaluate(t - h);
    const Vector3 fd[3] = {(rp.p_W - rm.p_W) / (2.0 * h), (rp.v_W - rm.v_W) / (2.0 * h),
                           (rp.a_W - rm.a_W) / (2.0 * h)};
    const Vector3 analytic[3] = {r.v_W, r.a_W, r.j_W};
    for (int k = 0; k < 3; ++k) {
      // Relative to the size of the derivative, absolute near zero.
      const double err = (fd[k] - analytic[k]).norm() / (1.0 + analytic[k].norm());
      if (err > worst[k]) {
        worst[k] = err;
        worst_t[k] = t;
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 100);
  const char* names[3] = {"velocity", "acceleration", "jerk"};
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT(worst[k], 1e-6) << names[k] << " differs from the finite difference at t = "
                              << worst_t[k];
  }
}

/// No NaN or infinity for t in [0, 100], far beyond the duration, and for negative t.
void ExpectFiniteEverywhere(const ReferenceTrajectory& ref) {
  std::vector<double> times;
  for (double t = 0.0; t <= 100.0; t += 0.01) times.push_back(t);
  for (double t : {-1.0, 1e3, 1e6, 1e9}) times.push_back(t);
  if (std::isfinite(ref.duration())) {
    for (double dt : {0.0, 1e-9, 0.5, 10.0, 1e4}) times.push_back(ref.duration() + dt);
  }
  for (double t : times) {
    const ReferencePoint r = ref.Evaluate(t);
    ASSERT_TRUE(r.p_W.allFinite() && r.v_W.allFinite() && r.a_W.allFinite() &&
                r.j_W.allFinite() && std::isfinite(r.yaw) && std::isfinite(r.yaw_rate))
        << "non-finite reference at t = " << t;
  }
}

void ExpectAtRest(const ReferencePoint& r, double tol = 1e-12) {
  EXPECT_TRUE(MatricesNear(r.v_W, Vector3::Zero(), tol));
  EXPECT_TRUE(MatricesNear(r.a_W, Vector3::Zero(), tol));
}

/// Holds the point at `t` for every later sample after the duration.
void ExpectHoldsAfterDuration(const ReferenceTrajectory& ref, const Vector3& p) {
  const double d = ref.duration();
  ASSERT_TRUE(std::isfinite(d));
  for (double t : {d, d + 1e-6, d + 1.0, d + 1e3}) {
    const ReferencePoint r = ref.Evaluate(t);
    EXPECT_TRUE(MatricesNear(r.p_W, p, 1e-12)) << "t = " << t;
    ExpectAtRest(r, 0.0);
    EXPECT_TRUE(MatricesNear(r.j_W, Vector3::Zero(), 0.0));
  }
}

// ----- hover

TEST(HoverReferenceTest, HoldsPositionAndYaw) {
  const HoverReference ref({.position_m = Vector3(1.0, -2.0, 3.0), .yaw_rad = 0.7});
  EXPECT_EQ(ref.duration(), 0.0);
  for (double t : {-1.0, 0.0, 1.0, 50.0, 1e6}) {
    const ReferencePoint r = ref.Evaluate(t);
    EXPECT_TRUE(MatricesNear(r.p_W, Vector3(1.0, -2.0, 3.0), 0.0));
    ExpectAtRest(r, 0.0);
    EXPECT_TRUE(MatricesNear(r.j_W, Vector3::Zero(), 0.0));
    EXPECT_EQ(r.yaw, 0.7);
    EXPECT_EQ(r.yaw_rate, 0.0);
  }
  ExpectDerivativesMatchFiniteDifferences(ref, 100.0);
  ExpectFiniteEverywhere(ref);
}

TEST(HoverReferenceTest, RejectsInvalidOptions) {
  RG_EXPECT_THROW_WITH((void)HoverReference({.position_m = Vector3(0.0, NAN, 0.0)}),
                       std::invalid_argument, "HoverOptions::position_m");
  RG_EXPECT_THROW_WITH((void)HoverReference({.yaw_rad = INFINITY}), std::invalid_argument,
                       "HoverOptions::yaw_rad = inf is invalid; expected a finite value");
}

// ----- takeoff

TEST(TakeoffReferenceTest, ClimbsFromRestToRestWithPeakSpeed) {
  const TakeoffOptions o{.start_m = Vector3(1.0, 2.0, 0.5), .altitude_m = 3.0,
                         .max_speed_m_s = 0.8, .yaw_rad = -0.3};
  const TakeoffReference ref(o);
  const double T = 1.875 * 3.0 / 0.8;
  EXPECT_DOUBLE_EQ(ref.duration(), T);

  const ReferencePoint start = ref.Evaluate(0.0);
  EXPECT_TRUE(MatricesNear(start.p_W, o.start_m, 0.0));
  ExpectAtRest(start, 0.0);
  const Vector3 top = o.start_m + Vector3(0.0, 0.0, 3.0);
  const ReferencePoint end = ref.Evaluate(T * (1.0 - 1e-12));  // just before the end
  EXPECT_TRUE(MatricesNear(end.p_W, top, 1e-9));
  ExpectAtRest(end, 1e-9);
  ExpectHoldsAfterDuration(ref, top);

  // Peak speed at mid-climb equals max_speed; nowhere faster. Purely vertical, monotonic.
  EXPECT_NEAR(ref.Evaluate(0.5 * T).v_W.z(), 0.8, 1e-12);
  double peak = 0.0;
  double last_z = o.start_m.z();
  for (int i = 0; i <= 100000; ++i) {
    const ReferencePoint r = ref.Evaluate(T * i / 100000.0);
    peak = std::max(peak, r.v_W.norm());
    EXPECT_GE(r.p_W.z(), last_z - 1e-15);
    last_z = r.p_W.z();
    ASSERT_EQ(r.p_W.x(), 1.0);
    ASSERT_EQ(r.p_W.y(), 2.0);
    ASSERT_EQ(r.yaw, -0.3);
    ASSERT_EQ(r.yaw_rate, 0.0);
  }
  EXPECT_NEAR(peak, 0.8, 1e-12);
}

TEST(TakeoffReferenceTest, DerivativesAreConsistent) {
  const TakeoffReference ref({.altitude_m = 2.0, .max_speed_m_s = 1.5});
  // The quintic's jerk jumps at both ends of the climb; everything else is smooth.
  ExpectDerivativesMatchFiniteDifferences(ref, ref.duration() + 5.0, {0.0, ref.duration()});
  ExpectFiniteEverywhere(ref);
  // The default speed is 0.5 m/s.
  EXPECT_DOUBLE_EQ(TakeoffReference(TakeoffOptions{.altitude_m = 1.0}).duration(), 3.75);
}

TEST(TakeoffReferenceTest, ANegativeAltitudeDescendsToRestAsTheMirrorOfTheClimb) {
  const TakeoffReference down({.start_m = Vector3(1, 2, 2), .altitude_m = -2.0, .max_speed_m_s = 0.4});
  const TakeoffReference up({.start_m = Vector3(1, 2, 0), .altitude_m = 2.0, .max_speed_m_s = 0.4});
  EXPECT_DOUBLE_EQ(down.duration(), 1.875 * 2.0 / 0.4);
  for (double t = 0.0; t <= down.duration() + 1.0; t += 0.37) {
    // z_down(t) = 2 - z_up(t): the same quintic, mirrored.
    EXPECT_NEAR(down.Evaluate(t).p_W.z(), 2.0 - up.Evaluate(t).p_W.z(), 1e-12);
    EXPECT_NEAR(down.Evaluate(t).v_W.z(), -up.Evaluate(t).v_W.z(), 1e-12);
    EXPECT_GE(down.Evaluate(t).v_W.z(), -0.4 - 1e-12);
  }
  EXPECT_NEAR(down.Evaluate(down.duration()).p_W.z(), 0.0, 1e-12);
}

TEST(TakeoffReferenceTest, RejectsInvalidOptions) {
  RG_EXPECT_THROW_WITH((void)TakeoffReference({.altitude_m = 0.0}), std::invalid_argument,
                       "TakeoffOptions::altitude_m = 0 is invalid; expected a finite nonzero height");
  RG_EXPECT_THROW_WITH((void)TakeoffReference({.altitude_m = NAN}), std::invalid_argument,
                       "TakeoffOptions::altitude_m");
  RG_EXPECT_THROW_WITH((void)TakeoffReference({.max_speed_m_s = -1.0}), std::invalid_argument,
                       "TakeoffOptions::max_speed_m_s = -1 is invalid; expected > 0");
  RG_EXPECT_THROW_WITH((void)TakeoffReference({.max_speed_m_s = NAN}), std::invalid_argument,
                       "TakeoffOptions::max_speed_m_s");
  RG_EXPECT_THROW_WITH((void)TakeoffReference({.start_m = Vector3(INFINITY, 0.0, 0.0)}),
                       std::invalid_argument, "TakeoffOptions::start_m");
  RG_EXPECT_THROW_WITH((void)TakeoffReference({.yaw_rad = NAN}), std::invalid_argument,
                       "TakeoffOptions::yaw_rad");
}

// ----- lemniscate

/// Min and max of every coordinate of position, and the max speed, over [t0, t0 + span].
struct SampledExtent {
  Vector3 min = Vector3::Constant(std::numeric_limits<double>::infinity());
  Vector3 max = -Vector3::Constant(std::numeric_limits<double>::infinity());
  double max_speed = 0.0;
};
SampledExtent Sample(const ReferenceTrajectory& ref, double t0, double span, int n) {
  SampledExtent e;
  for (int i = 0; i <= n; ++i) {
    const ReferencePoint r = ref.Evaluate(t0 + span * i / n);
    e.min = e.min.cwiseMin(r.p_W);
    e.max = e.max.cwiseMax(r.p_W);
    e.max_speed = std::max(e.max_speed, r.v_W.norm());
  }
  return e;
}

TEST(LemniscateReferenceTest, DefaultsArePaperFigureEight) {
  const LemniscateOptions o;
  EXPECT_EQ(o.size_x_m, 6.0);
  EXPECT_EQ(o.size_y_m, 3.0);
  EXPECT_EQ(o.size_z_m, 1.0);
  EXPECT_EQ(o.max_speed_m_s, 2.0);
  EXPECT_EQ(o.ramp_s, 3.0);
  const LemniscateReference ref(o);
  EXPECT_EQ(ref.duration(), std::numeric_limits<double>::infinity());
  // Max |c'| = sqrt(sx^2/4 + sz^2/4 + sy^2) = sqrt(9 + 0.25 + 9).
  EXPECT_NEAR(ref.phase_rate_rad_s(), 2.0 / std::sqrt(18.25), 1e-15);
  EXPECT_NEAR(ref.period_s(), 2.0 * kPi * std::sqrt(18.25) / 2.0, 1e-12);
}

struct LemniscateCase {
  Vector3 center;
  double sx, sy, sz, speed, ramp;
};
void PrintTo(const LemniscateCase& c, std::ostream* os) {
  *os << "center [" << c.center.transpose() << "] size " << c.sx << " x " << c.sy << " x " << c.sz
      << " speed " << c.speed << " ramp " << c.ramp;
}

class LemniscateShapeTest : public ::testing::TestWithParam<LemniscateCase> {
 protected:
  LemniscateOptions Options() const {
    const LemniscateCase& c = GetParam();
    return {.center_m = c.center, .size_x_m = c.sx, .size_y_m = c.sy, .size_z_m = c.sz,
            .max_speed_m_s = c.speed, .ramp_s = c.ramp, .yaw_rad = 0.4};
  }
};

TEST_P(LemniscateShapeTest, StartsAtCentreAtRest) {
  const LemniscateOptions o = Options();
  const LemniscateReference ref(o);
  const ReferencePoint r0 = ref.Evaluate(0.0);
  EXPECT_TRUE(MatricesNear(r0.p_W, o.center_m, 0.0));
  if (o.ramp_s > 0.0) {
    ExpectAtRest(r0, 0.0);
    EXPECT_TRUE(MatricesNear(r0.j_W, Vector3::Zero(), 0.0));
  }
  EXPECT_EQ(r0.yaw, 0.4);
  EXPECT_EQ(r0.yaw_rate, 0.0);
  // Negative times hold the start.
  EXPECT_TRUE(MatricesNear(ref.Evaluate(-5.0).p_W, o.center_m, 0.0));
}

TEST_P(LemniscateShapeTest, ExtentAndMaxSpeedOverOnePeriod) {
  const LemniscateOptions o = Options();
  const LemniscateReference ref(o);
  const double period = ref.period_s();
  const SampledExtent e = Sample(ref, o.ramp_s + 0.123, period, 400000);
  EXPECT_TRUE(MatricesNear(e.max - e.min, Vector3(o.size_x_m, o.size_y_m, o.size_z_m), 1e-6));
  EXPECT_TRUE(MatricesNear(0.5 * (e.max + e.min), o.center_m, 1e-6));
  EXPECT_NEAR(e.max_speed, o.max_speed_m_s, 1e-6);
  // Never faster than max_speed, ramp included.
  EXPECT_LE(Sample(ref, 0.0, o.ramp_s + 2.0 * period, 400000).max_speed,
            o.max_speed_m_s * (1.0 + 1e-12));
}

TEST_P(LemniscateShapeTest, PeriodIsTwoPiOverPhaseRate) {
  const LemniscateOptions o = Options();
  const LemniscateReference ref(o);
  // Phase rate from the closed-form max of |c'| at theta = 0.
  const double omega = o.max_speed_m_s / std::sqrt(o.size_x_m * o.size_x_m / 4.0 +
                                                   o.size_z_m * o.size_z_m / 4.0 +
                                                   o.size_y_m * o.size_y_m);
  EXPECT_NEAR(ref.phase_rate_rad_s(), omega, 1e-12 * omega);
  const double period = 2.0 * kPi / omega;
  EXPECT_NEAR(ref.period_s(), period, 1e-9 * period);
  for (double t : SampleTimes(o.ramp_s + period, 0.37)) {
    if (t < o.ramp_s) continue;
    const ReferencePoint a = ref.Evaluate(t);
    const ReferencePoint b = ref.Evaluate(t + period);
    EXPECT_TRUE(MatricesNear(a.p_W, b.p_W, 1e-9)) << "t = " << t;
    EXPECT_TRUE(MatricesNear(a.v_W, b.v_W, 1e-9)) << "t = " << t;
    EXPECT_TRUE(MatricesNear(a.a_W, b.a_W, 1e-9)) << "t = " << t;
    EXPECT_TRUE(MatricesNear(a.j_W, b.j_W, 1e-9)) << "t = " << t;
  }
  // Half a period is not a period: theta + pi flips x (and z) about the centre. At
  // t = ramp/2 + period/4, theta = pi/2: x = center + sx/2, half a period later center - sx/2.
  const double t = 0.5 * o.ramp_s + 0.25 * period;
  EXPECT_NEAR(ref.Evaluate(t).p_W.x() - ref.Evaluate(t + 0.5 * period).p_W.x(), o.size_x_m, 1e-9);
}

TEST_P(LemniscateShapeTest, DerivativesAreConsistentAndFinite) {
  const LemniscateReference ref(Options());
  ExpectDerivativesMatchFiniteDifferences(ref, 100.0);
  ExpectFiniteEverywhere(ref);
}

INSTANTIATE_TEST_SUITE_P(
    Shapes, LemniscateShapeTest,
    ::testing::Values(LemniscateCase{Vector3(0.0, 0.0, 1.5), 6.0, 3.0, 1.0, 2.0, 3.0},
                      LemniscateCase{Vector3(1.0, -2.0, 3.0), 6.0, 3.0, 0.0, 1.0, 0.5},
                      LemniscateCase{Vector3(0.0, 0.0, 2.0), 2.0, 5.0, 1.0, 3.0, 2.0},
                      LemniscateCase{Vector3(0.5, 0.5, 1.0), 4.0, 1.0, 3.0, 0.7, 0.0}));

TEST(LemniscateReferenceTest, RampIsSmooth) {
  const LemniscateOptions o;
  const LemniscateReference ref(o);
  // Position through jerk continuous across the end of the ramp.
  const ReferencePoint before = ref.Evaluate(o.ramp_s - 1e-9);
  const ReferencePoint after = ref.Evaluate(o.ramp_s + 1e-9);
  EXPECT_TRUE(MatricesNear(before.p_W, after.p_W, 1e-8));
  EXPECT_TRUE(MatricesNear(before.v_W, after.v_W, 1e-8));
  EXPECT_TRUE(MatricesNear(before.a_W, after.a_W, 1e-8));
  EXPECT_TRUE(MatricesNear(before.j_W, after.j_W, 1e-8));
  // And at the start (t < 0 holds the rest state).
  EXPECT_TRUE(MatricesNear(ref.Evaluate(1e-9).j_W, Vector3::Zero(), 1e-8));
  // Max speed at the centre crossing that follows the ramp: after the ramp
  // theta = Omega (t - ramp/2), so theta = 2 pi at t = ramp/2 + period.
  EXPECT_NEAR(ref.Evaluate(0.5 * o.ramp_s + ref.period_s()).v_W.norm(), 2.0, 1e-9);
}

TEST(LemniscateReferenceTest, RejectsInvalidOptions) {
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.max_speed_m_s = -1.0}), std::invalid_argument,
                       "LemniscateOptions::max_speed_m_s = -1 is invalid; expected > 0");
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.max_speed_m_s = 0.0}), std::invalid_argument,
                       "LemniscateOptions::max_speed_m_s");
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.size_x_m = 0.0}), std::invalid_argument,
                       "LemniscateOptions::size_x_m = 0 is invalid; expected > 0");
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.size_y_m = -3.0}), std::invalid_argument,
                       "LemniscateOptions::size_y_m");
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.size_z_m = -0.1}), std::invalid_argument,
                       "LemniscateOptions::size_z_m = -0.1 is invalid; expected >= 0");
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.ramp_s = -1.0}), std::invalid_argument,
                       "LemniscateOptions::ramp_s");
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.ramp_s = NAN}), std::invalid_argument,
                       "LemniscateOptions::ramp_s");
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.center_m = Vector3(0.0, 0.0, NAN)}),
                       std::invalid_argument, "LemniscateOptions::center_m");
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.yaw_rad = INFINITY}), std::invalid_argument,
                       "LemniscateOptions::yaw_rad");
  // A flat figure eight is fine.
  EXPECT_NO_THROW((void)LemniscateReference({.size_z_m = 0.0}));
  // Found by fuzzing (tests/fuzz, config): positive values whose phase rate max |c'| / speed leaves
  // the doubles aborted on the base class's invariant instead of being refused.
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.size_x_m = 1e-300, .size_y_m = 1e-300, .size_z_m = 0.0}),
                       std::invalid_argument, "LemniscateOptions::size_m");
  RG_EXPECT_THROW_WITH((void)LemniscateReference({.max_speed_m_s = 4.9e-324}), std::invalid_argument,
                       "finite phase rate");
}

// ----- circle

TEST(CircleReferenceTest, RadiusSpeedAndStart) {
  const CircleOptions o{.center_m = Vector3(1.0, 2.0, 3.0), .radius_m = 2.5, .speed_m_s = 1.5,
                        .ramp_s = 2.0, .yaw_rad = 1.0};
  const CircleReference ref(o);
  EXPECT_EQ(ref.duration(), std::numeric_limits<double>::infinity());
  EXPECT_NEAR(ref.phase_rate_rad_s(), 1.5 / 2.5, 1e-15);
  EXPECT_NEAR(ref.period_s(), 2.0 * kPi * 2.5 / 1.5, 1e-12);

  const ReferencePoint r0 = ref.Evaluate(0.0);
  EXPECT_TRUE(MatricesNear(r0.p_W, o.center_m + Vector3(2.5, 0.0, 0.0), 1e-15));
  ExpectAtRest(r0, 0.0);
  // |c'| is constant on a circle, so the speed follows the phase rate: it grows monotonically
  // during the ramp (smoothstep) and is exactly speed_m_s from its end.
  double last = 0.0;
  for (int i = 0; i <= 1000; ++i) {
    const double speed = ref.Evaluate(o.ramp_s * i / 1000.0).v_W.norm();
    EXPECT_GE(speed, last - 1e-12);
    last = speed;
  }
  EXPECT_NEAR(last, 1.5, 1e-12);

  for (double t : SampleTimes(100.0, 0.0123)) {
    const ReferencePoint r = ref.Evaluate(t);
    const Vector3 d = r.p_W - o.center_m;
    ASSERT_NEAR(d.norm(), 2.5, 1e-12) << "t = " << t;
    ASSERT_EQ(d.z(), 0.0);
    ASSERT_LE(r.v_W.norm(), 1.5 * (1.0 + 1e-12));
    ASSERT_NEAR(r.v_W.dot(d), 0.0, 1e-12);  // tangential
    ASSERT_GT(d.cross(r.v_W).z(), 0.0) << "counter-clockwise seen from above";
    if (t >= o.ramp_s) {
      ASSERT_NEAR(r.v_W.norm(), 1.5, 1e-12) << "t = " << t;
      // Uniform motion: centripetal acceleration v^2 / r, no jerk along the tangent.
      ASSERT_NEAR(r.a_W.norm(), 1.5 * 1.5 / 2.5, 1e-12);
    }
    ASSERT_EQ(r.yaw, 1.0);
    ASSERT_EQ(r.yaw_rate, 0.0);
  }
}

TEST(CircleReferenceTest, ClockwiseTurnsTheOtherWay) {
  const CircleReference ref({.radius_m = 1.0, .speed_m_s = 1.0, .ramp_s = 1.0, .clockwise = true});
  EXPECT_TRUE(MatricesNear(ref.Evaluate(0.0).p_W, Vector3(1.0, 0.0, 0.0), 0.0));
  for (double t : SampleTimes(20.0, 0.1)) {
    const ReferencePoint r = ref.Evaluate(t);
    ASSERT_LT(r.p_W.cross(r.v_W).z(), 0.0) << "t = " << t;
  }
  EXPECT_LT(ref.Evaluate(0.5).p_W.y(), 0.0);  // first moves towards -y
}

TEST(CircleReferenceTest, DerivativesAreConsistentAndFinite) {
  for (const double ramp : {0.0, 0.7, 4.0}) {
    for (const bool cw : {false, true}) {
      SCOPED_TRACE(::testing::Message() << "ramp " << ramp << " clockwise " << cw);
      const CircleReference ref({.center_m = Vector3(-1.0, 0.5, 2.0), .radius_m = 1.2,
                                 .speed_m_s = 2.0, .ramp_s = ramp, .clockwise = cw});
      ExpectDerivativesMatchFiniteDifferences(ref, 100.0);
      ExpectFiniteEverywhere(ref);
    }
  }
}

TEST(CircleReferenceTest, HelixClimbsAtItsRateOnceRampedAndKeepsConsistentDerivatives) {
  const CircleReference ref({.center_m = Vector3(0.0, 0.0, 1.0), .radius_m = 1.5, .speed_m_s = 1.0, .ramp_s = 2.0,
                             .climb_m_s = 0.2});
  ExpectDerivativesMatchFiniteDifferences(ref, 100.0);
  ExpectFiniteEverywhere(ref);
  // At full speed: tangential speed 1 m/s horizontally, 0.2 m/s up; a turn (2 pi r / v = 3 pi s)
  // later it is 0.2 * 3 pi higher, right above.
  const ReferencePoint a = ref.Evaluate(10.0), b = ref.Evaluate(10.0 + 3.0 * std::numbers::pi);
  EXPECT_NEAR(a.v_W.z(), 0.2, 1e-12);
  EXPECT_NEAR(a.v_W.head<2>().norm(), 1.0, 1e-12);
  EXPECT_NEAR(b.p_W.z() - a.p_W.z(), 0.2 * 3.0 * std::numbers::pi, 1e-9);
  EXPECT_NEAR((b.p_W - a.p_W).head<2>().norm(), 0.0, 1e-9);
  EXPECT_NEAR(ref.Evaluate(0.0).p_W.z(), 1.0, 1e-15);
}

TEST(CircleReferenceTest, RejectsInvalidOptions) {
  RG_EXPECT_THROW_WITH((void)CircleReference({.radius_m = 0.0}), std::invalid_argument,
                       "CircleOptions::radius_m = 0 is invalid; expected > 0");
  RG_EXPECT_THROW_WITH((void)CircleReference({.speed_m_s = -2.0}), std::invalid_argument,
                       "CircleOptions::speed_m_s = -2 is invalid; expected > 0");
  RG_EXPECT_THROW_WITH((void)CircleReference({.ramp_s = -0.5}), std::invalid_argument,
                       "CircleOptions::ramp_s = -0.5 is invalid; expected >= 0");
  RG_EXPECT_THROW_WITH((void)CircleReference({.center_m = Vector3(NAN, 0.0, 0.0)}),
                       std::invalid_argument, "CircleOptions::center_m");
  RG_EXPECT_THROW_WITH((void)CircleReference({.yaw_rad = NAN}), std::invalid_argument,
                       "CircleOptions::yaw_rad");
}

// ----- waypoints

/// Closed-form segment time from rest to rest: trapezoid L/v + v/a when L >= v^2/a, triangle
/// 2 sqrt(L/a) otherwise.
double SegmentTime(double length, double v, double a) {
  return length >= v * v / a ? length / v + v / a : 2.0 * std::sqrt(length / a);
}

struct ExpectedSchedule {
  std::vector<double> depart;       ///< time of leaving waypoint i (i < n - 1)
  std::vector<double> arrive;       ///< time of reaching waypoint i + 1
  std::vector<double> breakpoints;  ///< every phase switch
  double total = 0.0;
};

ExpectedSchedule Schedule(const WaypointOptions& o) {
  ExpectedSchedule s;
  const double v = o.max_speed_m_s;
  const double a = o.max_accel_m_s2;
  double t = 0.0;
  for (std::size_t i = 0; i + 1 < o.waypoints_m.size(); ++i) {
    const double length = (o.waypoints_m[i + 1] - o.waypoints_m[i]).norm();
    const double duration = SegmentTime(length, v, a);
    const double ramp = std::min(v, std::sqrt(length * a)) / a;
    s.depart.push_back(t);
    s.breakpoints.insert(s.breakpoints.end(), {t, t + ramp, t + duration - ramp, t + duration});
    t += duration;
    s.arrive.push_back(t);
    if (i + 2 < o.waypoints_m.size()) t += o.dwell_s;
    s.breakpoints.push_back(t);
  }
  s.total = t;
  return s;
}

WaypointOptions MixedWaypoints(double dwell) {
  // With v = 2, a = 1 the trapezoid needs L >= v^2/a = 4 m.
  return {.waypoints_m = {Vector3(0.0, 0.0, 1.0),     // 10 m: trapezoid
                          Vector3(10.0, 0.0, 1.0),    // 1 m: triangle
                          Vector3(10.0, 1.0, 1.0),    // 4 m: exactly the limit
                          Vector3(10.0, 1.0, 5.0),    // 5 m diagonal: trapezoid
                          Vector3(7.0, 5.0, 5.0),     // 0.3 m: triangle
                          Vector3(7.0, 5.0, 5.3)},
          .max_speed_m_s = 2.0,
          .max_accel_m_s2 = 1.0,
          .dwell_s = dwell,
          .yaw_rad = 0.25};
}

class WaypointDwellTest : public ::testing::TestWithParam<double> {};

TEST_P(WaypointDwellTest, TotalTimeMatchesClosedForm) {
  const WaypointOptions o = MixedWaypoints(GetParam());
  const WaypointReference ref(o);
  const ExpectedSchedule s = Schedule(o);
  // 10/2 + 2 + 2 sqrt(1) + 4/2 + 2 + 5/2 + 2 + 2 sqrt(0.3), plus 4 dwells.
  const double closed = 5.0 + 2.0 + 2.0 + 2.0 + 2.0 + 2.5 + 2.0 + 2.0 * std::sqrt(0.3) +
                        4.0 * GetParam();
  EXPECT_NEAR(s.total, closed, 1e-12);
  EXPECT_NEAR(ref.duration(), closed, 1e-12);
}

TEST_P(WaypointDwellTest, PassesThroughAndStopsAtEveryWaypoint) {
  const WaypointOptions o = MixedWaypoints(GetParam());
  const WaypointReference ref(o);
  const ExpectedSchedule s = Schedule(o);
  const std::vector<Vector3>& w = o.waypoints_m;
  for (std::size_t i = 0; i + 1 < w.size(); ++i) {
    SCOPED_TRACE(::testing::Message() << "segment " << i);
    const ReferencePoint leave = ref.Evaluate(s.depart[i]);
    EXPECT_TRUE(MatricesNear(leave.p_W, w[i], 1e-12));
    EXPECT_TRUE(MatricesNear(leave.v_W, Vector3::Zero(), 1e-12));
    const ReferencePoint reach = ref.Evaluate(s.arrive[i]);
    EXPECT_TRUE(MatricesNear(reach.p_W, w[i + 1], 1e-9));
    EXPECT_TRUE(MatricesNear(reach.v_W, Vector3::Zero(), 1e-9));
    // Just before arrival: almost there and almost stopped.
    const ReferencePoint nearly = ref.Evaluate(s.arrive[i] - 1e-6);
    EXPECT_TRUE(MatricesNear(nearly.p_W, w[i + 1], 1e-9));
    EXPECT_LT(nearly.v_W.norm(), 2e-6);
    if (GetParam() > 0.0 && i + 2 < w.size()) {
      const ReferencePoint dwell = ref.Evaluate(s.arrive[i] + 0.5 * GetParam());
      EXPECT_TRUE(MatricesNear(dwell.p_W, w[i + 1], 0.0));
      ExpectAtRest(dwell, 0.0);
    }
    // On the straight line between the two waypoints, moving towards the next one.
    const Vector3 u = (w[i + 1] - w[i]).normalized();
    for (int k = 1; k < 50; ++k) {
      const double t = s.depart[i] + (s.arrive[i] - s.depart[i]) * k / 50.0;
      const ReferencePoint r = ref.Evaluate(t);
      const Vector3 d = r.p_W - w[i];
      EXPECT_NEAR((d - d.dot(u) * u).norm(), 0.0, 1e-12);
      EXPECT_GT(r.v_W.dot(u), 0.0);
    }
  }
  ExpectHoldsAfterDuration(ref, w.back());
}

TEST_P(WaypointDwellTest, RespectsSpeedAndAccelerationLimits) {
  const WaypointOptions o = MixedWaypoints(GetParam());
  const WaypointReference ref(o);
  const ExpectedSchedule s = Schedule(o);
  double max_speed = 0.0;
  double max_accel = 0.0;
  for (double t = 0.0; t <= ref.duration() + 1.0; t += 1e-4) {
    const ReferencePoint r = ref.Evaluate(t);
    max_speed = std::max(max_speed, r.v_W.norm());
    max_accel = std::max(max_accel, r.a_W.norm());
    ASSERT_TRUE(MatricesNear(r.j_W, Vector3::Zero(), 0.0));
    ASSERT_EQ(r.yaw, 0.25);
    ASSERT_EQ(r.yaw_rate, 0.0);
  }
  EXPECT_LE(max_speed, 2.0 * (1.0 + 1e-12));
  EXPECT_NEAR(max_speed, 2.0, 1e-3);  // reached on the long segments
  EXPECT_LE(max_accel, 1.0 * (1.0 + 1e-12));
  // Triangle segment (1 m): peak speed sqrt(L a) = 1 at mid-segment.
  EXPECT_NEAR(ref.Evaluate(0.5 * (s.depart[1] + s.arrive[1])).v_W.norm(), 1.0, 1e-12);
}

TEST_P(WaypointDwellTest, DerivativesAreConsistentAndFinite) {
  const WaypointOptions o = MixedWaypoints(GetParam());
  const WaypointReference ref(o);
  // Acceleration steps at the phase switches; jerk is zero (and the FD of acceleration zero)
  // inside every phase.
  ExpectDerivativesMatchFiniteDifferences(ref, ref.duration() + 5.0, Schedule(o).breakpoints);
  ExpectFiniteEverywhere(ref);
}

INSTANTIATE_TEST_SUITE_P(Dwell, WaypointDwellTest, ::testing::Values(0.0, 1.5));

TEST(WaypointReferenceTest, SingleSegmentTrapezoidAndTriangle) {
  // Trapezoid: L = 9 >= v^2/a = 4.5 (v = 3, a = 2): T = 9/3 + 3/2.
  const WaypointReference trap({.waypoints_m = {Vector3::Zero(), Vector3(0.0, 9.0, 0.0)},
                                .max_speed_m_s = 3.0, .max_accel_m_s2 = 2.0});
  EXPECT_NEAR(trap.duration(), 4.5, 1e-12);
  EXPECT_NEAR(trap.Evaluate(2.25).v_W.y(), 3.0, 1e-12);
  EXPECT_NEAR(trap.Evaluate(0.5).a_W.y(), 2.0, 1e-12);
  EXPECT_NEAR(trap.Evaluate(4.0).a_W.y(), -2.0, 1e-12);
  // Triangle: L = 2 < 4.5: T = 2 sqrt(2/2) = 2, peak speed sqrt(L a) = 2.
  const WaypointReference tri({.waypoints_m = {Vector3::Zero(), Vector3(0.0, 0.0, -2.0)},
                               .max_speed_m_s = 3.0, .max_accel_m_s2 = 2.0, .dwell_s = 7.0});
  EXPECT_NEAR(tri.duration(), 2.0, 1e-12);  // no intermediate waypoint, so no dwell
  EXPECT_NEAR(tri.Evaluate(1.0).v_W.z(), -2.0, 1e-12);
  EXPECT_TRUE(MatricesNear(tri.Evaluate(1.0).p_W, Vector3(0.0, 0.0, -1.0), 1e-12));
  ExpectHoldsAfterDuration(tri, Vector3(0.0, 0.0, -2.0));
  EXPECT_TRUE(MatricesNear(tri.Evaluate(-3.0).p_W, Vector3::Zero(), 0.0));
}

TEST(WaypointReferenceTest, RejectsInvalidOptions) {
  const std::vector<Vector3> two = {Vector3::Zero(), Vector3::UnitX()};
  RG_EXPECT_THROW_WITH((void)WaypointReference({.waypoints_m = {Vector3::Zero()}}),
                       std::invalid_argument,
                       "WaypointOptions::waypoints_m = (1 waypoints) is invalid; "
                       "expected at least 2");
  RG_EXPECT_THROW_WITH((void)WaypointReference(WaypointOptions{}), std::invalid_argument,
                       "WaypointOptions::waypoints_m");
  const std::vector<Vector3> repeated = {Vector3::Zero(), Vector3::UnitX(), Vector3::UnitX()};
  RG_EXPECT_THROW_WITH(
      (void)WaypointReference({.waypoints_m = repeated}), std::invalid_argument,
      "WaypointOptions::waypoints_m.2 = [1, 0, 0] is invalid; expected a point distinct from "
      "waypoints_m.1");
  RG_EXPECT_THROW_WITH(
      (void)WaypointReference({.waypoints_m = {Vector3::Zero(), Vector3(NAN, 0.0, 0.0)}}),
      std::invalid_argument, "WaypointOptions::waypoints_m.1");
  RG_EXPECT_THROW_WITH((void)WaypointReference({.waypoints_m = two, .max_speed_m_s = 0.0}),
                       std::invalid_argument,
                       "WaypointOptions::max_speed_m_s = 0 is invalid; expected > 0");
  RG_EXPECT_THROW_WITH((void)WaypointReference({.waypoints_m = two, .max_accel_m_s2 = -1.0}),
                       std::invalid_argument,
                       "WaypointOptions::max_accel_m_s2 = -1 is invalid; expected > 0");
  RG_EXPECT_THROW_WITH((void)WaypointReference({.waypoints_m = two, .dwell_s = -0.1}),
                       std::invalid_argument,
                       "WaypointOptions::dwell_s = -0.1 is invalid; expected >= 0");
  RG_EXPECT_THROW_WITH((void)WaypointReference({.waypoints_m = two, .yaw_rad = NAN}),
                       std::invalid_argument, "WaypointOptions::yaw_rad");
}

}  // namespace
}  // namespace rotorguard::planning
