#pragma once
/// Control allocation by the pseudo-inverse of the effectiveness matrix, with saturation; whether
/// a vehicle can still hover on the rotors it has left.
#include <optional>
#include <vector>

#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/multirotor.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::control {

/// Minimum-norm allocation t = M^+ [T; tau] followed by clipping to [0, T_bar] per rotor.
/// Not fault tolerant: it ignores failed rotors (the "no FTC" baseline of later benchmarks).
class PseudoInverseAllocator {
 public:
  explicit PseudoInverseAllocator(const vehicle::MultirotorModel& model);
  /// `wrench` = [T; tau_x; tau_y; tau_z] in the body frame. Returns true when no rotor saturated.
  bool Allocate(const Eigen::Vector4d& wrench, RotorVector* thrust) const;

 private:
  AllocationMatrix pinv_;
  RotorVector max_thrust_;
};

/// The minimum-norm rotor thrusts that hold the vehicle's weight with zero roll and pitch torque,
/// each in [0, max_thrust_n] and zero on a failed rotor, or none when no such split exists: the
/// vehicle cannot hover on what is left. Yaw is left free (after a failure it is given up and the
/// spin balances it against the yaw damping). The test is static: a vehicle that could fly only by
/// balancing a torque gyroscopically while spinning (Mueller and D'Andrea's flight on one
/// propeller) is judged unable to. `failed` has one entry per rotor.
std::optional<RotorVector> HoverThrustSplit(const vehicle::VehicleParams& vehicle, const std::vector<bool>& failed);

}  // namespace rotorguard::control
