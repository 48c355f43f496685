#pragma once
/// The simplified quadrotor model of paper 004 (Chamseddine et al., JGCD 2012), eqs. (1)-(2):
///   ẍ = θ g,  ÿ = −φ g,  z̈ = u_z/m − g,  J1 θ̈ = u_θ,  J2 φ̈ = u_φ,  J3 ψ̈ = u_ψ,
///   u_z = K (u1 + u2 + u3 + u4),  u_θ = K L (u1 − u2),  u_φ = K L (u3 − u4),
///   u_ψ = K K_ψ (u1 + u2 − u3 − u4),
/// linearised about hover with ψ = 0, for a "+" quadrotor driven by PWM inputs u_i with thrust
/// T_i = K u_i. The vehicle's rotors 0..3 are the paper's motors 1..4: rotor 0 at (−L, 0), rotor 1
/// at (+L, 0) (a positive u_θ, rotor 0 above rotor 1, pitches about +y, which tilts the thrust
/// towards +x: ẍ = θ g), rotor 2 at (0, +L), rotor 3 at (0, −L), rotors 0 and 1 with a positive
/// reaction torque about z (clockwise, K_ψ = their yaw coefficient), 2 and 3 negative. θ is the
/// rotation about body y (pitch), φ about body x (roll); J1 = I_yy, J2 = I_xx, J3 = I_zz.
#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::vehicle {

struct PwmQuadModel {
  double mass_kg = 0.0;
  double gain_n = 0.0;             ///< K: thrust per unit PWM [N]
  double arm_m = 0.0;              ///< L: centre of mass to each motor [m]
  double yaw_coefficient_m = 0.0;  ///< K_ψ: reaction torque per newton of thrust [m]
  double j1 = 0.0, j2 = 0.0, j3 = 0.0;  ///< I_yy, I_xx, I_zz [kg m²]
  double u_max = 0.0;              ///< the largest PWM input (max_thrust / K)
  double gravity = kGravity;

  /// From a vehicle with a PWM gain and the rotor layout above (within 1 mm and 1 % of the arm).
  /// Throws ValidationError naming the vehicle's field ("rotors.2.position_m", "pwm_gain_n") and
  /// the rule it breaks.
  static PwmQuadModel FromVehicle(const VehicleParams& vehicle);

  /// The PWM input of each motor at hover, m g / (4 K) (eq. 19's first term).
  double hover_pwm() const { return mass_kg * gravity / (4.0 * gain_n); }
  /// Eq. (2): (u_z, u_θ, u_φ, u_ψ) = Mixer() (u1, u2, u3, u4).
  Eigen::Matrix4d Mixer() const;
};

}  // namespace rotorguard::vehicle
