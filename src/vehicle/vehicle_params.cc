#include "rotorguard/vehicle/vehicle_params.h"

#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "rotorguard/core/error.h"
#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::vehicle {

namespace {
constexpr char kOwner[] = "VehicleParams";
constexpr double kRpmPerRadPerSecond = 60.0 / (2.0 * std::numbers::pi);

void RequirePositive(const std::string& field, double value) {
  if (!std::isfinite(value) || value <= 0.0) ThrowValidation(kOwner, field, value, "a finite value > 0");
}
void RequireNonNegative(const std::string& field, double value) {
  if (!std::isfinite(value) || value < 0.0) ThrowValidation(kOwner, field, value, "a finite value >= 0");
}
}  // namespace

double ThrustCoefficientFromRpm(double k) { return k * kRpmPerRadPerSecond * kRpmPerRadPerSecond; }
double RadPerSecondToRpm(double w) { return w * kRpmPerRadPerSecond; }
double RpmToRadPerSecond(double rpm) { return rpm / kRpmPerRadPerSecond; }
double ThrustCoefficientToRpm(double k) { return k / (kRpmPerRadPerSecond * kRpmPerRadPerSecond); }

double VehicleParams::total_max_thrust_n() const {
  double sum = 0.0;
  for (const Rotor& r : rotors) sum += r.max_thrust_n;
  return sum;
}

void VehicleParams::Validate() const {
  RequirePositive("mass_kg", mass_kg);
  if (!inertia_kg_m2.allFinite() || (inertia_kg_m2 - inertia_kg_m2.transpose()).norm() >
                                        1e-9 * inertia_kg_m2.norm()) {
    throw ValidationError("inertia_kg_m2",
                          fmt::format("{}::inertia_kg_m2 is invalid; expected a finite symmetric "
                                      "3x3 matrix",
                                      kOwner));
  }
  // The principal moments, ascending.
  const Eigen::Vector3d moments =
      Eigen::SelfAdjointEigenSolver<Matrix3>(inertia_kg_m2, Eigen::EigenvaluesOnly).eigenvalues();
  if (moments[0] <= 0.0) {
    ThrowValidation(kOwner, "inertia_kg_m2", fmt::format("(smallest eigenvalue {:g})", moments[0]),
                    "a positive definite matrix");
  }
  // A rigid body's second moment of mass Σ = ∫ r rᵀ dm = ½ tr(I) 1 − I is positive semidefinite:
  // each principal moment is at most the sum of the other two (a flat plate reaches the bound).
  if (moments[2] > (moments[0] + moments[1]) * (1.0 + 1e-9)) {
    ThrowValidation(kOwner, "inertia_kg_m2",
                    fmt::format("(principal moments {:g}, {:g}, {:g})", moments[0], moments[1], moments[2]),
                    "a rigid body's inertia: each principal moment at most the sum of the other two");
  }
  for (int i = 0; i < 3; ++i) RequireNonNegative(fmt::format("rotor_drag_kg_s.{}", i), rotor_drag_kg_s[i]);
  RequireNonNegative("yaw_damping_n_m_s", yaw_damping_n_m_s);
  // Reported in the unit of the config files (per rpm^2), not the internal per (rad/s)^2.
  RequirePositive("thrust_coefficient_n_per_rpm2",
                  thrust_coefficient_n_s2 / (kRpmPerRadPerSecond * kRpmPerRadPerSecond));
  RequirePositive("motor_time_constant_s", motor_time_constant_s);
  RequirePositive("motor_stop_time_constant_s", motor_stop_time_constant_s);
  if (!std::isfinite(unloaded_speed_ratio) || unloaded_speed_ratio < 1.0 || unloaded_speed_ratio > 3.0) {
    ThrowValidation(kOwner, "unloaded_rpm_ratio", unloaded_speed_ratio, "a value in [1, 3]");
  }
  RequirePositive("collision_radius_m", collision_radius_m);
  for (std::size_t i = 0; i < collision_spheres.size(); ++i) {
    const CollisionSphere& c = collision_spheres[i];
    if (!c.centre_B.allFinite()) {
      ThrowValidation(kOwner, fmt::format("collision_spheres.{}.centre_m", i), "(non-finite)", "finite numbers");
    }
    RequirePositive(fmt::format("collision_spheres.{}.radius_m", i), c.radius_m);
    if (c.centre_B.norm() + c.radius_m > collision_radius_m * (1.0 + 1e-9)) {
      ThrowValidation(kOwner, fmt::format("collision_spheres.{}", i), c.centre_B.norm() + c.radius_m,
                      fmt::format("within the bounding collision_radius_m = {} m", collision_radius_m));
    }
  }
  RequireNonNegative("pwm_gain_n", pwm_gain_n);
  if (rotors.empty() || num_rotors() > kMaxRotors) {
    ThrowValidation(kOwner, "rotors", fmt::format("({} rotors)", rotors.size()),
                    fmt::format("between 1 and {} rotors", kMaxRotors));
  }
  for (int i = 0; i < num_rotors(); ++i) {
    const Rotor& r = rotors[i];
    if (!r.p_B.allFinite()) {
      ThrowValidation(kOwner, fmt::format("rotors.{}.position_m", i), "(non-finite)", "finite numbers");
    }
    RequireNonNegative(fmt::format("rotors.{}.yaw_coefficient_m", i), r.yaw_coefficient_m);
    RequirePositive(fmt::format("rotors.{}.max_thrust_n", i), r.max_thrust_n);
  }
  const double twr = total_max_thrust_n() / weight_n();
  if (twr <= 1.0) {
    ThrowValidation(kOwner, "rotors", fmt::format("(thrust-to-weight {:.3f})", twr),
                    "total max_thrust_n above the weight m*g (thrust-to-weight > 1)");
  }
  // The rotors must produce independent thrust, roll, pitch and yaw torque, and hold hover within
  // their limits with the minimum-norm allocation the nominal controller uses.
  const EffectivenessMatrix m = ComputeEffectivenessMatrix(rotors);
  AllocationMatrix pinv;
  try {
    pinv = PseudoInverse(m);
  } catch (const std::invalid_argument&) {
    ThrowValidation(kOwner, "rotors", fmt::format("({} rotors)", rotors.size()),
                    "a geometry that produces independent thrust, roll, pitch and yaw torques "
                    "(at least 4 rotors, not all on one line, yaw coefficients not all zero)");
  }
  const RotorVector hover = pinv * Eigen::Vector4d(weight_n(), 0.0, 0.0, 0.0);
  for (int i = 0; i < num_rotors(); ++i) {
    if (hover[i] < 0.0 || hover[i] > rotors[i].max_thrust_n) {
      ThrowValidation(kOwner, fmt::format("rotors.{}.max_thrust_n", i), rotors[i].max_thrust_n,
                      fmt::format("a limit that allows hover: the minimum-norm hover allocation needs "
                                  "{:.3f} N from rotor {}",
                                  hover[i], i));
    }
  }
}

}  // namespace rotorguard::vehicle
