#pragma once
/// Standard reference trajectories: hover, vertical takeoff, figure eight (lemniscate), circle and
/// straight-line waypoints. All are analytic (no numerical integration), give position through jerk
/// in the world frame (z up, SI units), hold a constant yaw (yaw_rate = 0) and treat t < 0 as
/// t = 0.
/// Each constructor validates its options and throws ValidationError (a std::invalid_argument)
/// "<Options>::<field> = <value> is invalid; expected <rule>".
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/core/types.h"

namespace rotorguard::planning {

// ---------------------------------------------------------------------------------------------
// Hover

struct HoverOptions {
  Vector3 position_m = Vector3::Zero();  ///< point to hold, world frame [m]; finite
  double yaw_rad = 0.0;                  ///< heading to hold [rad]; finite
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("position_m", &position_m,
             {.meaning = "the point to hold [m]",
              .min = -kMaxCoordinateM,
              .max = kMaxCoordinateM,
              .default_text = "the initial position"});
    a->Visit("yaw_rad", &yaw_rad,
             {.meaning = "the heading held [rad]", .min = -kTwoPi, .max = kTwoPi, .default_text = "the initial yaw"});
  }
};

/// Holds one point at rest forever (duration() = 0).
class HoverReference final : public ReferenceTrajectory {
 public:
  /// Throws ValidationError (std::invalid_argument) naming the first invalid field of `options`.
  explicit HoverReference(const HoverOptions& options);
  [[nodiscard]] ReferencePoint Evaluate(double t) const override;
  [[nodiscard]] double duration() const override { return 0.0; }
  /// The options this reference was built from.
  [[nodiscard]] const HoverOptions& options() const { return options_; }

 private:
  HoverOptions options_;
};

// ---------------------------------------------------------------------------------------------
// Takeoff

struct TakeoffOptions {
  Vector3 start_m = Vector3::Zero();  ///< position at t = 0, world frame [m]; finite
  double altitude_m = 1.0;            ///< climb above start_m [m]; finite, nonzero (< 0: a descent)
  double max_speed_m_s = 0.5;         ///< peak climb speed [m/s]; finite, > 0
  double yaw_rad = 0.0;               ///< heading held throughout [rad]; finite
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("altitude_m", &altitude_m,
             {.meaning = "the climb above the start [m] (a minimum-jerk climb)",
              .max = kMaxCoordinateM,
              .positive = true,
              .required = true});
    a->Visit("max_speed_m_s", &max_speed_m_s,
             {.meaning = "peak climb speed [m/s]", .min = kMinSpeedMS, .max = kMaxSpeedMS});
    a->Visit("yaw_rad", &yaw_rad,
             {.meaning = "the heading held [rad]", .min = -kTwoPi, .max = kTwoPi, .default_text = "the initial yaw"});
  }
};

/// Vertical climb (or, with a negative altitude, descent) from rest to rest along the minimum-jerk quintic
///   z(t) = z0 + h (10 s^3 - 15 s^4 + 6 s^5),  s = t / T,
/// whose velocity and acceleration are zero at both ends. The peak speed (at s = 1/2) is
/// 1.875 |h| / T, so T = 1.875 |h| / max_speed. Holds start + h after T. Jerk is the analytic
/// derivative h / T^3 (60 - 360 s + 360 s^2); it jumps at t = 0 and t = T (from/to zero), as it
/// does for every minimum-jerk rest-to-rest profile.
class TakeoffReference final : public ReferenceTrajectory {
 public:
  /// Throws ValidationError (std::invalid_argument) naming the first invalid field of `options`.
  explicit TakeoffReference(const TakeoffOptions& options);
  [[nodiscard]] ReferencePoint Evaluate(double t) const override;
  /// Climb time T = 1.875 altitude / max_speed [s].
  [[nodiscard]] double duration() const override { return climb_time_s_; }
  /// The options this reference was built from.
  [[nodiscard]] const TakeoffOptions& options() const { return options_; }

 private:
  TakeoffOptions options_;
  double climb_time_s_;
};

