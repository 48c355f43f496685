#include "rotorguard/harness/flight_metrics.h"

#include <algorithm>
#include <cmath>

#include "rotorguard/core/math.h"

namespace rotorguard::harness {

void TrackingErrorAccumulator::Add(double dt, const Vector3& p, const Vector3& p_ref) {
  const double e2 = (p - p_ref).squaredNorm();
  integral_ += e2 * dt;
  duration_ += dt;
  max_error_ = std::max(max_error_, std::sqrt(e2));
}

double TrackingErrorAccumulator::rmse() const {
  return duration_ > 0.0 ? std::sqrt(integral_ / duration_) : 0.0;
}

double TrackingErrorAccumulator::rmse_eq37() const {
  return duration_ > 0.0 ? std::sqrt(integral_) / duration_ : 0.0;
}

namespace {
double Finite(double v) { return std::isfinite(v) ? v : 0.0; }
}  // namespace

FlightMetrics::FlightMetrics(const FlightMetricsOptions& options) : options_(options) {}

Vector3 FlightMetrics::BodyOrigin(const vehicle::StateView& s) const {
  return s.p_W() + s.q_WB() * options_.body_origin_m;
}

void FlightMetrics::OnStep(TimeNs t, const vehicle::StateView& s, const Vector3& p_ref, bool after_fault) {
  const double t_s = ToSeconds(t);
  const Vector3 p = BodyOrigin(s);
  if (t >= options_.tracking_start_ns && t < options_.tracking_end_ns) {
    tracking_.Add(ToSeconds(options_.step_ns), p, p_ref);
  }
  const double error = (p - p_ref).norm();
  if (!(error <= options_.success_error_m)) last_violation_ = Violation{t_s, error};
  const double altitude = p.z();
  min_altitude_all_ = std::min(min_altitude_all_, altitude);
  if (after_fault) {
    if (!onset_altitude_) onset_altitude_ = altitude;
    min_altitude_after_fault_ = std::min(min_altitude_after_fault_, altitude);
  }
  max_spin_rad_s_ = std::max(max_spin_rad_s_, std::abs(s.w_B().z()));
  const double tilt = TiltOf(s.q_WB());
  if (after_fault && tilt > options_.recovered_tilt_rad) last_tilted_s_ = t_s;
  max_tilt_rad_ = std::max(max_tilt_rad_, tilt);
}

void FlightMetrics::OnEstimate(const vehicle::StateView& state, const StateEstimate& estimate) {
  if (!estimate.valid) return;
  const double e = (estimate.p_W - BodyOrigin(state)).norm();
  estimate_sum2_ += e * e;
  ++estimates_;
  estimate_max_m_ = std::max(estimate_max_m_, e);
  estimate_attitude_max_rad_ =
      std::max(estimate_attitude_max_rad_, LogSO3(state.q_WB().conjugate() * estimate.q_WB).norm());
}

void FlightMetrics::Finish(const FlightEnd& end, const std::function<Vector3(double)>& reference_at,
                           RunSummary* summary) {
  const bool after_fault = end.first_onset_s.has_value();
  min_altitude_all_ = std::min(min_altitude_all_, end.p_W.z());  // the final state (or the crash site)
  if (after_fault) {
    if (!onset_altitude_) onset_altitude_ = end.p_W.z();  // a fault at the flight's very end
    min_altitude_after_fault_ = std::min(min_altitude_after_fault_, end.p_W.z());
  }
  summary->tracking_rmse_m = Finite(tracking_.rmse());
  summary->tracking_rmse_eq37_m = Finite(tracking_.rmse_eq37());
  summary->max_position_error_m = Finite(tracking_.max_error());
  const TimeNs dt_ns = options_.step_ns;
  if (end.crashed) {
    // A wreck does not follow the reference: over the rest of the window the vehicle is where it
    // crashed, so that crashing early does not shorten the error's window (paper 002's Table II
    // counts its collided flights' errors). Sampled on the physics steps' grid, as the flight was.
    TimeNs t = end.t_ns;
    if (t < options_.tracking_start_ns) t += (options_.tracking_start_ns - t + dt_ns - 1) / dt_ns * dt_ns;
    for (; t < options_.tracking_end_ns; t += dt_ns) tracking_.Add(ToSeconds(dt_ns), end.p_W, reference_at(ToSeconds(t)));
  }
  summary->tracking_rmse_window_m = Finite(tracking_.rmse());
  const double end_s = ToSeconds(end.t_ns);
  summary->tracking_start_s = options_.tracking_start_s;
  // A flight that stopped early without a crash (its mission done) was tracked up to its stop.
  summary->tracking_end_s =
      end.crashed ? ToSeconds(options_.tracking_end_ns) : std::min(ToSeconds(options_.tracking_end_ns), end_s);
  summary->min_altitude_m = Finite(after_fault ? min_altitude_after_fault_ : min_altitude_all_);
  // MiniA (docs/metrics.md): the lowest altitude after the onset relative to the onset's; <= 0.
  summary->altitude_change_m.reset();
  if (after_fault) summary->altitude_change_m = Finite(min_altitude_after_fault_ - *onset_altitude_);
  summary->max_spin_rad_s = max_spin_rad_s_;
  summary->max_tilt_rad = max_tilt_rad_;
  summary->estimate_position_rmse_m =
      estimates_ > 0 ? Finite(std::sqrt(estimate_sum2_ / static_cast<double>(estimates_))) : 0.0;
  summary->estimate_position_max_m = Finite(estimate_max_m_);
  summary->estimate_attitude_max_rad = Finite(estimate_attitude_max_rad_);
  summary->tilt_recovery_s.reset();
  if (after_fault && !end.crashed) {
    const double onset = *end.first_onset_s;
    const double settle = last_tilted_s_.value_or(onset);
    // Still tilted at the very end: it never settled.
    if (settle < end_s - 2.0 * ToSeconds(dt_ns)) summary->tilt_recovery_s = std::max(0.0, settle - onset);
  }
}

}  // namespace rotorguard::harness
