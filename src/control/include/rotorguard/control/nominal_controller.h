#pragma once
/// Nominal cascaded geometric controller: position -> thrust vector -> attitude -> body rates ->
/// torques, then pseudo-inverse allocation. Flatness feedforward of acceleration and jerk (and snap,
/// NominalControllerOptions::snap_feedforward).
/// Not fault tolerant: the "no FTC" row of the benchmarks.
#include "rotorguard/control/allocation.h"
#include "rotorguard/control/controller.h"
#include "rotorguard/control/position_loop.h"
#include "rotorguard/core/config_schema.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::control {

struct NominalControllerOptions {
  PositionLoopOptions position;       ///< the outer loop (scenario keys kp_position ... max_tilt_rad)
  Vector3 k_attitude = Vector3(9.0, 9.0, 4.0);    ///< attitude error -> rate [1/s], > 0
  Vector3 k_rate = Vector3(22.0, 22.0, 10.0);     ///< rate error -> angular acceleration [1/s], > 0
  double max_rate_rad_s = 8.0;        ///< commanded body-rate limit [rad/s], > 0
  /// The tilt's angular acceleration from the reference's snap as feed-forward. For a vehicle whose
  /// attitude is slow against its plans (an assembly: a 4x1 row's pitch inertia is 20 times a
  /// unit's). Off by default: a quadrotor's rate loop follows without it, and the replanner's brake
  /// to rest asks for snap beyond its rotors, whose feed-forward saturates them.
  bool snap_feedforward = false;
  /// Throws ValidationError naming the field.
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    position.Serialize(a);
    a->Visit("k_attitude", &k_attitude,
             {.meaning = "attitude error to body rate [1/s]", .max = 1000.0, .positive = true});
    a->Visit("k_rate", &k_rate,
             {.meaning = "rate error to angular acceleration [1/s]", .max = 1000.0, .positive = true});
    a->Visit("max_rate_rad_s", &max_rate_rad_s,
             {.meaning = "commanded body-rate limit [rad/s]", .max = kMaxBodyRateRadS, .positive = true});
    a->Visit("snap_feedforward", &snap_feedforward,
             {.meaning = "feed the tilt's angular acceleration forward from the reference's snap"});
  }
};

/// The cascade of NominalController up to the wrench: position loop -> thrust vector -> attitude ->
/// body rates -> [T; tau] about the centre of mass, for any rigid multirotor (an assembly of
/// units too: the torques scale with its inertia). Allocation is the caller's.
class CascadedWrenchLaw {
 public:
  /// Validates `options` (throws ValidationError).
  CascadedWrenchLaw(const vehicle::VehicleParams& vehicle, const NominalControllerOptions& options);
  /// [T; tau_x; tau_y; tau_z] in the body frame for the estimate and the reference point; `dt`
  /// advances the position loop's integral. False when an input is not finite or the estimate is
  /// not valid (the wrench is then not to be used).
  bool Compute(const StateEstimate& estimate, const ReferencePoint& reference, double dt, Eigen::Vector4d* wrench);
  void Reset() { position_loop_.Reset(); }

 private:
  vehicle::VehicleParams vehicle_;
  NominalControllerOptions options_;
  PositionLoop position_loop_;
};

class NominalController final : public Controller {
 public:
  NominalController(const vehicle::MultirotorModel& model, const NominalControllerOptions& options);
  std::string_view name() const override { return "nominal"; }
  void Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t, double dt,
               RotorVector* thrust_command) override;
  void Reset() override { law_.Reset(); }

 private:
  CascadedWrenchLaw law_;
  PseudoInverseAllocator allocator_;
  RotorVector hover_;
};

}  // namespace rotorguard::control