struct LandingOptions {
  Vector3 start_m = Vector3::Zero();  ///< position at t = 0, world frame [m]; finite, above the ground
  double start_s = 2.0;               ///< the start is held until then [s]; finite, >= 0
  double max_speed_m_s = 0.5;         ///< peak descent speed [m/s]; finite, > 0
  double depth_m = 0.3;               ///< the descent aims this far below the ground [m]; finite, > 0
  double yaw_rad = 0.0;               ///< heading held throughout [rad]; finite
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("start_s", &start_s, {.meaning = "the start is held until then [s]", .min = 0.0, .max = kMaxFlightS});
    a->Visit("max_speed_m_s", &max_speed_m_s,
             {.meaning = "peak descent speed [m/s]", .min = kMinSpeedMS, .max = kMaxSpeedMS});
    a->Visit("depth_m", &depth_m,
             {.meaning = "the descent aims this far below the ground, so that the ground stops it [m]",
              .max = 10.0,
              .positive = true});
    a->Visit("yaw_rad", &yaw_rad,
             {.meaning = "the heading held [rad]", .min = -kTwoPi, .max = kTwoPi, .default_text = "the initial yaw"});
  }
};

/// A landing: the start held until start_s, then TakeoffReference's minimum-jerk descent from rest to
/// depth_m below the ground (z = -depth_m). The ground stops the vehicle before the reference does,
/// and the stack's land detector (stack/supervisor.h) stops its motors, as an emergency landing's.
class LandingReference final : public ReferenceTrajectory {
 public:
  /// Throws ValidationError (std::invalid_argument) naming the first invalid field of `options`.
  explicit LandingReference(const LandingOptions& options);
  [[nodiscard]] ReferencePoint Evaluate(double t) const override;
  /// The hold and the descent [s].
  [[nodiscard]] double duration() const override { return options_.start_s + descent_.duration(); }

 private:
  static TakeoffOptions DescentOf(const LandingOptions& options);
  LandingOptions options_;
  TakeoffReference descent_;
};

// ---------------------------------------------------------------------------------------------
// Parametric curves with a ramped phase (shared by the lemniscate and the circle)

/// A periodic curve c(theta) (period 2 pi in theta) traversed with a phase theta(t) that starts at
/// 0 with zero rate and zero phase acceleration and reaches the constant rate Omega after ramp_s:
///   thd(t)   = Omega S(t / ramp_s),  S(s) = 10 s^3 - 15 s^4 + 6 s^5  (quintic smoothstep),
///   theta(t) = Omega ramp_s (2.5 s^4 - 3 s^5 + s^6)          for t <  ramp_s,
///   theta(t) = Omega (t - ramp_s / 2)                         for t >= ramp_s.
/// S, S' and S'' are continuous at both ends of the ramp, so theta is C3 and the reference is
/// continuous from position through jerk (chain rule with c', c'', c'''). With ramp_s = 0 the
/// phase runs at Omega from t = 0 (the reference then starts moving, not at rest).
/// duration() is +infinity.
class RampedPhaseCurveReference : public ReferenceTrajectory {
 public:
  /// c(theta(t)) and its time derivatives by the chain rule.
  [[nodiscard]] ReferencePoint Evaluate(double t) const final;
  /// +infinity: the curve is periodic.
  [[nodiscard]] double duration() const final;
  /// Steady phase rate Omega after the ramp [rad/s].
  [[nodiscard]] double phase_rate_rad_s() const { return phase_rate_rad_s_; }
  /// Time for one lap once the ramp is over, 2 pi / Omega [s].
  [[nodiscard]] double period_s() const;
  /// Time to reach the steady phase rate from rest [s].
  [[nodiscard]] double ramp_s() const { return ramp_s_; }

 protected:
  /// c(theta) and its first three derivatives with respect to theta.
  struct CurvePoint {
    Vector3 c = Vector3::Zero();
    Vector3 dc = Vector3::Zero();
    Vector3 ddc = Vector3::Zero();
    Vector3 dddc = Vector3::Zero();
  };

  /// Arguments must already be validated by the derived class: Omega > 0, ramp_s >= 0, all finite.
  RampedPhaseCurveReference(double phase_rate_rad_s, double ramp_s, double yaw_rad);

 private:
  [[nodiscard]] virtual CurvePoint CurveAt(double theta) const = 0;

  double phase_rate_rad_s_;
  double ramp_s_;
  double yaw_rad_;
};

// ---------------------------------------------------------------------------------------------
// Lemniscate (figure eight)

