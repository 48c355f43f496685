#include "rotorguard/sim/parachute.h"

#include <algorithm>

#include "rotorguard/core/key_ranges.h"

namespace rotorguard::sim {

void ParachuteOptions::Validate() const { CheckDeclaredRanges("ParachuteOptions", *this); }

Parachute::Parachute(const ParachuteOptions& options) : options_(options) { options_.Validate(); }

void Parachute::Release(TimeNs t_ns) {
  if (!released_ns_) released_ns_ = t_ns;
}

double Parachute::DragAreaAt(TimeNs t_ns) const {
  if (!options_.fitted || !released_ns_) return 0.0;
  const double tau = ToSeconds(t_ns - *released_ns_) - options_.ejection_delay_s;
  if (tau < 0.0) return 0.0;
  if (tau >= options_.inflation_time_s) return options_.drag_area_m2;
  const double filled = tau / options_.inflation_time_s;
  return options_.drag_area_m2 * filled * filled;
}

void Parachute::Update(TimeNs t_ns) { drag_area_m2_ = DragAreaAt(t_ns); }

void Parachute::AddTo(const vehicle::StateVector& x, vehicle::Disturbance* d) const {
  if (drag_area_m2_ <= 0.0) return;
  const Vector3 airspeed = vehicle::StateView(x).v_W() - d->wind_W;
  d->force_W -= 0.5 * options_.air_density_kg_m3 * drag_area_m2_ * airspeed.norm() * airspeed;
}

}  // namespace rotorguard::sim
