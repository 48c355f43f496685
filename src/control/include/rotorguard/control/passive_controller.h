#pragma once
/// Baseline "UnifP" of paper 000: one fixed controller that never reconfigures (no fault
/// detection), in the spirit of Ke, Cai and Quan's uniform passive FTC (T-RO 2023); our
/// re-implementation. It controls position through the thrust direction only (a reduced attitude:
/// yaw is left free to spin) and allocates with priority on thrust and tilt torques: a small
/// box-constrained least-squares problem that gives up the yaw torque entirely.
#include "rotorguard/control/controller.h"
#include "rotorguard/control/dense_qp.h"
#include "rotorguard/control/position_loop.h"
#include "rotorguard/core/config_schema.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::control {

struct PassiveControllerOptions {
  PositionLoopOptions position;  ///< the outer loop, as the nominal controller's
  double k_tilt = 9.0;   ///< reduced-attitude error -> roll/pitch rate [1/s], > 0
  double k_rate = 22.0;  ///< roll/pitch rate error -> angular acceleration [1/s], > 0
  /// Regularisation towards equal rotor thrusts (makes the 4-rotor, 3-objective allocation
  /// unique), relative to the thrust weight, > 0.
  double regularisation = 1e-3;
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    position.Serialize(a);
    a->Visit("k_tilt", &k_tilt,
             {.meaning = "reduced-attitude error to roll/pitch rate [1/s]", .max = 1000.0, .positive = true});
    a->Visit("k_rate", &k_rate,
             {.meaning = "roll/pitch rate error to angular acceleration [1/s]", .max = 1000.0, .positive = true});
    a->Visit(
        "regularisation", &regularisation,
        {.meaning = "weight towards equal rotor thrusts, relative to the thrust's", .max = 1000.0, .positive = true});
  }
};

class PassiveController final : public Controller {
 public:
  PassiveController(const vehicle::MultirotorModel& model, const PassiveControllerOptions& options);
  std::string_view name() const override { return "passive"; }
  void Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t, double dt,
               RotorVector* thrust_command) override;
  void Reset() override { position_loop_.Reset(); }

 private:
  const vehicle::MultirotorModel& model_;
  PassiveControllerOptions options_;
  PositionLoop position_loop_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> allocation_map_;  // rows [T; tau_x; tau_y] of M_t
  Eigen::Vector3d objective_weights_;                        // thrust, roll, pitch
  DenseQp qp_;
  DenseQpSolver solver_;
  RotorVector hover_;
};

}  // namespace rotorguard::control
