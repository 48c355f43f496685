#include "rotorguard/planning/flatness.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "rotorguard/core/error.h"

namespace rotorguard::planning {

namespace {

constexpr double kHalfPi = 1.57079632679489661923;

}  // namespace

void FlatnessLimits::Validate() const {
  const auto angle = [](const char* field, double v) {
    if (!(v > 0.0 && (v < kHalfPi || std::isinf(v)))) {
      ThrowValidation("FlatnessLimits", field, v, "an angle in (0, pi/2) rad (below 90 deg), or infinity for none");
    }
  };
  angle("theta_max_rad", theta_max_rad);
  angle("phi_max_rad", phi_max_rad);
  if (!(rho_angle > 0.0 && rho_angle <= 1.0)) ThrowValidation("FlatnessLimits", "rho_angle", rho_angle, "in (0, 1]");
  if (!(u_max >= 0.0 && u_max <= kMaxPwmInput)) {
    ThrowValidation("FlatnessLimits", "u_max", u_max,
                    fmt::format("a PWM input in (0, {:g}] (or 0 for the vehicle's)", kMaxPwmInput));
  }
  if (!(rho_u > 0.0 && rho_u <= 1.0)) ThrowValidation("FlatnessLimits", "rho_u", rho_u, "in (0, 1]");
}

const char* ToString(FlatnessBinding b) {
  switch (b) {
    case FlatnessBinding::kNone: return "none";
    case FlatnessBinding::kPitch: return "pitch";
    case FlatnessBinding::kRoll: return "roll";
    case FlatnessBinding::kMotor1: return "motor 1";
    case FlatnessBinding::kMotor2: return "motor 2";
    case FlatnessBinding::kMotor3: return "motor 3";
    case FlatnessBinding::kMotor4: return "motor 4";
  }
  return "unknown";
}

double EnvelopeSettlingTime(double distance_m, double angle_max_rad, double rho) {
  if (std::isinf(angle_max_rad) || distance_m == 0.0) return 0.0;
  // θ*(τ) = ω² (1 − τ) e^{−τ} R / g with τ = ω t (eq. 10): candidates at τ = 0, 2 (the extremum,
  // eq. 14) and 5.83 (eq. 15); the first is always the largest.
  const double bound = std::abs(distance_m) / (kGravity * rho * angle_max_rad);
  const double c = kSettlingConstant;
  const double candidates[3] = {1.0, std::exp(-2.0), (c - 1.0) * std::exp(-c)};
  double t_s = 0.0;
  for (const double k : candidates) t_s = std::max(t_s, c * std::sqrt(k * bound));
  return t_s;
}

double MotorSettlingTime(double signed_coefficient, double u_bar) {
  // u_i − h = c ω⁴ (3 − τ) e^{−τ}: at τ = 0 the factor is 3, at τ = 4 (the extremum, eq. 21)
  // −e^{−4}, at τ = 5.83 −2.83 e^{−5.83} (eq. 22). A candidate whose left side is negative never
  // reaches a positive ū (a complex root of eq. 23).
  const double c = kSettlingConstant;
  const double factors[3] = {3.0, -std::exp(-4.0), -(c - 3.0) * std::exp(-c)};
  double t_s = 0.0;
  for (const double f : factors) {
    const double lhs = f * signed_coefficient;
    if (lhs > 0.0) t_s = std::max(t_s, c * std::pow(lhs / u_bar, 0.25));
  }
  return t_s;
}

SettlingTime PlanSettlingTime(const vehicle::PwmQuadModel& model, const FlatnessLimits& limits,
                              const Eigen::Vector2d& delta_m, const Eigen::Vector4d& w_hat) {
  limits.Validate();
  if (!delta_m.allFinite()) ThrowInvalidArgument("PlanSettlingTime", "delta_m", "(non-finite)", "finite distances");
  for (int i = 0; i < 4; ++i) {
    if (!(w_hat[i] >= 0.0 && w_hat[i] < 1.0)) {
      ThrowInvalidArgument("PlanSettlingTime", fmt::format("w_hat.{}", i), w_hat[i],
                           "a loss of effectiveness in [0, 1)");
    }
  }
  SettlingTime out;
  const double u_max = limits.u_max > 0.0 ? limits.u_max : model.u_max;
  const double h = model.hover_pwm();
  // Eq. (19) and its siblings: u_i* = h + s_i F⁽⁴⁾ along motor i's axis.
  const double kx = model.j1 / (2.0 * model.gravity * model.gain_n * model.arm_m);
  const double ky = model.j2 / (2.0 * model.gravity * model.gain_n * model.arm_m);
  const double coefficient[4] = {kx * delta_m.x(), -kx * delta_m.x(), -ky * delta_m.y(), ky * delta_m.y()};
  const auto raise = [&](double t, FlatnessBinding b) {
    if (t > out.t_s) out.t_s = t, out.binding = b;
  };
  for (int i = 0; i < 4; ++i) {
    const double u_bar = (1.0 - w_hat[i]) * limits.rho_u * u_max - h;  // ū of eq. (23), after a fault
    if (!(u_bar > 0.0)) {
      out.feasible = false;
      out.why = fmt::format("motor {} may give at most {:.4g} of PWM (1 - w = {:.3f}) but needs {:.4g} to hover", i + 1,
                            (1.0 - w_hat[i]) * limits.rho_u * u_max, 1.0 - w_hat[i], h);
      continue;
    }
    const double t = MotorSettlingTime(coefficient[i], u_bar);
    out.actuator_s = std::max(out.actuator_s, t);
    raise(t, static_cast<FlatnessBinding>(static_cast<int>(FlatnessBinding::kMotor1) + i));
  }
  const double pitch = EnvelopeSettlingTime(delta_m.x(), limits.theta_max_rad, limits.rho_angle);
  const double roll = EnvelopeSettlingTime(delta_m.y(), limits.phi_max_rad, limits.rho_angle);
  out.envelope_s = std::max(pitch, roll);
  raise(pitch, FlatnessBinding::kPitch);
  raise(roll, FlatnessBinding::kRoll);
  if (!out.feasible) out.t_s = 0.0, out.binding = FlatnessBinding::kNone;
  return out;
}

Eigen::Vector4d NominalPwm(const vehicle::PwmQuadModel& m, const Vector3& snap_W) {
  // Eq. (18): u_z = m g, u_θ = J1 F2⁽⁴⁾ / g, u_φ = −J2 F3⁽⁴⁾ / g, u_ψ = 0, through the inverse of
  // eq. (2).
  const Eigen::Vector4d wrench(m.mass_kg * m.gravity, m.j1 * snap_W.x() / m.gravity, -m.j2 * snap_W.y() / m.gravity,
                               0.0);
  return m.Mixer().inverse() * wrench;
}

CriticallyDampedReference::CriticallyDampedReference(double t0, const Vector3& p0, const Vector3& v0,
                                                     const Vector3& goal, double t_s, double yaw)
    : t0_(t0), t_s_(t_s), omega_(kSettlingConstant / t_s), yaw_(yaw), p0_(p0), v0_(v0), goal_(goal) {
  if (!(std::isfinite(t_s) && t_s > 0.0)) ThrowValidation("CriticallyDampedReference", "t_s", t_s, "a time > 0 s");
  if (!std::isfinite(t0)) ThrowValidation("CriticallyDampedReference", "t0", t0, "a finite time");
  if (!p0.allFinite() || !v0.allFinite() || !goal.allFinite() || !std::isfinite(yaw)) {
    ThrowValidation("CriticallyDampedReference", "state", "(non-finite)", "finite start, velocity, goal and yaw");
  }
}

std::array<Vector3, 5> CriticallyDampedReference::Derivatives(double tau) const {
  // Each term is (a + b τ) e^{−ω τ}; its derivative is (b − ω a − ω b τ) e^{−ω τ}. Start from
  // −Δ (1 + ω τ) + v0 τ, i.e. a = −Δ, b = −ω Δ + v0, and add R to the position.
  const double w = omega_, e = std::exp(-w * tau);
  Vector3 a = -(goal_ - p0_), b = -w * (goal_ - p0_) + v0_;
  std::array<Vector3, 5> d;
  for (int k = 0; k < 5; ++k) {
    d[static_cast<std::size_t>(k)] = (a + b * tau) * e;
    const Vector3 a_next = b - w * a;
    b = -w * b;
    a = a_next;
  }
  d[0] += goal_;
  return d;
}

ReferencePoint CriticallyDampedReference::Evaluate(double t) const {
  ReferencePoint r;
  r.yaw = yaw_;
  if (t >= duration()) {
    r.p_W = goal_;
    return r;
  }
  if (t <= t0_) {
    r.p_W = p0_;
    r.v_W = v0_;  // before the start: the start state (the step has not come)
    return r;
  }
  const auto d = Derivatives(t - t0_);
  r.p_W = d[0];
  r.v_W = d[1];
  r.a_W = d[2];
  r.j_W = d[3];
  r.s_W = d[4];
  return r;
}


}  // namespace rotorguard::planning
