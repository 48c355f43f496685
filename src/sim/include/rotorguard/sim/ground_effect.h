#pragma once
/// The ground effect: a rotor close to the ground makes more thrust at the same speed, its wake
/// slowed by the ground (Cheeseman and Bennett, "The effect of the ground on a helicopter rotor in
/// forward flight", ARC R&M 3021, 1957, from the method of images):
///
///     T / T_inf = 1 / (1 - s (R / (4 z))^2),
///
/// R the propeller's radius, z the hub's height above the ground. The effect is about 7 % at z = R
/// and 1.6 % at z = 2 R, and a few parts in ten thousand at a metre for a 5-inch propeller; it is
/// applied at every height, per rotor, along the rotor's axis at its hub (so a tilted vehicle near
/// the ground feels a moment righting it). s scales the formula: measured multirotors depart from
/// the single rotor's image solution both ways (the fountain between rotors adds lift, a body
/// under the rotors blocks the wake), which `realistic` draws (docs/truth.md). Near the ground the
/// formula diverges (z -> R/4 sqrt(s)); the ratio is bounded by `max_ratio`, continuously.
///
/// Only the thrust changes: the motors' speeds and reaction torques are those out of ground effect
/// (a rotor in ground effect needs slightly less torque for its thrust; neglected).
#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"
#include "rotorguard/sim/contact.h"
#include "rotorguard/vehicle/faults.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::sim {

/// The strongest ground effect a scenario or a draw may give (four times the image solution's).
inline constexpr double kMaxGroundEffectStrength = 4.0;

struct GroundEffectOptions {
  /// s of the formula; 0: no ground effect. Off by default for now: with it on (s = 1), flights
  /// that take off change by the few percent of thrust near the ground, and three of the closed-
  /// loop tests' fixed seeds land on known weaknesses (a moving obstacle grazed in the indoor
  /// scenario, a second failure's isolation 0.27 s after onset); those are to be fixed before the
  /// effect becomes the default.
  double strength = 0.0;
  /// The largest T / T_inf, reached at the ground.
  double max_ratio = 1.5;
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("strength", &strength,
             {.meaning = "s of T/T∞ = 1/(1 − s (R/4z)²), per rotor (Cheeseman-Bennett: 1; 0: none, the default for now)", .min = 0.0, .max = kMaxGroundEffectStrength});
    a->Visit("max_ratio", &max_ratio, {.meaning = "the largest T/T∞, near the ground", .min = 1.0, .max = 3.0});
  }
};

class GroundEffect {
 public:
  /// `model`: its rotors (positions about the centre of gravity, thrusts) and its vehicle's
  /// propeller radius; `ground`: the plane the contact stands on (heights along its normal). The
  /// model must outlive this object.
  GroundEffect(const vehicle::MultirotorModel& model, const GroundEffectOptions& options, const GroundPlane& ground);

  /// T / T_inf for a hub at `height_m` above the ground (1 for a rotor at or above no ground).
  double Ratio(double height_m) const;
  /// Adds the thrust the ground adds to the rotors at x (force world frame, torque body frame).
  void AddTo(const vehicle::StateVector& x, const vehicle::RotorFaults& faults, vehicle::Disturbance* d) const;

  double propeller_radius_m() const { return radius_m_; }

 private:
  const vehicle::MultirotorModel& model_;
  GroundEffectOptions options_;
  GroundPlane ground_;
  double radius_m_ = 0.0;
  double max_image_term_ = 0.0;  // s (R/4z)^2 at which the ratio reaches max_ratio
};

}  // namespace rotorguard::sim
