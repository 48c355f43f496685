#pragma once
/// Multirotor parameters as data: rigid body, aerodynamics, motors and a list of rotors.
#include <string>
#include <vector>

#include "rotorguard/core/types.h"

namespace rotorguard::vehicle {

/// Propeller rotation seen from above. A counter-clockwise propeller pushes the body clockwise:
/// its reaction torque about body z is negative (paper 000, eq. 5: rotors 0 and 1).
enum class SpinDirection { kCounterClockwise, kClockwise };

struct Rotor {
  Vector3 p_B = Vector3::Zero();  ///< rotor hub relative to the centre of gravity, body frame [m]
  SpinDirection direction = SpinDirection::kCounterClockwise;
  double yaw_coefficient_m = 0.0;  ///< kappa_t: reaction torque per newton of thrust [N*m/N]
  double max_thrust_n = 0.0;       ///< T_bar [N]

  /// +1 when the reaction torque about body z is positive for positive thrust.
  double yaw_sign() const { return direction == SpinDirection::kClockwise ? 1.0 : -1.0; }
};

/// A sphere of the body that must not touch an obstacle (body frame).
struct CollisionSphere {
  Vector3 centre_B = Vector3::Zero();
  double radius_m = 0.0;
};

struct VehicleParams {
  std::string name;
  double mass_kg = 0.0;                            ///< m_0
  Matrix3 inertia_kg_m2 = Matrix3::Zero();         ///< I_v, symmetric positive definite
  Vector3 rotor_drag_kg_s = Vector3::Zero();       ///< diagonal of D (eq. 1) [kg/s]
  double yaw_damping_n_m_s = 0.0;                  ///< k_d,psi (eq. 3) [N*m*s]
  double thrust_coefficient_n_s2 = 0.0;            ///< k_n with speed in rad/s: T = k_n w^2
  double motor_time_constant_s = 0.0;              ///< sigma (eq. 6)
  double motor_stop_time_constant_s = 0.0;         ///< decay of a stopped motor's speed
  double unloaded_speed_ratio = 1.0;               ///< speed of a motor without propeller / loaded
  double collision_radius_m = 0.0;                 ///< sphere about the CoG that bounds the body [m]
  /// The body's shape for collision checks when it is not one sphere (an assembly: one sphere per
  /// unit, paper 002's footprint); empty: the sphere of collision_radius_m about the CoG.
  std::vector<CollisionSphere> collision_spheres;
  /// K of paper 004, eq. (2): thrust per unit of PWM input [N] (T_i = K u_i), for vehicles driven
  /// by PWM inputs (PwmQuadModel); 0 when the vehicle has no PWM model.
  double pwm_gain_n = 0.0;
  std::vector<Rotor> rotors;

  int num_rotors() const { return static_cast<int>(rotors.size()); }
  double weight_n() const { return mass_kg * kGravity; }
  double total_max_thrust_n() const;

  /// Checks every rule (positive mass, positive definite inertia, thrust-to-weight above one, ...).
  /// Throws ValidationError naming the field ("rotors.2.max_thrust_n"), its value and the rule.
  void Validate() const;
};

/// k_n given per rpm^2 (as in paper 000, Table II) converted to per (rad/s)^2.
double ThrustCoefficientFromRpm(double k_n_per_rpm2);
/// Motor speed conversions between rad/s (inside) and rpm (telemetry, configs).
double RadPerSecondToRpm(double w);
double RpmToRadPerSecond(double rpm);

}  // namespace rotorguard::vehicle
