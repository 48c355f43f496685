#include "rotorguard/vehicle/vehicle_params.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::vehicle {

namespace {
constexpr char kOwner[] = "VehicleParams";
constexpr double kRpmPerRadPerSecond = 60.0 / (2.0 * std::numbers::pi);

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

std::vector<Vector3> VehicleParams::LandingGear() const {
  if (!landing_gear_B.empty()) return landing_gear_B;
  std::vector<Vector3> feet;
  for (const Rotor& r : rotors) feet.emplace_back(r.p_B.x(), r.p_B.y(), -kDefaultGearDepth * collision_radius_m);
  return feet;
}

double VehicleParams::RestingHeight() const {
  double lowest = 0.0;
  for (const Vector3& f : LandingGear()) lowest = std::min(lowest, f.z());
  return -lowest;
}

double VehicleParams::PropellerRadius() const {
  if (propeller_radius_m > 0.0) return propeller_radius_m;
  double closest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < rotors.size(); ++i) {
    for (std::size_t j = i + 1; j < rotors.size(); ++j) closest = std::min(closest, (rotors[i].p_B - rotors[j].p_B).norm());
  }
  // Coincident hubs (a coaxial pair) say nothing of the radius.
  return std::isfinite(closest) && closest > 0.0 ? 0.5 * closest : 0.5 * collision_radius_m;
}

void VehicleParams::Validate() const {
  // Each key in its range (the rotors' and collision spheres' too, named "rotors.2.max_thrust_n",
  // the thrust coefficient in the files' unit), then the rules of the whole.
  CheckDeclaredRanges(kOwner, *this);
  if ((inertia_kg_m2 - inertia_kg_m2.transpose()).norm() > 1e-9 * inertia_kg_m2.norm()) {
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
  for (std::size_t i = 0; i < collision_spheres.size(); ++i) {
    const CollisionSphere& c = collision_spheres[i];
    if (c.centre_B.norm() + c.radius_m > collision_radius_m * (1.0 + 1e-9)) {
      ThrowValidation(kOwner, fmt::format("collision_spheres.{}", i), c.centre_B.norm() + c.radius_m,
                      fmt::format("within the bounding collision_radius_m = {} m", collision_radius_m));
    }
  }
  for (std::size_t i = 0; i < landing_gear_B.size(); ++i) {
    if (!(landing_gear_B[i].z() < 0.0)) {
      ThrowValidation(kOwner, fmt::format("landing_gear_m.{}", i), landing_gear_B[i].z(),
                      "a foot below the centre of gravity (body z < 0)");
    }
  }
  if (rotors.empty() || num_rotors() > kMaxRotors) {
    ThrowValidation(kOwner, "rotors", fmt::format("({} rotors)", rotors.size()),
                    fmt::format("between 1 and {} rotors", kMaxRotors));
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
