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

/// Moore-Penrose pseudo-inverse of an effectiveness matrix of full row rank (minimum-norm
/// allocation). Throws std::invalid_argument when the matrix is rank deficient.
AllocationMatrix PseudoInverse(const EffectivenessMatrix& m);

}  // namespace rotorguard::vehicle
