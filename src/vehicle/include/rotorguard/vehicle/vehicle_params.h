#pragma once
/// Multirotor parameters as data: rigid body, aerodynamics, motors and a list of rotors.
#include <span>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"

namespace rotorguard::vehicle {

/// Propeller rotation seen from above. A counter-clockwise propeller pushes the body clockwise:
/// its reaction torque about body z is negative (paper 000, eq. 5: rotors 0 and 1).
enum class SpinDirection { kCounterClockwise, kClockwise };
inline constexpr EnumName<SpinDirection> kSpinDirectionNames[] = {{SpinDirection::kCounterClockwise, "ccw"},
                                                                  {SpinDirection::kClockwise, "cw"}};
constexpr std::span<const EnumName<SpinDirection>> NamesOf(const SpinDirection*) { return kSpinDirectionNames; }

struct Rotor {
  Vector3 p_B = Vector3::Zero();  ///< rotor hub relative to the centre of gravity, body frame [m]
  SpinDirection direction = SpinDirection::kCounterClockwise;
  double yaw_coefficient_m = 0.0;  ///< kappa_t: reaction torque per newton of thrust [N*m/N]
  double max_thrust_n = 0.0;       ///< T_bar [N]

  /// +1 when the reaction torque about body z is positive for positive thrust.
  double yaw_sign() const { return direction == SpinDirection::kClockwise ? 1.0 : -1.0; }

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("position_m", &p_B,
             {.meaning = "hub relative to the centre of gravity, body frame [m]",
              .min = -kMaxBodyOffsetM,
              .max = kMaxBodyOffsetM,
              .required = true});
    a->Visit("direction", &direction,
             {.meaning = "propeller rotation seen from above; ccw gives reaction torque -κ_t T", .required = true});
    // κ_t is a propeller's torque over its thrust: about a hundredth of its radius.
    a->Visit("yaw_coefficient_m", &yaw_coefficient_m, {.meaning = "κ_t [m]", .min = 0, .max = 1, .required = true});
    // A heavy-lift rotor gives a few hundred newtons.
    a->Visit("max_thrust_n", &max_thrust_n,
             {.meaning = "T̄ [N]; the sum must exceed m·g", .max = 1e4, .positive = true, .required = true});
  }
};

/// A sphere of the body that must not touch an obstacle (body frame).
struct CollisionSphere {
  Vector3 centre_B = Vector3::Zero();
  double radius_m = 0.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("centre_m", &centre_B,
             {.meaning = "[m], body frame", .min = -kMaxBodyOffsetM, .max = kMaxBodyOffsetM, .required = true});
    a->Visit("radius_m", &radius_m, {.meaning = "[m]", .max = kMaxBodyOffsetM, .positive = true, .required = true});
  }
};

struct VehicleParams {
  std::string name;
  double mass_kg = 0.0;                       ///< m_0
  Matrix3 inertia_kg_m2 = Matrix3::Zero();    ///< I_v, symmetric positive definite
  Vector3 rotor_drag_kg_s = Vector3::Zero();  ///< diagonal of D (eq. 1) [kg/s]
  double yaw_damping_n_m_s = 0.0;             ///< k_d,psi (eq. 3) [N*m*s]
  double thrust_coefficient_n_s2 = 0.0;       ///< k_n with speed in rad/s: T = k_n w^2
  double motor_time_constant_s = 0.0;         ///< sigma (eq. 6)
  double motor_stop_time_constant_s = 0.0;    ///< decay of a stopped motor's speed
  double unloaded_speed_ratio = 1.0;          ///< speed of a motor without propeller / loaded
  double collision_radius_m = 0.0;            ///< sphere about the CoG that bounds the body [m]
  /// The body's shape for collision checks when it is not one sphere (an assembly: one sphere per
  /// unit, paper 002's footprint); empty: the sphere of collision_radius_m about the CoG.
  std::vector<CollisionSphere> collision_spheres;
  /// K of paper 004, eq. (2): thrust per unit of PWM input [N] (T_i = K u_i), for vehicles driven
  /// by PWM inputs (PwmQuadModel); 0 when the vehicle has no PWM model.
  double pwm_gain_n = 0.0;
  std::vector<Rotor> rotors;
  /// The landing gear's feet relative to the centre of gravity, body frame [m]: the points the
  /// vehicle stands on (sim/contact.h). Empty: the default, LandingGear().
  std::vector<Vector3> landing_gear_B;
  /// The propellers' radius [m] (the ground effect's scale, sim/ground_effect.h); 0: the default,
  /// PropellerRadius().
  double propeller_radius_m = 0.0;

  /// The feet: landing_gear_B, or one below each rotor hub, kDefaultGearDepth collision radii
  /// below the centre of gravity (a frame whose legs hang under its motor mounts).
  std::vector<Vector3> LandingGear() const;
  /// The centre of gravity's height above flat ground when the vehicle stands level on its feet.
  double RestingHeight() const;
  static constexpr double kDefaultGearDepth = 0.25;
  /// propeller_radius_m, or the largest propellers that do not overlap: half the smallest
  /// distance between two hubs (a single rotor: half the collision radius).
  double PropellerRadius() const;

