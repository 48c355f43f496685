#pragma once
/// Flight metrics as defined in docs/metrics.md, accumulated sample by sample.
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "rotorguard/core/messages.h"
#include "rotorguard/core/types.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::harness {

/// Tracking error over [t1, t2]: RMSE = sqrt( (1/(t2-t1)) * integral |p - p_ref|^2 dt ), and
/// paper 000's eq. (37), which divides outside the root: sqrt( integral |p - p_ref|^2 dt ) / (t2-t1).
/// Integrated with the rectangle rule at the sampling step.
class TrackingErrorAccumulator {
 public:
  void Add(double dt, const Vector3& p, const Vector3& p_ref);
  double rmse() const;
  double rmse_eq37() const;
  double max_error() const { return max_error_; }
  double duration() const { return duration_; }

 private:
  double integral_ = 0.0;
  double duration_ = 0.0;
  double max_error_ = 0.0;
};

/// What a flight metric needs to know of the scenario: the tracking window, the success rule's
/// bound and the tilt that counts as recovered (docs/metrics.md).
struct FlightMetricsOptions {
  TimeNs step_ns = 1'000'000;   ///< the physics step at which the flight is sampled
  /// The tracking window [start, end) on the physics steps' grid; tracking_start_s is the
  /// scenario's value as written (summary.json "tracking_window_s").
  TimeNs tracking_start_ns = 0, tracking_end_ns = 0;
  double tracking_start_s = 0.0;
  double success_error_m = 0.5;       ///< the success rule's bound on |p - p_ref| [m]
  double recovered_tilt_rad = 0.0873;  ///< roll and pitch count as recovered below this tilt [rad]
  /// Where the vehicle file's body frame has its origin, from the true centre of gravity (body
  /// frame) [m]: positions are measured there, the point the stack estimates and the reference
  /// means (minus the drawn offset of the centre of gravity; zero in the ideal world).
  Vector3 body_origin_m = Vector3::Zero();
};

/// How a flight ended.
struct FlightEnd {
  TimeNs t_ns = 0;          ///< the simulated time at the end
  bool crashed = false;
  Vector3 p_W = Vector3::Zero();   ///< the final position (the crash site)
  std::optional<double> first_onset_s;  ///< the first fault's onset, when one happened
};

/// A flight's metrics (docs/metrics.md), accumulated from the true state at every physics step:
/// the tracking error over the window, the last breach of the success rule's bound, the lowest
/// altitude (after the first fault when there is one), the largest spin and tilt, and when the
/// tilt last exceeded the recovered bound after a fault.
class FlightMetrics {
 public:
  explicit FlightMetrics(const FlightMetricsOptions& options);

  /// The state at time t, before the step from t; p_ref is the reference the stack followed at t,
  /// and after_fault whether a fault has begun.
  void OnStep(TimeNs t, const vehicle::StateView& state, const Vector3& p_ref, bool after_fault);

  /// The stack's estimate at a control cycle against the true state then: the estimator's
  /// absolute trajectory error (no alignment: the stack starts at a known pose).
  void OnEstimate(const vehicle::StateView& state, const StateEstimate& estimate);
  /// The vehicle file's body-frame origin of the true state (FlightMetricsOptions::body_origin_m).
  Vector3 BodyOrigin(const vehicle::StateView& state) const;

  /// The last time the position error exceeded the success bound, and by how much.
  struct Violation {
    double t_s = 0.0;
    double error_m = 0.0;
  };
  const std::optional<Violation>& last_violation() const { return last_violation_; }

  /// Fills `summary`'s metrics: tracking_* and max_position_error_m (a crashed vehicle held at its
  /// crash site over the rest of the window for tracking_rmse_window_m, against `reference_at`,
  /// the position the stack's reference gives at a time), min_altitude_m (the final state
  /// counted), max_spin_rad_s, max_tilt_rad, tilt_recovery_s and estimate_*.
  void Finish(const FlightEnd& end, const std::function<Vector3(double t_s)>& reference_at, RunSummary* summary);

 private:
  FlightMetricsOptions options_;
  TrackingErrorAccumulator tracking_;
  std::optional<Violation> last_violation_;
  std::optional<double> last_tilted_s_;  // after a fault
  double min_altitude_all_ = std::numeric_limits<double>::infinity();
  double min_altitude_after_fault_ = std::numeric_limits<double>::infinity();
  std::optional<double> onset_altitude_;  ///< at the first step after the first fault's onset
  double max_spin_rad_s_ = 0.0;
  double max_tilt_rad_ = 0.0;
  double estimate_sum2_ = 0.0, estimate_max_m_ = 0.0, estimate_attitude_max_rad_ = 0.0;
  long estimates_ = 0;
};

}  // namespace rotorguard::harness
