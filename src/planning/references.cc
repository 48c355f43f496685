#include "rotorguard/planning/references.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include <fmt/format.h>

#include "rotorguard/core/error.h"

namespace rotorguard::planning {

namespace {

// ----- validation helpers: every message names the Options type, the field, the value, the rule.

std::string FormatVector(const Vector3& v) {
  return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z());
}

void RequireFinite(const char* owner, const std::string& field, double value) {
  if (!std::isfinite(value)) ThrowValidation(owner, field, value, "a finite value");
}
void RequireFinite(const char* owner, const std::string& field, const Vector3& value) {
  if (!value.allFinite()) ThrowValidation(owner, field, FormatVector(value), "finite coordinates");
}
void RequirePositive(const char* owner, const std::string& field, double value) {
  // Written so that NaN fails too.
  if (!(std::isfinite(value) && value > 0.0)) ThrowValidation(owner, field, value, "> 0");
}
void RequireNonNegative(const char* owner, const std::string& field, double value) {
  if (!(std::isfinite(value) && value >= 0.0)) ThrowValidation(owner, field, value, ">= 0");
}

/// The reference holds its t = 0 point for negative times.
double ClampTime(double t) { return t > 0.0 ? t : (std::isnan(t) ? t : 0.0); }

// ----- ramped phase

/// theta(t) and its first three time derivatives.
struct Phase {
  double theta = 0.0;
  double rate = 0.0;   ///< thd
  double accel = 0.0;  ///< thdd
  double jerk = 0.0;   ///< thddd
};

/// Phase whose rate follows Omega * S(t / ramp), S(s) = 10 s^3 - 15 s^4 + 6 s^5, then Omega.
///   theta = Omega ramp  integral_0^s S = Omega ramp (2.5 s^4 - 3 s^5 + s^6)
///   thdd  = Omega / ramp   S'(s) = Omega / ramp   30 s^2 (1 - s)^2
///   thddd = Omega / ramp^2 S''(s) = Omega / ramp^2 60 s (1 - s)(1 - 2 s)
/// At s = 1: integral = 1/2, S = 1, S' = S'' = 0, so after the ramp theta = Omega (t - ramp / 2)
/// continues with matching rate, phase acceleration and phase jerk.
Phase RampedPhase(double t, double omega, double ramp) {
  Phase ph;
  if (ramp > 0.0 && t < ramp) {
    const double s = t / ramp;
    const double s2 = s * s;
    const double one_minus_s = 1.0 - s;
    ph.theta = omega * ramp * s2 * s2 * (2.5 - 3.0 * s + s2);
    ph.rate = omega * s2 * s * (10.0 - 15.0 * s + 6.0 * s2);
    ph.accel = omega / ramp * 30.0 * s2 * one_minus_s * one_minus_s;
    ph.jerk = omega / (ramp * ramp) * 60.0 * s * one_minus_s * (1.0 - 2.0 * s);
  } else {
    ph.theta = omega * (t - 0.5 * ramp);
    ph.rate = omega;
  }
  return ph;
}

// ----- option checks used before the base-class constructor runs

constexpr char kHover[] = "HoverOptions";
constexpr char kTakeoff[] = "TakeoffOptions";
constexpr char kLemniscate[] = "LemniscateOptions";
constexpr char kCircle[] = "CircleOptions";
constexpr char kWaypoint[] = "WaypointOptions";

/// Omega such that the fastest point of the curve moves at max_speed. With
///   c'(theta) = [sx/2 cos(theta), sy cos(2 theta), sz/2 cos(theta)],
///   |c'|^2 = (sx^2/4 + sz^2/4) cos^2(theta) + sy^2 cos^2(2 theta),
/// both terms are at most their coefficient and reach it together at theta = 0 (the centre
/// crossing), so max |c'| = sqrt(sx^2/4 + sz^2/4 + sy^2) and speed = |c'| Omega.
double LemniscatePhaseRate(const LemniscateOptions& o) {
  const double max_dc = std::sqrt(0.25 * (o.size_x_m * o.size_x_m + o.size_z_m * o.size_z_m) + o.size_y_m * o.size_y_m);
  return o.max_speed_m_s / max_dc;
}

const LemniscateOptions& Validated(const LemniscateOptions& o) {
  RequireFinite(kLemniscate, "center_m", o.center_m);
  RequirePositive(kLemniscate, "size_x_m", o.size_x_m);
  RequirePositive(kLemniscate, "size_y_m", o.size_y_m);
  RequireNonNegative(kLemniscate, "size_z_m", o.size_z_m);
  RequirePositive(kLemniscate, "max_speed_m_s", o.max_speed_m_s);
  RequireNonNegative(kLemniscate, "ramp_s", o.ramp_s);
  RequireFinite(kLemniscate, "yaw_rad", o.yaw_rad);
  // Each positive, yet a size of 1e-300 m would make the phase rate infinite.
  const double rate = LemniscatePhaseRate(o);
  if (!(std::isfinite(rate) && rate > 0.0)) {
    ThrowValidation(kLemniscate, "size_m", fmt::format("[{}, {}, {}]", o.size_x_m, o.size_y_m, o.size_z_m),
                    fmt::format("a size at which max_speed_m_s = {} gives a finite phase rate", o.max_speed_m_s));
  }
  return o;
}

const CircleOptions& Validated(const CircleOptions& o) {
  RequireFinite(kCircle, "center_m", o.center_m);
  RequirePositive(kCircle, "radius_m", o.radius_m);
  RequirePositive(kCircle, "speed_m_s", o.speed_m_s);
  RequireNonNegative(kCircle, "ramp_s", o.ramp_s);
  RequireFinite(kCircle, "yaw_rad", o.yaw_rad);
  RequireFinite(kCircle, "climb_m_s", o.climb_m_s);
  return o;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Hover

HoverReference::HoverReference(const HoverOptions& options) : options_(options) {
  RequireFinite(kHover, "position_m", options_.position_m);
  RequireFinite(kHover, "yaw_rad", options_.yaw_rad);
}

ReferencePoint HoverReference::Evaluate(double /*t*/) const {
  ReferencePoint r;
  r.p_W = options_.position_m;
  r.yaw = options_.yaw_rad;
  return r;
}

// ---------------------------------------------------------------------------------------------
// Takeoff

TakeoffReference::TakeoffReference(const TakeoffOptions& options) : options_(options) {
  RequireFinite(kTakeoff, "start_m", options_.start_m);
  if (!std::isfinite(options_.altitude_m) || options_.altitude_m == 0.0) {
    ThrowValidation(kTakeoff, "altitude_m", options_.altitude_m, "a finite nonzero height (< 0 descends)");
  }
  RequirePositive(kTakeoff, "max_speed_m_s", options_.max_speed_m_s);
  RequireFinite(kTakeoff, "yaw_rad", options_.yaw_rad);
  // Peak of h d/dt(10 s^3 - 15 s^4 + 6 s^5) = h/T 30 s^2 (1 - s)^2 is at s = 1/2: 1.875 h / T.
  climb_time_s_ = 1.875 * std::abs(options_.altitude_m) / options_.max_speed_m_s;
}

ReferencePoint TakeoffReference::Evaluate(double t) const {
  ReferencePoint r;
  r.yaw = options_.yaw_rad;
  r.p_W = options_.start_m;
  const double h = options_.altitude_m;
  const double tc = ClampTime(t);
  if (!(tc < climb_time_s_)) {
    r.p_W.z() += h;
    return r;
  }
  const double T = climb_time_s_;
  const double s = tc / T;
  const double s2 = s * s;
  const double one_minus_s = 1.0 - s;
  r.p_W.z() += h * s2 * s * (10.0 - 15.0 * s + 6.0 * s2);
  r.v_W.z() = h / T * 30.0 * s2 * one_minus_s * one_minus_s;
  r.a_W.z() = h / (T * T) * 60.0 * s * one_minus_s * (1.0 - 2.0 * s);
  r.j_W.z() = h / (T * T * T) * (60.0 - 360.0 * s + 360.0 * s2);
  r.s_W.z() = h / (T * T * T * T) * (-360.0 + 720.0 * s);
  return r;
}

TakeoffOptions LandingReference::DescentOf(const LandingOptions& o) {
  constexpr const char* kLanding = "LandingOptions";
  RequireFinite(kLanding, "start_m", o.start_m);
  if (!(o.start_m.z() > 0.0)) ThrowValidation(kLanding, "start_m.z", o.start_m.z(), "a start above the ground (z > 0)");
  if (!std::isfinite(o.start_s) || o.start_s < 0.0) ThrowValidation(kLanding, "start_s", o.start_s, "a time >= 0 s");
  if (!std::isfinite(o.depth_m) || o.depth_m <= 0.0) ThrowValidation(kLanding, "depth_m", o.depth_m, "a depth > 0 m");
  TakeoffOptions d;
  d.start_m = o.start_m;
  d.altitude_m = -(o.start_m.z() + o.depth_m);
  d.max_speed_m_s = o.max_speed_m_s;
  d.yaw_rad = o.yaw_rad;
  return d;
}

LandingReference::LandingReference(const LandingOptions& options) : options_(options), descent_(DescentOf(options)) {}

ReferencePoint LandingReference::Evaluate(double t) const { return descent_.Evaluate(t - options_.start_s); }

// ---------------------------------------------------------------------------------------------
// Ramped-phase curves

RampedPhaseCurveReference::RampedPhaseCurveReference(double phase_rate_rad_s, double ramp_s,
                                                     double yaw_rad)
    : phase_rate_rad_s_(phase_rate_rad_s), ramp_s_(ramp_s), yaw_rad_(yaw_rad) {
  RG_INVARIANT(std::isfinite(phase_rate_rad_s_) && phase_rate_rad_s_ > 0.0,
               "phase rate must be validated by the derived class");
  RG_INVARIANT(std::isfinite(ramp_s_) && ramp_s_ >= 0.0,
               "ramp time must be validated by the derived class");
}

double RampedPhaseCurveReference::duration() const {
  return std::numeric_limits<double>::infinity();
}

double RampedPhaseCurveReference::period_s() const {
  return 2.0 * std::numbers::pi / phase_rate_rad_s_;
}

ReferencePoint RampedPhaseCurveReference::Evaluate(double t) const {
  const Phase ph = RampedPhase(ClampTime(t), phase_rate_rad_s_, ramp_s_);
  const CurvePoint c = CurveAt(ph.theta);
  const double thd = ph.rate;
  const double thdd = ph.accel;
  const double thddd = ph.jerk;
  ReferencePoint r;
  // Chain rule for p(t) = c(theta(t)).
  r.p_W = c.c;
  r.v_W = c.dc * thd;
  r.a_W = c.ddc * (thd * thd) + c.dc * thdd;
  r.j_W = c.dddc * (thd * thd * thd) + c.ddc * (3.0 * thd * thdd) + c.dc * thddd;
  r.yaw = yaw_rad_;
  return r;
}

// ---------------------------------------------------------------------------------------------
// Lemniscate

LemniscateReference::LemniscateReference(const LemniscateOptions& options)
    : RampedPhaseCurveReference(LemniscatePhaseRate(Validated(options)), options.ramp_s,
                                options.yaw_rad),
      options_(options) {}

RampedPhaseCurveReference::CurvePoint LemniscateReference::CurveAt(double theta) const {
  const double hx = 0.5 * options_.size_x_m;
  const double hy = 0.5 * options_.size_y_m;
  const double hz = 0.5 * options_.size_z_m;
  const double s1 = std::sin(theta);
  const double c1 = std::cos(theta);
  const double s2 = std::sin(2.0 * theta);
  const double c2 = std::cos(2.0 * theta);
  CurvePoint p;
  p.c = options_.center_m + Vector3(hx * s1, hy * s2, hz * s1);
  p.dc = Vector3(hx * c1, 2.0 * hy * c2, hz * c1);
  p.ddc = Vector3(-hx * s1, -4.0 * hy * s2, -hz * s1);
  p.dddc = Vector3(-hx * c1, -8.0 * hy * c2, -hz * c1);
  return p;
}

// ---------------------------------------------------------------------------------------------
// Circle

CircleReference::CircleReference(const CircleOptions& options)
    : RampedPhaseCurveReference(Validated(options).speed_m_s / options.radius_m, options.ramp_s,
                                options.yaw_rad),
      options_(options) {}

RampedPhaseCurveReference::CurvePoint CircleReference::CurveAt(double theta) const {
  const double r = options_.radius_m;
  // Counter-clockwise seen from above (z up) is increasing atan2(y, x).
  const double sign = options_.clockwise ? -1.0 : 1.0;
  const double s = std::sin(theta);
  const double c = std::cos(theta);
  const double rise = options_.climb_m_s * r / options_.speed_m_s;  // per radian: climb / Omega
  CurvePoint p;
  p.c = options_.center_m + Vector3(r * c, sign * r * s, rise * theta);
  p.dc = Vector3(-r * s, sign * r * c, rise);
  p.ddc = Vector3(-r * c, -sign * r * s, 0.0);
  p.dddc = Vector3(r * s, -sign * r * c, 0.0);
  return p;
}

// ---------------------------------------------------------------------------------------------
// Waypoints

WaypointReference::WaypointReference(const WaypointOptions& options) : options_(options) {
  const std::vector<Vector3>& w = options_.waypoints_m;
  if (w.size() < 2) {
    ThrowValidation(kWaypoint, "waypoints_m", fmt::format("({} waypoints)", w.size()),
                    "at least 2 waypoints");
  }
  for (std::size_t i = 0; i < w.size(); ++i) {
    RequireFinite(kWaypoint, fmt::format("waypoints_m.{}", i), w[i]);
    if (i > 0 && w[i] == w[i - 1]) {
      ThrowValidation(kWaypoint, fmt::format("waypoints_m.{}", i), FormatVector(w[i]),
                      fmt::format("a point distinct from waypoints_m.{}", i - 1));
    }
  }
  RequirePositive(kWaypoint, "max_speed_m_s", options_.max_speed_m_s);
  RequirePositive(kWaypoint, "max_accel_m_s2", options_.max_accel_m_s2);
  RequireNonNegative(kWaypoint, "dwell_s", options_.dwell_s);
  RequireFinite(kWaypoint, "yaw_rad", options_.yaw_rad);

  const double v_max = options_.max_speed_m_s;
  const double a_max = options_.max_accel_m_s2;
  double t = 0.0;
  segments_.reserve(w.size() - 1);
  for (std::size_t i = 0; i + 1 < w.size(); ++i) {
    Segment seg;
    const Vector3 delta = w[i + 1] - w[i];
    seg.start_m = w[i];
    seg.end_m = w[i + 1];
    seg.length_m = delta.norm();
    seg.direction = delta / seg.length_m;
    // Accelerating from rest to v covers v^2 / (2 a); braking the same. Max speed is reached only
    // when L >= v^2 / a, otherwise the profile peaks at sqrt(L a) (triangle).
    seg.peak_speed_m_s = std::min(v_max, std::sqrt(seg.length_m * a_max));
    seg.accel_time_s = seg.peak_speed_m_s / a_max;
    const double ramps_length = seg.peak_speed_m_s * seg.accel_time_s;  // 2 * v^2 / (2 a)
    seg.cruise_time_s = std::max(0.0, (seg.length_m - ramps_length) / seg.peak_speed_m_s);
    seg.move_time_s = 2.0 * seg.accel_time_s + seg.cruise_time_s;
    seg.start_time_s = t;
    t += seg.move_time_s;
    if (i + 2 < w.size()) t += options_.dwell_s;  // dwell at intermediate waypoints only
    segments_.push_back(seg);
  }
  duration_s_ = t;
}

ReferencePoint WaypointReference::Evaluate(double t) const {
  ReferencePoint r;
  r.yaw = options_.yaw_rad;
  const double tc = ClampTime(t);
  if (!(tc < duration_s_)) {
    r.p_W = options_.waypoints_m.back();
    return r;
  }
  // Last segment that started at or before tc (the first starts at 0 <= tc).
  const auto next = std::upper_bound(
      segments_.begin(), segments_.end(), tc,
      [](double time, const Segment& seg) { return time < seg.start_time_s; });
  const Segment& seg = *std::prev(next);
  const double tau = tc - seg.start_time_s;
  const double a = options_.max_accel_m_s2;
  double s = 0.0;        // distance along the segment [m]
  double speed = 0.0;    // [m/s]
  double s_accel = 0.0;  // [m/s^2]
  if (tau < seg.accel_time_s) {  // accelerate
    s = 0.5 * a * tau * tau;
    speed = a * tau;
    s_accel = a;
  } else if (tau < seg.accel_time_s + seg.cruise_time_s) {  // cruise
    s = 0.5 * a * seg.accel_time_s * seg.accel_time_s +
        seg.peak_speed_m_s * (tau - seg.accel_time_s);
    speed = seg.peak_speed_m_s;
  } else if (tau < seg.move_time_s) {  // brake, written from the end so that s(T) = L exactly
    const double to_go = seg.move_time_s - tau;
    s = seg.length_m - 0.5 * a * to_go * to_go;
    speed = a * to_go;
    s_accel = -a;
  } else {  // dwell at the end waypoint, exactly on it
    r.p_W = seg.end_m;
    return r;
  }
  r.p_W = seg.start_m + seg.direction * s;
  r.v_W = seg.direction * speed;
  r.a_W = seg.direction * s_accel;
  // j_W stays zero: acceleration is piecewise constant (see the class comment).
  return r;
}

}  // namespace rotorguard::planning
