#pragma once
/// Baseline "INDI": incremental nonlinear dynamic inversion for a quadrotor that lost one rotor, in
/// the spirit of Sun, Wang, Chu and de Visser (T-RO 2021, "Incremental nonlinear fault-tolerant
/// control of a quadrotor with complete loss of two opposing rotors") and Sun et al. (RA-L 2021);
/// our re-implementation, driven by a fault detector's isolation.
///
/// Before a failure it flies as the nominal cascade. After it, yaw is given up and the vehicle
/// spins; the controller steers a body-fixed *primary axis* n_B towards the desired thrust
/// direction (a reduced attitude). n_B is the spin axis of the relaxed hover: the rotor diagonal to
/// the failed one carries `opposite_ratio` times the thrust of its two neighbours, and the roll and
/// pitch torque this leaves is balanced by the gyroscopic torque of the spin (RelaxedHover).
///
/// With h = R^T n_des (the desired direction in the body frame), h' = h x w and
/// h'' = h' x w + h x w'. The outer law asks h''_xy = k_h (n_B - h)_xy - d_h h'_xy; solving for the
/// roll and pitch angular accelerations (the measured yaw acceleration kept) gives w'_des, and the
/// incremental law tau = tau_f + I (w'_des - w'_f) turns it into torques: tau_f from the ESC
/// telemetry thrusts, w'_f from the differentiated gyro, through the same filter so that both are
/// synchronous (Sun et al., Sec. III). Thrust and the two tilt torques are inverted through the
/// three remaining rotors.
#include <optional>
#include <vector>

#include "rotorguard/control/controller.h"
#include "rotorguard/control/nominal_controller.h"
#include "rotorguard/control/position_loop.h"
#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/filters.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::control {

struct IndiControllerOptions {
  /// The outer loop after a failure (before it, `nominal` flies); the defaults are its defaults.
  PositionLoopOptions position;
  double k_h = 250.0;  ///< reduced-attitude stiffness [1/s^2], > 0
  double d_h = 35.0;   ///< reduced-attitude damping [1/s], > 0
  /// Relaxed hover: thrust of the failed rotor's diagonal twin relative to its neighbours, in
  /// [0, 1). 0 idles it (the primary axis is then the body z axis) and leaves it no authority
  /// downwards; 0.2 tilts the primary axis by about 0.27 rad on the reference quadrotor.
  double opposite_ratio = 0.2;
  /// Cut-off of the second-order low-pass shared by the angular-acceleration and the measured
  /// thrust channels [Hz], > 0 and below half of `sample_hz`.
  double filter_cutoff_hz = 50.0;
  double sample_hz = 200.0;  ///< rate at which Compute is called [Hz], > 0
  NominalControllerOptions nominal;  ///< before any failure
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    position.Serialize(a);  // used after a failure; before it, stack.nominal flies
    a->Visit("k_h", &k_h, {.meaning = "reduced-attitude stiffness [1/s²]", .max = 1e5, .positive = true});
    a->Visit("d_h", &d_h, {.meaning = "reduced-attitude damping [1/s]", .max = 1000.0, .positive = true});
    a->Visit("opposite_ratio", &opposite_ratio,
             {.meaning = "relaxed hover: the failed rotor's twin's thrust relative to its neighbours",
              .min = 0.0,
              .max = 1.0,
              .open_max = true});
    a->Visit(
        "filter_cutoff_hz", &filter_cutoff_hz,
        {.meaning = "cut-off of the angular-acceleration and thrust filters [Hz], below half of stack.control_rate_hz",
         .max = kMaxRateHz / 2.0,
         .positive = true});
  }
};

/// The relaxed-hover equilibrium of a quadrotor with one failed rotor: the spin axis n_B (unit, body
/// frame, pointing up in the world), the spin rate about it and the rotor thrusts.
struct RelaxedHover {
  Vector3 primary_axis_B = Vector3::UnitZ();
  double spin_rate_rad_s = 0.0;
  RotorVector thrust_n;
};

/// Solves the relaxed hover for `failed` with the diagonal twin at `opposite_ratio` of its
/// neighbours: weight carried along n_B, yaw torque against the yaw damping, roll/pitch torque
/// against the gyroscopic torque of w = r n_B (fixed-point iteration; a diagonal inertia is
/// assumed). Throws std::invalid_argument for a vehicle that is not a quadrotor, without yaw
/// damping, or when the balance has no feasible solution (an inertia with I_zz = I_xx cannot hold
/// a tilted spin).
RelaxedHover SolveRelaxedHover(const vehicle::MultirotorModel& model, int failed, double opposite_ratio);

class IndiController final : public Controller {
 public:
  /// Throws ValidationError for bad options and std::invalid_argument for a vehicle that is not a
  /// quadrotor (the method is for one) or whose relaxed hover cannot be solved for some rotor.
  IndiController(const vehicle::MultirotorModel& model, const IndiControllerOptions& options);
  std::string_view name() const override { return "indi"; }
  void Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t, double dt,
               RotorVector* thrust_command) override;
  void Reset() override;
  void SetRotorFailed(int rotor) override;
  /// The equilibrium in use after a failure (empty before).
  const std::optional<RelaxedHover>& relaxed_hover() const { return hover_; }

 private:
  const vehicle::MultirotorModel& model_;
  IndiControllerOptions options_;
  NominalController nominal_;
  PositionLoop position_loop_;
  std::optional<int> failed_;
  std::vector<RelaxedHover> hovers_;  // per failed rotor
  std::optional<RelaxedHover> hover_;
  Eigen::Matrix3d inverse_map_ = Eigen::Matrix3d::Identity();  // [T; tau_x; tau_y] -> three rotors
  int remaining_[3] = {0, 0, 0};
  // Synchronous filters (Sun et al.): angular acceleration from the gyro, rotor
  // thrusts from telemetry (per rotor, so that the failed one can be left out).
  FilteredDerivative<3> alpha_filter_;
  LowPass2<4> thrust_filter_;
  bool filters_started_ = false;
};

}  // namespace rotorguard::control
