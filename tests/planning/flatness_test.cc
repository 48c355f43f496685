
#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/planning/flatness.h"
#include "rotorguard/planning/flatness_navigator.h"
#include "rotorguard/vehicle/pwm_model.h"
#include "vehicle_fixture.h"

namespace rotorguard::planning {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// The Qball-X4-like vehicle of configs/vehicles/qball_x4.yaml.
vehicle::PwmQuadModel Qball() { return vehicle::PwmQuadModel::FromVehicle(::rotorguard::testing::QballX4()); }

/// The largest value of f over [0, t_end]: a dense grid, then golden-section refinement around the
/// best sample (an extremum between samples is found to ~1e-12 of the interval).
double MaxOver(const std::function<double(double)>& f, double t_end) {
  constexpr int kSamples = 4000;
  const double h = t_end / kSamples;
  int best = 0;
  double best_value = f(0.0);
  for (int k = 1; k <= kSamples; ++k) {
    const double v = f(k * h);
    if (v > best_value) best_value = v, best = k;
  }
  double lo = std::max(0.0, (best - 1) * h), hi = std::min(t_end, (best + 1) * h);
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  for (int it = 0; it < 200 && hi - lo > 1e-14; ++it) {
    const double a = hi - r * (hi - lo), b = lo + r * (hi - lo);
    if (f(a) > f(b)) hi = b; else lo = a;
  }
  return std::max(best_value, f(0.5 * (lo + hi)));
}

TEST(Flatness, EnvelopeSettlingTimeIsThePapersFigure) {
  // Fig. 1(a): R2 = -1.5 m, |theta_max| = 10 deg gives t_s = 5.46 s (rho_theta = 1).
  EXPECT_NEAR(EnvelopeSettlingTime(-1.5, 10.0 * kDeg, 1.0), 5.46, 0.01);
  // Eq. (16) itself: sqrt(5.83^2 |R| / (g rho theta_max)).
  EXPECT_NEAR(EnvelopeSettlingTime(2.0, 0.2, 0.8), std::sqrt(5.83 * 5.83 * 2.0 / (kGravity * 0.8 * 0.2)), 1e-12);
  EXPECT_EQ(EnvelopeSettlingTime(0.0, 0.2, 1.0), 0.0);
  EXPECT_EQ(EnvelopeSettlingTime(1.0, std::numeric_limits<double>::infinity(), 1.0), 0.0);
}

TEST(Flatness, ReferenceOfEq7AndItsDerivativesByFiniteDifferences) {
  const double t_s = 4.0, w = 5.83 / t_s;
  const Vector3 goal(-1.5, 0.7, 0.0);
  const CriticallyDampedReference ref(0.0, Vector3::Zero(), Vector3::Zero(), goal, t_s);
  for (double t = 0.05; t < 3.0 * t_s; t += 0.137) {
    // Eq. (7).
    const Vector3 closed = (1.0 - (1.0 + w * t) * std::exp(-w * t)) * goal;
    EXPECT_LT((ref.Evaluate(t).p_W - closed).norm(), 1e-12) << t;
    // Eq. (10): theta* = F2'' / g.
    EXPECT_NEAR(ref.Evaluate(t).a_W.x() / kGravity, -w * w / kGravity * (w * t - 1.0) * std::exp(-w * t) * goal.x(),
                1e-12);
  }
  // Eq. (8), a start in motion: every derivative against central differences of the one below.
  const CriticallyDampedReference moving(1.0, Vector3(0.3, -0.2, 1.0), Vector3(0.4, 0.1, -0.2), goal, 3.0);
  const double h = 1e-5;
  for (double t = 1.02; t < 8.0; t += 0.31) {
    const ReferencePoint a = moving.Evaluate(t - h), b = moving.Evaluate(t + h), c = moving.Evaluate(t);
    EXPECT_LT(((b.p_W - a.p_W) / (2 * h) - c.v_W).norm(), 1e-8) << t;
    EXPECT_LT(((b.v_W - a.v_W) / (2 * h) - c.a_W).norm(), 1e-8) << t;
    EXPECT_LT(((b.a_W - a.a_W) / (2 * h) - c.j_W).norm(), 1e-7) << t;
    EXPECT_LT(((b.j_W - a.j_W) / (2 * h) - c.s_W).norm(), 1e-6) << t;
  }
  // It starts from the given state and ends at rest on the goal.
  const ReferencePoint start = moving.Evaluate(1.0 + 1e-12);
  EXPECT_LT((start.p_W - Vector3(0.3, -0.2, 1.0)).norm(), 1e-9);
  EXPECT_LT((start.v_W - Vector3(0.4, 0.1, -0.2)).norm(), 1e-9);
  EXPECT_EQ(moving.Evaluate(moving.duration() + 1.0).p_W, goal);
  EXPECT_LT((moving.Evaluate(moving.duration() - 1e-9).p_W - goal).norm(), 1e-12);
}

TEST(Flatness, ChosenSettlingTimeMeetsTheBindingLimitWithEqualityAndKeepsTheOthers) {
  // Brute force over random moves, vehicles and limits: fly the reference of the chosen t_s on
  // paper (eq. 3 for the angles, eq. 19 for the PWM inputs) and find each limit's worst value.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  int binding_counts[7] = {};
  for (int trial = 0; trial < 300; ++trial) {
    vehicle::PwmQuadModel m = Qball();
    m.j1 = 0.01 + 0.1 * U(rng);
    m.j2 = 0.01 + 0.1 * U(rng);
    m.arm_m = 0.1 + 0.2 * U(rng);
    FlatnessLimits limits;
    limits.theta_max_rad = (3.0 + 40.0 * U(rng)) * kDeg;
    limits.phi_max_rad = (3.0 + 40.0 * U(rng)) * kDeg;
    limits.rho_angle = 0.5 + 0.5 * U(rng);
    limits.u_max = m.hover_pwm() * (1.01 + 1.0 * U(rng));
    limits.rho_u = 1.0;
    if (trial % 3 == 0) limits.theta_max_rad = limits.phi_max_rad = std::numeric_limits<double>::infinity();
    const Eigen::Vector2d delta(4.0 * U(rng) - 2.0, trial % 5 == 0 ? 0.0 : 4.0 * U(rng) - 2.0);
    Eigen::Vector4d w = Eigen::Vector4d::Zero();
    if (trial % 4 == 1) w[trial % 4] = 0.3 * U(rng);
    const SettlingTime st = PlanSettlingTime(m, limits, delta, w);
    if (!st.feasible) continue;
    ASSERT_GT(st.t_s, 0.0);
    const CriticallyDampedReference ref(0.0, Vector3::Zero(), Vector3::Zero(), Vector3(delta.x(), delta.y(), 0.0), st.t_s);
    const double theta_limit = limits.rho_angle * limits.theta_max_rad, phi_limit = limits.rho_angle * limits.phi_max_rad;
    const double max_theta = MaxOver([&](double t) { return std::abs(ref.Evaluate(t).a_W.x()) / kGravity; }, st.t_s);
    const double max_phi = MaxOver([&](double t) { return std::abs(ref.Evaluate(t).a_W.y()) / kGravity; }, st.t_s);
    double max_u_margin[4];
    for (int i = 0; i < 4; ++i) {
      const double limit = (1.0 - w[i]) * limits.rho_u * limits.u_max;
      // The reference's t = 0 is a step (the acceleration jumps); evaluate just after it.
      max_u_margin[i] = MaxOver([&](double t) { return NominalPwm(m, ref.Evaluate(std::max(t, 1e-13)).s_W)[i]; }, st.t_s) - limit;
    }
    // Every limit holds ...
    EXPECT_LE(max_theta, theta_limit * (1.0 + 1e-9));
    EXPECT_LE(max_phi, phi_limit * (1.0 + 1e-9));
    for (int i = 0; i < 4; ++i) EXPECT_LE(max_u_margin[i], 1e-9) << "motor " << i + 1 << " trial " << trial;
    // ... and the binding one with equality.
    ++binding_counts[static_cast<int>(st.binding)];
    switch (st.binding) {
      case FlatnessBinding::kPitch: EXPECT_NEAR(max_theta, theta_limit, 1e-6); break;
      case FlatnessBinding::kRoll: EXPECT_NEAR(max_phi, phi_limit, 1e-6); break;
      case FlatnessBinding::kNone: ADD_FAILURE() << "a move without a binding limit"; break;
      default: {
        const int motor = static_cast<int>(st.binding) - static_cast<int>(FlatnessBinding::kMotor1);
        EXPECT_NEAR(max_u_margin[motor], 0.0, 1e-6) << "motor " << motor + 1 << " trial " << trial;
      }
    }
  }
  // The random cases exercise each kind of binding limit.
  EXPECT_GT(binding_counts[static_cast<int>(FlatnessBinding::kPitch)], 5);
  EXPECT_GT(binding_counts[static_cast<int>(FlatnessBinding::kRoll)], 5);
  EXPECT_GT(binding_counts[static_cast<int>(FlatnessBinding::kMotor1)] +
                binding_counts[static_cast<int>(FlatnessBinding::kMotor2)],
            5);
  EXPECT_GT(binding_counts[static_cast<int>(FlatnessBinding::kMotor3)] +
                binding_counts[static_cast<int>(FlatnessBinding::kMotor4)],
            5);
}

TEST(Flatness, ALossOfEffectivenessLengthensTheActuatorBoundPlan) {
  vehicle::PwmQuadModel m = Qball();
  FlatnessLimits limits;
  limits.theta_max_rad = limits.phi_max_rad = std::numeric_limits<double>::infinity();
  // Towards -x, as in the paper (R2 = -1.5 m): motor 2 gives the initial push (u2*(0) is the
  // largest input), so its loss binds.
  const Eigen::Vector2d delta(-1.0, 0.0);
  double last = PlanSettlingTime(m, limits, delta).t_s;
  for (const double w : {0.1, 0.2, 0.3, 0.4}) {
    const SettlingTime st = PlanSettlingTime(m, limits, delta, Eigen::Vector4d(0.0, w, 0.0, 0.0));
    ASSERT_TRUE(st.feasible);
    EXPECT_GT(st.t_s, last) << w;
    EXPECT_EQ(st.binding, FlatnessBinding::kMotor2);
    last = st.t_s;
  }
}

TEST(Flatness, AFaultThatLeavesTooLittleToHoverIsInfeasibleAndSaysWhy) {
  const vehicle::PwmQuadModel m = Qball();  // hover PWM 0.0286, u_max 0.06: 1 - w must exceed 0.477
  const SettlingTime st = PlanSettlingTime(m, FlatnessLimits{}, Eigen::Vector2d(1.0, 0.0), Eigen::Vector4d(0, 0, 0.6, 0));
  EXPECT_FALSE(st.feasible);
  EXPECT_NE(st.why.find("motor 3"), std::string::npos) << st.why;
  EXPECT_NE(st.why.find("hover"), std::string::npos) << st.why;
}

TEST(Flatness, InvalidLimitsAreRejectedNamingTheField) {
  const auto message = [](const FlatnessLimits& l) {
    try {
      l.Validate();
    } catch (const ValidationError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  FlatnessLimits l;
  l.theta_max_rad = 90.0 * kDeg;
  EXPECT_NE(message(l).find("theta_max_rad"), std::string::npos);
  l = FlatnessLimits{};
  l.phi_max_rad = -0.1;
  EXPECT_NE(message(l).find("phi_max_rad"), std::string::npos);
  l = FlatnessLimits{};
  l.u_max = -0.01;
  EXPECT_NE(message(l).find("u_max"), std::string::npos);
  l = FlatnessLimits{};
  l.rho_u = 0.0;
  EXPECT_NE(message(l).find("rho_u"), std::string::npos);
  EXPECT_THROW(PlanSettlingTime(Qball(), FlatnessLimits{}, Eigen::Vector2d(1, 0), Eigen::Vector4d(0, 1.0, 0, 0)),
               std::invalid_argument);
  EXPECT_THROW(CriticallyDampedReference(0.0, Vector3::Zero(), Vector3::Zero(), Vector3::Ones(), 0.0), ValidationError);
}

TEST(PwmQuadModel, FromTheVehicleLayoutOfEq2) {
  vehicle::VehicleParams v = ::rotorguard::testing::QballX4();
  const Vector3 p[4] = {{-0.2, 0, 0}, {0.2, 0, 0}, {0, 0.2, 0}, {0, -0.2, 0}};
  const vehicle::PwmQuadModel m = vehicle::PwmQuadModel::FromVehicle(v);
  EXPECT_DOUBLE_EQ(m.arm_m, 0.2);
  EXPECT_DOUBLE_EQ(m.u_max, 0.06);
  EXPECT_DOUBLE_EQ(m.j1, 0.03);
  // Eq. (2) against the rigid body: thrust and torques of the rotors r x (0, 0, K u) + yaw.
  const Eigen::Vector4d u(0.021, 0.033, 0.027, 0.018);
  Vector3 torque = Vector3::Zero();
  double thrust = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double T = 120.0 * u[i];
    thrust += T;
    torque += p[i].cross(Vector3(0, 0, T)) + Vector3(0, 0, v.rotors[i].yaw_sign() * (4.0 / 120.0) * T);
  }
  const Eigen::Vector4d wrench = m.Mixer() * u;  // (u_z, u_theta about y, u_phi about x, u_psi)
  EXPECT_NEAR(wrench[0], thrust, 1e-12);
  EXPECT_NEAR(wrench[1], torque.y(), 1e-12);
  EXPECT_NEAR(wrench[2], torque.x(), 1e-12);
  EXPECT_NEAR(wrench[3], torque.z(), 1e-12);
  // A rotor out of place or spinning the wrong way is named.
  v.rotors[2].p_B = Vector3(0.2, 0.2, 0.0);
  try {
    vehicle::PwmQuadModel::FromVehicle(v);
    ADD_FAILURE() << "expected a ValidationError";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("rotors.2.position_m"), std::string::npos) << e.what();
  }
  v.rotors[2].p_B = p[2];
  v.rotors[1].direction = vehicle::SpinDirection::kCounterClockwise;
  EXPECT_THROW(vehicle::PwmQuadModel::FromVehicle(v), ValidationError);
}

}  // namespace
}  // namespace rotorguard::planning

