#pragma once
/// The reference vehicle of paper 000 (Table II and configs/vehicles/zhou2025_quad.yaml), built in code for unit tests that
/// must not depend on config files.
#include "rotorguard/core/messages.h"
#include "rotorguard/vehicle/multirotor.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::testing {

/// A perfect estimate of the state `x` at time t: its pose, velocity, rates and motor thrusts.
inline StateEstimate ExactEstimate(const vehicle::StateVector& x, TimeNs t = 0) {
  const vehicle::StateView s(x);
  StateEstimate e;
  e.t_ns = t;
  e.valid = true;
  e.p_W = s.p_W();
  e.q_WB = s.q_WB();
  e.v_W = s.v_W();
  e.w_B = s.w_B();
  e.motor_thrust_n = x.tail(x.size() - vehicle::StateIndex::kMotor);
  return e;
}

inline vehicle::VehicleParams ReferenceQuad() {
  using vehicle::Rotor;
  using vehicle::SpinDirection;
  vehicle::VehicleParams p;
  p.name = "reference_quad";
  p.mass_kg = 1.15;
  p.inertia_kg_m2 = Eigen::Vector3d(6.862e-3, 6.992e-3, 8.650e-3).asDiagonal();
  p.rotor_drag_kg_s = Eigen::Vector3d(0.48, 0.50, 0.65);
  p.yaw_damping_n_m_s = 0.011;
  p.thrust_coefficient_n_s2 = vehicle::ThrustCoefficientFromRpm(1.41e-8);
  p.motor_time_constant_s = 0.03;
  p.motor_stop_time_constant_s = 0.005;
  p.unloaded_speed_ratio = 1.1;
  p.collision_radius_m = 0.2;
  const double a = 0.5 * std::sqrt(2.0) * 0.063;
  const double kappa = 0.0107;
  p.rotors = {
      Rotor{{a, -a, 0.0}, SpinDirection::kCounterClockwise, kappa, 11.5},
      Rotor{{-a, a, 0.0}, SpinDirection::kCounterClockwise, kappa, 11.5},
      Rotor{{a, a, 0.0}, SpinDirection::kClockwise, kappa, 11.5},
      Rotor{{-a, -a, 0.0}, SpinDirection::kClockwise, kappa, 11.5},
  };
  return p;
}

/// The Qball-X4-like vehicle of paper 004 (configs/vehicles/qball_x4.yaml): a + quadrotor with a
/// PWM gain, rotors 0..3 the paper's motors 1..4 (vehicle/pwm_model.h).
inline vehicle::VehicleParams QballX4() {
  using vehicle::Rotor;
  using vehicle::SpinDirection;
  vehicle::VehicleParams p;
  p.name = "qball_x4";
  p.mass_kg = 1.4;
  p.inertia_kg_m2 = Eigen::Vector3d(0.03, 0.03, 0.04).asDiagonal();
  p.rotor_drag_kg_s = Eigen::Vector3d(0.3, 0.3, 0.4);
  p.yaw_damping_n_m_s = 0.01;
  p.thrust_coefficient_n_s2 = vehicle::ThrustCoefficientFromRpm(9.5e-8);
  p.motor_time_constant_s = 0.0667;
  p.motor_stop_time_constant_s = 0.02;
  p.unloaded_speed_ratio = 1.1;
  p.collision_radius_m = 0.35;
  p.pwm_gain_n = 120.0;
  const double kappa = 4.0 / 120.0;
  p.rotors = {
      Rotor{{-0.2, 0.0, 0.0}, SpinDirection::kClockwise, kappa, 7.2},
      Rotor{{0.2, 0.0, 0.0}, SpinDirection::kClockwise, kappa, 7.2},
      Rotor{{0.0, 0.2, 0.0}, SpinDirection::kCounterClockwise, kappa, 7.2},
      Rotor{{0.0, -0.2, 0.0}, SpinDirection::kCounterClockwise, kappa, 7.2},
  };
  return p;
}

/// One unit of a modular assembly (configs/vehicles/mars_unit.yaml).
inline vehicle::VehicleParams MarsUnit() {
  using vehicle::Rotor;
  using vehicle::SpinDirection;
  vehicle::VehicleParams p;
  p.name = "mars_unit";
  p.mass_kg = 0.5;
  p.inertia_kg_m2 = Eigen::Vector3d(2.2e-3, 2.2e-3, 4.0e-3).asDiagonal();
  p.rotor_drag_kg_s = Eigen::Vector3d(0.10, 0.10, 0.15);
  p.yaw_damping_n_m_s = 0.004;
  p.thrust_coefficient_n_s2 = vehicle::ThrustCoefficientFromRpm(1.2e-8);
  p.motor_time_constant_s = 0.03;
  p.motor_stop_time_constant_s = 0.005;
  p.unloaded_speed_ratio = 1.1;
  p.collision_radius_m = 0.15;
  const double a = 0.075, kappa = 0.016;
  p.rotors = {
      Rotor{{a, -a, 0.0}, SpinDirection::kCounterClockwise, kappa, 2.6},
      Rotor{{-a, a, 0.0}, SpinDirection::kCounterClockwise, kappa, 2.6},
      Rotor{{a, a, 0.0}, SpinDirection::kClockwise, kappa, 2.6},
      Rotor{{-a, -a, 0.0}, SpinDirection::kClockwise, kappa, 2.6},
  };
  return p;
}

}  // namespace rotorguard::testing