struct LemniscateOptions {
  Vector3 center_m = Vector3::Zero();  ///< centre of the figure eight, world frame [m]; finite
  double size_x_m = 6.0;               ///< full extent along x [m]; finite, > 0
  double size_y_m = 3.0;               ///< full extent along y [m]; finite, > 0
  double size_z_m = 1.0;               ///< full extent along z [m]; finite, >= 0 (0: planar)
  double max_speed_m_s = 2.0;          ///< top speed once ramped up [m/s]; finite, > 0
  double ramp_s = 3.0;                 ///< time to full phase rate from rest [s]; finite, >= 0
  double yaw_rad = 0.0;                ///< heading held throughout [rad]; finite
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("center_m", &center_m,
             {.meaning = "centre of the figure eight x = sx/2 sin θ, y = sy/2 sin 2θ, z = sz/2 sin θ [m]",
              .min = -kMaxCoordinateM,
              .max = kMaxCoordinateM,
              .default_text = "the initial position"});
    a->Visit("size_m", TripleOf{&size_x_m, &size_y_m, &size_z_m},
             {.meaning = "its full extent [sx, sy, sz] [m]",
              .min = 0.0,
              .max = kMaxCoordinateM,
              .rule_note = "sx and sy > 0"});
    a->Visit("max_speed_m_s", &max_speed_m_s,
             {.meaning = "top speed once ramped up [m/s]", .min = kMinSpeedMS, .max = kMaxSpeedMS, .required = true});
    a->Visit("ramp_s", &ramp_s, {.meaning = "time to full phase rate from rest [s]", .min = 0.0, .max = kMaxTimeoutS});
    a->Visit("yaw_rad", &yaw_rad,
             {.meaning = "the heading held [rad]", .min = -kTwoPi, .max = kTwoPi, .default_text = "the initial yaw"});
  }
};

/// Figure eight c(theta) = center + [sx/2 sin(theta), sy/2 sin(2 theta), sz/2 sin(theta)]
/// (default 6 x 3 x 1 m, as in the paper), starting at the centre at rest. The phase rate is
/// Omega = max_speed / sqrt(sx^2/4 + sz^2/4 + sy^2), the fastest point being the centre crossing.
class LemniscateReference final : public RampedPhaseCurveReference {
 public:
  /// Throws ValidationError (std::invalid_argument) naming the first invalid field of `options`.
  explicit LemniscateReference(const LemniscateOptions& options);
  /// The options this reference was built from.
  [[nodiscard]] const LemniscateOptions& options() const { return options_; }

 private:
  [[nodiscard]] CurvePoint CurveAt(double theta) const override;

  LemniscateOptions options_;
};

// ---------------------------------------------------------------------------------------------
// Circle

struct CircleOptions {
  Vector3 center_m = Vector3::Zero();  ///< centre, world frame [m]; circle at its z; finite
  double radius_m = 1.0;               ///< [m]; finite, > 0
  double speed_m_s = 1.0;              ///< tangential speed once ramped up [m/s]; finite, > 0
  double ramp_s = 3.0;                 ///< time to reach full speed from rest [s]; finite, >= 0
  double yaw_rad = 0.0;                ///< heading held throughout [rad]; finite
  bool clockwise = false;              ///< seen from above (z up); false: counter-clockwise
  /// Vertical speed once ramped up [m/s]: non-zero makes the circle a helix (paper 002's spiral),
  /// z = center.z + climb_m_s * theta / Omega; finite.
  double climb_m_s = 0.0;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("center_m", &center_m,
             {.meaning = "centre; the circle starts at centre + [radius, 0, 0] [m]",
              .min = -kMaxCoordinateM,
              .max = kMaxCoordinateM,
              .required = true});
    // From a centimetre: the phase rate is speed / radius, the acceleration speed² / radius.
    a->Visit("radius_m", &radius_m, {.meaning = "[m]", .min = 0.01, .max = kMaxCoordinateM, .required = true});
    a->Visit(
        "speed_m_s", &speed_m_s,
        {.meaning = "tangential speed once ramped up [m/s]", .min = kMinSpeedMS, .max = kMaxSpeedMS, .required = true});
    a->Visit("ramp_s", &ramp_s, {.meaning = "time to full speed from rest [s]", .min = 0.0, .max = kMaxTimeoutS});
    a->Visit("clockwise", &clockwise, {.meaning = "seen from above"});
    a->Visit("climb_m_s", &climb_m_s,
             {.meaning = "vertical speed: non-zero makes the circle a helix (paper 002's spiral) [m/s]",
              .min = -kMaxSpeedMS,
              .max = kMaxSpeedMS});
    a->Visit("yaw_rad", &yaw_rad,
             {.meaning = "the heading held [rad]", .min = -kTwoPi, .max = kTwoPi, .default_text = "the initial yaw"});
  }
};

