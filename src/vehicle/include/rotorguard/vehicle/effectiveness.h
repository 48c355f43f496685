#pragma once
/// Rotor geometry -> effectiveness matrix, a pure function of data (paper 000, eqs. 4-5).
#include <vector>

#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::vehicle {

/// Maps rotor thrusts to [T; tau_x; tau_y; tau_z] in the body frame, one column per rotor.
/// Thrust acts along body z at the rotor hub: tau_x = y_i T_i, tau_y = -x_i T_i,
/// tau_z = yaw_sign_i * kappa_t,i * T_i. For the reference quad this is eq. (5) of paper 000.
EffectivenessMatrix ComputeEffectivenessMatrix(const std::vector<Rotor>& rotors);

/// The rotors at the mirror image of `rotor` through the centre of gravity in the body's xy plane
/// (within 5 % of its arm): its diagonal twin on a quadrotor, whose thrust balances its roll and
/// pitch torque. Empty when there is none.
std::vector<int> DiagonalTwins(const std::vector<Rotor>& rotors, int rotor);

/// Moore-Penrose pseudo-inverse of an effectiveness matrix of full row rank (minimum-norm
/// allocation). Throws std::invalid_argument when the matrix is rank deficient.
AllocationMatrix PseudoInverse(const EffectivenessMatrix& m);

}  // namespace rotorguard::vehicle
