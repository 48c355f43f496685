#pragma once
/// What the NMPC's model misses, estimated in flight so that constant model errors leave no
/// steady-state error (offset-free MPC after Pannocchia and Rawlings, 2003): an extended-state
/// observer on the velocity and on the body rate, each with a constant disturbance as its extra
/// state, driven by the prediction model's own accelerations at the measured state. A mass,
/// thrust-coefficient or drag error becomes a world-frame acceleration, a centre-of-gravity offset
/// or an external torque a body-frame angular acceleration (docs/control.md, "Offset-free NMPC").
#include <Eigen/Core>
#include <vector>

#include "rotorguard/control/nmpc_model.h"
#include "rotorguard/core/config_schema.h"

namespace rotorguard::control {

struct DisturbanceObserverOptions {
  bool enabled = true;  ///< false: the model is flown as the file gives it (no disturbance terms)
  /// The double pole of the velocity observer's error dynamics [rad/s], > 0: slow, so that a
  /// fault's first 0.2 s moves the estimate by 12 % of the fault's acceleration (docs/control.md).
  double force_bandwidth_rad_s = 3.0;
  /// The double pole of the body-rate observer's error dynamics [rad/s], > 0.
  double torque_bandwidth_rad_s = 6.0;
  /// Its double pole once a rotor failed and the vehicle spins [rad/s], >= 0 (0: the estimate
  /// stays where it was).
  double torque_bandwidth_after_failure_rad_s = 1.0;
  /// The estimates are clamped to these magnitudes: a world-frame acceleration [m/s²] and a
  /// body-frame angular acceleration [rad/s²], > 0. A constant model error that needs more is
  /// not one the file's vehicle can fly with.
  double max_acceleration_m_s2 = 5.0;
  double max_angular_acceleration_rad_s2 = 100.0;
  /// The observer runs while the state is above this altitude [m] (the ground is z = 0): on the
  /// ground its reaction is no disturbance to predict with.
  double min_altitude_m = 0.05;
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("enabled", &enabled, {.meaning = "estimate what the model misses and predict with it"});
    a->Visit("force_bandwidth_rad_s", &force_bandwidth_rad_s,
             {.meaning = "the velocity observer's double pole [rad/s]", .min = 1e-3, .max = 1e3});
    a->Visit("torque_bandwidth_rad_s", &torque_bandwidth_rad_s,
             {.meaning = "the body-rate observer's double pole [rad/s]", .min = 1e-3, .max = 1e3});
    a->Visit("torque_bandwidth_after_failure_rad_s", &torque_bandwidth_after_failure_rad_s,
             {.meaning = "... once a rotor failed and the vehicle spins [rad/s] (0: held)", .min = 0.0, .max = 1e3});
    a->Visit("max_acceleration_m_s2", &max_acceleration_m_s2,
             {.meaning = "the largest acceleration estimated [m/s²]", .min = 1e-6, .max = kMaxAccelerationMS2});
    a->Visit("max_angular_acceleration_rad_s2", &max_angular_acceleration_rad_s2,
             {.meaning = "the largest angular acceleration estimated [rad/s²]", .min = 1e-6, .max = 1e4});
    a->Visit("min_altitude_m", &min_altitude_m,
             {.meaning = "the observer runs above this altitude [m]", .min = 0.0, .max = kMaxCoordinateM});
  }
};

/// One observer per axis group: for the velocity v (world frame) with its model acceleration a(x),
///   prediction  v- = v^ + dt (a(x_prev) + d^),   innovation e = v_measured - v-,
///   correction  v^ = v- + k1 e,  d^ = d^ + k2 e,
/// and the same for the body rate. With k1 = 1 - p², k2 = (1 - p)² / dt and p = exp(-w dt) the
/// error dynamics [[1 - k1, dt (1 - k1)], [-k2, 1 - k2 dt]] have the double eigenvalue p: a
/// constant disturbance is found with no steady-state error, at the bandwidth w.
class DisturbanceObserver {
 public:
  DisturbanceObserver(const NmpcModel& model, const DisturbanceObserverOptions& options);
  /// One measurement of the state (NmpcModel's layout, the motor thrusts measured) at time t [s].
  /// The first, and any after a gap of more than 0.1 s, a non-finite one or one on the ground
  /// (at or below min_altitude_m), restarts the velocity and rate estimates and keeps the
  /// disturbances.
  void Update(const Eigen::VectorXd& x, double t);
  /// Back to zero disturbances and no measurement (and the torque estimate running again).
  void Reset();
  /// From now on the angular-acceleration estimate moves at torque_bandwidth_after_failure_rad_s
  /// (the force estimate runs on). For a vehicle spinning after a failure: there the gyroscopic
  /// coupling of a wrong inertia grows with the spin and is no constant, and a torque observer
  /// that chases it feeds the precession (docs/control.md).
  void SlowTorque() { torque_slowed_ = true; }
  /// The disturbances estimated at time `t` or just before it, from the last kHistory updates
  /// (about 5 s at 200 Hz; the oldest one kept when t is older): the value to return to when a
  /// fault found later is put into the model, so that the fault's own transient is not counted
  /// twice.
  void RewindTo(double t);
  const Eigen::Vector3d& acceleration_W() const { return d_a_; }
  const Eigen::Vector3d& angular_acceleration_B() const { return d_alpha_; }
  const DisturbanceObserverOptions& options() const { return options_; }

 private:
  const NmpcModel& model_;
  DisturbanceObserverOptions options_;
  bool have_prev_ = false;
  bool torque_slowed_ = false;
  double t_prev_ = 0.0;
  Eigen::Vector3d a_prev_, alpha_prev_;  // the model's accelerations at the previous measurement
  Eigen::Vector3d v_hat_, w_hat_, d_a_, d_alpha_;
  struct Stamped {
    double t;
    Eigen::Vector3d d_a, d_alpha;
  };
  static constexpr int kHistory = 1024;
  std::vector<Stamped> history_;  // a ring of kHistory entries: allocated once
  int history_next_ = 0, history_size_ = 0;
};

}  // namespace rotorguard::control