/// Horizontal circle c(theta) = center + radius [cos(theta), +-sin(theta), 0] (minus when
/// clockwise), starting at center + [radius, 0, 0] at rest; Omega = speed / radius. With a climb
/// it rises climb_m_s / Omega per radian: a helix.
class CircleReference final : public RampedPhaseCurveReference {
 public:
  /// Throws ValidationError (std::invalid_argument) naming the first invalid field of `options`.
  explicit CircleReference(const CircleOptions& options);
  /// The options this reference was built from.
  [[nodiscard]] const CircleOptions& options() const { return options_; }

 private:
  [[nodiscard]] CurvePoint CurveAt(double theta) const override;

  CircleOptions options_;
};

// ---------------------------------------------------------------------------------------------
// Waypoints

struct WaypointOptions {
  std::vector<Vector3> waypoints_m;  ///< world frame [m]; at least 2, finite, consecutive distinct
  double max_speed_m_s = 1.0;        ///< speed limit on every segment [m/s]; finite, > 0
  double max_accel_m_s2 = 1.0;       ///< acceleration limit on every segment [m/s^2]; finite, > 0
  double dwell_s = 0.0;              ///< pause at each intermediate waypoint [s]; finite, >= 0
  double yaw_rad = 0.0;              ///< heading held throughout [rad]; finite
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("waypoints_m", &waypoints_m,
             {.meaning = "the points flown to from the start, in turn, stopping at each [m]",
              .min = -kMaxCoordinateM,
              .max = kMaxCoordinateM,
              .required = true});
    a->Visit("max_speed_m_s", &max_speed_m_s,
             {.meaning = "speed limit of the trapezoidal profile [m/s]",
              .min = kMinSpeedMS,
              .max = kMaxSpeedMS,
              .required = true});
    a->Visit("max_accel_m_s2", &max_accel_m_s2,
             {.meaning = "its acceleration limit [m/s²]", .min = kMinAccelerationMS2, .max = kMaxAccelerationMS2});
    a->Visit("dwell_s", &dwell_s,
             {.meaning = "pause at each intermediate waypoint [s]", .min = 0.0, .max = kMaxTimeoutS});
    a->Visit("yaw_rad", &yaw_rad,
             {.meaning = "the heading held [rad]", .min = -kTwoPi, .max = kTwoPi, .default_text = "the initial yaw"});
  }
};

/// Straight segments between consecutive waypoints, each flown from rest to rest with a
/// trapezoidal speed profile (accelerate at max_accel, cruise at max_speed, brake at max_accel),
/// or a triangular one (peak speed sqrt(L max_accel)) when the segment length L < max_speed^2 /
/// max_accel. Segment time: L / v + v / a (trapezoid) or 2 sqrt(L / a) (triangle). The reference
/// stops for dwell_s at each intermediate waypoint and holds the last waypoint afterwards.
/// Acceleration is piecewise constant, so it steps at the phase switches and the jerk reported is
/// zero everywhere (the true jerk is impulsive at the switches): a controller tracking this
/// reference sees acceleration steps. Prefer the lemniscate or a polynomial trajectory when a
/// smooth jerk matters.
class WaypointReference final : public ReferenceTrajectory {
 public:
  /// Throws ValidationError (std::invalid_argument) naming the first invalid field of `options`.
  explicit WaypointReference(const WaypointOptions& options);
  [[nodiscard]] ReferencePoint Evaluate(double t) const override;
  /// Sum of the segment times plus the dwells [s].
  [[nodiscard]] double duration() const override { return duration_s_; }
  /// The options this reference was built from.
  [[nodiscard]] const WaypointOptions& options() const { return options_; }

 private:
  struct Segment {
    Vector3 start_m = Vector3::Zero();
    Vector3 end_m = Vector3::Zero();
    Vector3 direction = Vector3::Zero();  ///< unit vector from start to end
    double length_m = 0.0;
    double peak_speed_m_s = 0.0;  ///< max_speed (trapezoid) or sqrt(L a) (triangle)
    double accel_time_s = 0.0;    ///< peak_speed / max_accel (also the braking time)
    double cruise_time_s = 0.0;   ///< time at peak speed (0 for a triangle)
    double move_time_s = 0.0;     ///< 2 accel_time + cruise_time
    double start_time_s = 0.0;    ///< since the start of the reference
  };

  WaypointOptions options_;
  std::vector<Segment> segments_;
  double duration_s_ = 0.0;
};

}  // namespace rotorguard::planning