  int num_rotors() const { return static_cast<int>(rotors.size()); }
  double weight_n() const { return mass_kg * kGravity; }
  double total_max_thrust_n() const;

  /// Checks every rule (positive mass, positive definite inertia, thrust-to-weight above one, ...).
  /// Throws ValidationError naming the field ("rotors.2.max_thrust_n"), its value and the rule.
  void Validate() const;

  /// The keys of a vehicle file (configs/vehicles/).
  template <typename Archive>
  void Serialize(Archive* a);
};

/// k_n given per rpm^2 (as in paper 000, Table II) converted to per (rad/s)^2.
double ThrustCoefficientFromRpm(double k_n_per_rpm2);
/// Motor speed conversions between rad/s (inside) and rpm (telemetry, configs).
double RadPerSecondToRpm(double w);
double RpmToRadPerSecond(double rpm);
/// k_n per (rad/s)^2 back to per rpm^2.
double ThrustCoefficientToRpm(double k_n_per_rad_s2);

template <typename Archive>
void VehicleParams::Serialize(Archive* a) {
  // The bounds hold a passenger-carrying multirotor and the largest assembly, 16 units of a few
  // kilograms (64 rotors; configs/assemblies: inertia, drag and yaw damping grow with the units).
  a->Visit("name", &name, {.meaning = "label", .default_text = "vehicle"});
  a->Visit("mass_kg", &mass_kg, {.meaning = "m_0 [kg]", .max = 1000, .positive = true, .required = true});
  a->Visit("inertia_kg_m2", &inertia_kg_m2,
           {.meaning = "I_v [kg·m²]",
            .min = -1e5,
            .max = 1e5,
            .required = true,
            .rule_note = "symmetric positive definite"});
  a->Visit("rotor_drag_kg_s", &rotor_drag_kg_s,
           {.meaning = "diagonal of D (eq. 1) [kg/s]", .min = 0, .max = 1000, .required = true});
  a->Visit("yaw_damping_n_m_s", &yaw_damping_n_m_s,
           {.meaning = "k_dψ (eq. 3) [N·m·s]", .min = 0, .max = 1000, .required = true});
  // Paper 000's vehicle: 1.2e-8 N/rpm²; 1e-3 is 1000 N at 1000 rpm.
  a->Visit("thrust_coefficient_n_per_rpm2",
           ConvertedOf{&thrust_coefficient_n_s2, &ThrustCoefficientFromRpm, &ThrustCoefficientToRpm},
           {.meaning = "k_n, T = k_n ω² with ω in rpm [N/rpm²]", .max = 1e-3, .positive = true, .required = true});
  // The physics step must be at most half the faster constant (sim.physics_rate_hz).
  a->Visit("motor_time_constant_s", &motor_time_constant_s,
           {.meaning = "σ of eq. (6) [s]", .max = 2, .positive = true, .required = true});
  a->Visit("motor_stop_time_constant_s", &motor_stop_time_constant_s,
           {.meaning = "how fast a stopped motor's speed decays [s]", .max = 10, .positive = true, .required = true});
  a->Visit(
      "unloaded_rpm_ratio", &unloaded_speed_ratio,
      {.meaning = "speed of a motor without its propeller relative to loaded", .min = 1, .max = 3, .required = true});
  a->Visit(
      "collision_radius_m", &collision_radius_m,
      {.meaning = "the sphere used for collisions [m]", .max = kMaxBodyOffsetM, .positive = true, .required = true});
  a->Visit(
      "pwm_gain_n", &pwm_gain_n,
      {.meaning = "K of paper 004, eq. (2): thrust per unit PWM input [N], for controller lqr and planner flatness "
                  "(0: none)",
       .min = 0,
       .max = 1e4,
       .default_text = "none"});
  a->Visit("collision_spheres", &collision_spheres,
           {.meaning = "the body's shape when it is not one sphere, each within collision_radius_m of the centre of "
                       "gravity (an assembly writes one per unit)",
            .min = 1});
  a->Visit("rotors", &rotors, {.meaning = "the rotors, 1 to 64", .min = 1, .required = true});
  a->Visit("landing_gear_m", &landing_gear_B,
           {.meaning = "the feet it stands on, relative to the centre of gravity, body frame [m], each below it",
            .min = -kMaxBodyOffsetM,
            .max = kMaxBodyOffsetM,
            .default_text = "one foot below each rotor hub, a quarter of collision_radius_m below the centre of gravity"});
  a->Visit("propeller_radius_m", &propeller_radius_m,
           {.meaning = "the propellers' radius [m]: the scale of the ground effect (simulated vehicles)",
            .min = 0,
            .max = kMaxBodyOffsetM,
            .default_text = "half the smallest distance between two hubs (propellers that do not overlap)"});
}

}  // namespace rotorguard::vehicle