namespace rotorguard::planning {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

TEST(FlatnessNavigator, HoldsOnADetectionThenReplansTheRemainingDistanceWithTheIdentifiedLoss) {
  const vehicle::PwmQuadModel m = vehicle::PwmQuadModel::FromVehicle(::rotorguard::testing::QballX4());
  FlatnessNavigatorOptions o;
  o.min_hold_s = 3.0;
  FlatnessNavigator nav(m, o, Vector3(0, 0, 1));
  nav.SetGoal(Vector3(-1.5, 0, 1), 0.0);
  ASSERT_EQ(nav.decisions().size(), 1u);
  EXPECT_NEAR(nav.decisions()[0].t_s, EnvelopeSettlingTime(-1.5, 10.0 * kDegree, 1.0), 1e-12);
  EXPECT_FALSE(nav.arrived(5.0));
  nav.OnFaultDetected(2.0);
  EXPECT_TRUE(nav.holding());
  // The hold starts where the reference is and barely moves while the estimate converges.
  const Vector3 at_fault = nav.Evaluate(2.0 - 1e-9).p_W;
  EXPECT_LT((nav.Evaluate(2.0 + 1e-9).p_W - at_fault).norm(), 1e-6);
  EXPECT_LT((nav.Evaluate(5.0).p_W - at_fault).norm(), 2e-3);
  const Eigen::Vector4d w(0.0, 0.4, 0.0, 0.0);
  nav.Update(4.0, true, w);  // settled, but before min_hold_s
  EXPECT_TRUE(nav.holding());
  nav.Update(5.0, true, w);
  ASSERT_FALSE(nav.holding());
  const FlatnessDecision& d = nav.decisions().back();
  EXPECT_EQ(d.kind, "continue");
  EXPECT_EQ(d.w_hat, w);
  // The re-plan is the closed form for the remaining distance with the degraded limit.
  const Vector3 remaining = Vector3(-1.5, 0, 1) - nav.Evaluate(5.0 - 1e-9).p_W;
  const SettlingTime expected = PlanSettlingTime(m, o.limits, remaining.head<2>(), w);
  EXPECT_NEAR(d.t_s, expected.t_s, 1e-6);
  EXPECT_LT((d.delta_m - remaining).norm(), 1e-6);
  // ... and its actuator candidate is longer than a fault-free one over the same distance.
  EXPECT_GT(d.actuator_s, PlanSettlingTime(m, o.limits, remaining.head<2>()).actuator_s);
  EXPECT_TRUE(nav.arrived(5.0 + d.t_s + 1e-6));
  EXPECT_LT((nav.Evaluate(5.0 + 40.0 * d.t_s).p_W - Vector3(-1.5, 0, 1)).norm(), 1e-9);
  EXPECT_FALSE(nav.land_request());
}

TEST(FlatnessNavigator, ReturnsHomeOrLandsWhenTheLegExceedsTheBudgetOrCannotBeFlown) {
  const vehicle::PwmQuadModel m = vehicle::PwmQuadModel::FromVehicle(::rotorguard::testing::QballX4());
  FlatnessNavigatorOptions o;
  o.time_budget_s = 10.0;
  o.min_hold_s = 0.0;
  {  // 20 m to go take 20 s at 10 deg; home is close: return.
    FlatnessNavigator nav(m, o, Vector3(0, 0, 1));
    nav.SetGoal(Vector3(-20, 0, 1), 0.0);
    nav.OnFaultDetected(0.5);
    nav.Update(0.6, true, Eigen::Vector4d(0, 0.3, 0, 0));
    EXPECT_EQ(nav.decisions().back().kind, "return");
    EXPECT_TRUE(nav.returning());
    EXPECT_NE(nav.decisions().back().reason.find("budget"), std::string::npos);
  }
  {  // 1 - w = 0.4 leaves motor 2 less than its share of the weight: land, saying why.
    FlatnessNavigator nav(m, o, Vector3(0, 0, 1));
    nav.SetGoal(Vector3(-1.0, 0, 1), 0.0);
    nav.OnFaultDetected(0.5);
    nav.Update(0.6, true, Eigen::Vector4d(0, 0.6, 0, 0));
    EXPECT_EQ(nav.decisions().back().kind, "land");
    ASSERT_TRUE(nav.land_request());
    EXPECT_NE(nav.land_request()->find("hover"), std::string::npos) << *nav.land_request();
  }
  {  // An estimate that never settles is re-planned once max_hold_s is over.
    o.min_hold_s = 1.0;
    o.max_hold_s = 5.0;
    FlatnessNavigator nav(m, o, Vector3(0, 0, 1));
    nav.SetGoal(Vector3(-1.0, 0, 1), 0.0);
    nav.OnFaultDetected(0.5);
    nav.Update(5.0, false, Eigen::Vector4d(0, 0.3, 0, 0));
    EXPECT_TRUE(nav.holding());
    nav.Update(5.6, false, Eigen::Vector4d(0, 0.3, 0, 0));
    EXPECT_EQ(nav.decisions().back().kind, "continue");
    EXPECT_EQ(nav.decisions().back().reason, "hold timed out");
  }
  FlatnessNavigatorOptions bad;
  bad.max_hold_s = 1.0;
  bad.min_hold_s = 2.0;
  EXPECT_THROW(FlatnessNavigator(m, bad, Vector3::Zero()), ValidationError);
}

}  // namespace
}  // namespace rotorguard::planning
