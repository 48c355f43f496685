#include "rotorguard/vehicle/pwm_model.h"

#include <cmath>

#include <fmt/format.h>

#include "rotorguard/core/error.h"

namespace rotorguard::vehicle {

PwmQuadModel PwmQuadModel::FromVehicle(const VehicleParams& v) {
  constexpr const char* kOwner = "VehicleParams";
  if (!(v.pwm_gain_n > 0.0)) ThrowValidation(kOwner, "pwm_gain_n", v.pwm_gain_n, "a PWM gain K > 0 N (paper 004, eq. 2)");
  if (v.num_rotors() != 4) {
    ThrowValidation(kOwner, "rotors", fmt::format("({} rotors)", v.num_rotors()), "4 rotors in a + layout");
  }
  const double arm = v.rotors[0].p_B.head<2>().norm();  // the others are checked against it
  const Eigen::Vector2d layout[4] = {{-arm, 0.0}, {arm, 0.0}, {0.0, arm}, {0.0, -arm}};
  const double sign[4] = {1.0, 1.0, -1.0, -1.0};
  const double tolerance = std::max(1e-3, 0.01 * arm);
  for (int i = 0; i < 4; ++i) {
    const Rotor& r = v.rotors[static_cast<std::size_t>(i)];
    if ((r.p_B.head<2>() - layout[i]).norm() > tolerance || std::abs(r.p_B.z()) > tolerance) {
      ThrowValidation(kOwner, fmt::format("rotors.{}.position_m", i),
                      fmt::format("[{:g}, {:g}, {:g}]", r.p_B.x(), r.p_B.y(), r.p_B.z()),
                      fmt::format("[{:g}, {:g}, 0] (paper 004's motor {} of a + layout with arm {:g} m)", layout[i].x(),
                                  layout[i].y(), i + 1, arm));
    }
    if (r.yaw_sign() != sign[i]) {
      ThrowValidation(kOwner, fmt::format("rotors.{}.direction", i), r.yaw_sign() > 0 ? "cw" : "ccw",
                      sign[i] > 0 ? "cw (eq. 2: +K_psi for motors 1 and 2)" : "ccw (eq. 2: -K_psi for motors 3 and 4)");
    }
    if (std::abs(r.yaw_coefficient_m - v.rotors[0].yaw_coefficient_m) > 1e-9 ||
        std::abs(r.max_thrust_n - v.rotors[0].max_thrust_n) > 1e-9) {
      ThrowValidation(kOwner, fmt::format("rotors.{}", i), "(differs from rotor 0)",
                      "identical motors (one K_psi and one u_max in eq. 2)");
    }
  }
  const Matrix3& J = v.inertia_kg_m2;
  if (std::abs(J(0, 1)) + std::abs(J(0, 2)) + std::abs(J(1, 2)) > 1e-9 * J.trace()) {
    ThrowValidation(kOwner, "inertia_kg_m2", "(products of inertia)", "a diagonal inertia (eq. 1)");
  }
  PwmQuadModel m;
  m.mass_kg = v.mass_kg;
  m.gain_n = v.pwm_gain_n;
  m.arm_m = arm;
  m.yaw_coefficient_m = v.rotors[0].yaw_coefficient_m;
  m.j1 = J(1, 1);
  m.j2 = J(0, 0);
  m.j3 = J(2, 2);
  m.u_max = v.rotors[0].max_thrust_n / v.pwm_gain_n;
  return m;
}

Eigen::Matrix4d PwmQuadModel::Mixer() const {
  const double K = gain_n, L = arm_m, Kpsi = yaw_coefficient_m;
  Eigen::Matrix4d M;
  M << K, K, K, K,                            // u_z
      K * L, -K * L, 0.0, 0.0,                // u_theta
      0.0, 0.0, K * L, -K * L,                // u_phi
      K * Kpsi, K * Kpsi, -K * Kpsi, -K * Kpsi;  // u_psi
  return M;
}

}  // namespace rotorguard::vehicle
