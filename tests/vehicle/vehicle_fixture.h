#pragma once
/// The reference vehicle of paper 000 (Table II and DESIGN.md), built in code for unit tests that
/// must not depend on config files.
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::testing {

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

}  // namespace rotorguard::testing
