#include "rotorguard/sim/ground_effect.h"

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::sim {

void GroundEffectOptions::Validate() const { CheckDeclaredRanges("GroundEffectOptions", *this); }

GroundEffect::GroundEffect(const vehicle::MultirotorModel& model, const GroundEffectOptions& options,
                           const GroundPlane& ground)
    : model_(model),
      options_(options),
      ground_(ground),
      radius_m_(model.params().PropellerRadius()),
      max_image_term_(1.0 - 1.0 / options.max_ratio) {
  options_.Validate();
}

double GroundEffect::Ratio(double height_m) const {
  if (options_.strength <= 0.0) return 1.0;
  if (!(height_m > 0.0)) return options_.max_ratio;
  const double r = radius_m_ / (4.0 * height_m);
  return 1.0 / (1.0 - std::min(options_.strength * r * r, max_image_term_));
}

void GroundEffect::AddTo(const vehicle::StateVector& x, const vehicle::RotorFaults& faults,
                         vehicle::Disturbance* d) const {
  if (options_.strength <= 0.0) return;
  const vehicle::StateView s(x);
  const Matrix3 R = s.q_WB().toRotationMatrix();
  // A rotor whose axis points away from the ground blows no wake onto it.
  const Vector3& n = ground_.normal_W;
  if (n.dot(R.col(2)) <= 0.0) return;
  RotorVector thrust;
  model_.RotorThrusts(x, faults, &thrust);
  const std::vector<vehicle::Rotor>& rotors = model_.params().rotors;
  double added_total = 0.0;
  Vector3 torque_B = Vector3::Zero();
  for (int i = 0; i < model_.num_rotors(); ++i) {
    const Vector3& hub_B = rotors[static_cast<std::size_t>(i)].p_B;
    const double height = n.dot(s.p_W() + R * hub_B) - ground_.offset_m;
    const double added = (Ratio(height) - 1.0) * thrust[i];
    added_total += added;
    torque_B += hub_B.cross(Vector3(0.0, 0.0, added));
  }
  d->force_W += added_total * R.col(2);
  d->torque_B += torque_B;
}

}  // namespace rotorguard::sim
