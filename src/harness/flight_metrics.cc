#include "rotorguard/harness/flight_metrics.h"

#include <algorithm>
#include <cmath>

namespace rotorguard::harness {

void TrackingErrorAccumulator::Add(double dt, const Vector3& p, const Vector3& p_ref) {
  const double e2 = (p - p_ref).squaredNorm();
  integral_ += e2 * dt;
  duration_ += dt;
  max_error_ = std::max(max_error_, std::sqrt(e2));
}

double TrackingErrorAccumulator::rmse() const {
  return duration_ > 0.0 ? std::sqrt(integral_ / duration_) : 0.0;
}

double TrackingErrorAccumulator::rmse_eq37() const {
  return duration_ > 0.0 ? std::sqrt(integral_) / duration_ : 0.0;
}

bool KindMatches(vehicle::FaultKind truth, fdd::RotorHealth diagnosis) {
  switch (truth) {
    // kFailed: a method that cannot tell the motor from the propeller isolates either correctly.
    case vehicle::FaultKind::kMotorStop:
      return diagnosis == fdd::RotorHealth::kMotorFailed || diagnosis == fdd::RotorHealth::kFailed;
    case vehicle::FaultKind::kPropellerLoss:
      return diagnosis == fdd::RotorHealth::kPropellerFailed || diagnosis == fdd::RotorHealth::kFailed;
    case vehicle::FaultKind::kLossOfEffectiveness: return diagnosis == fdd::RotorHealth::kDegraded;
    case vehicle::FaultKind::kStuck: return diagnosis != fdd::RotorHealth::kOk;
    case vehicle::FaultKind::kNone: return false;
  }
  return false;
}

FddRecord ScoreFdd(const std::vector<fdd::RotorStatus>& rotors, const std::vector<sim::FaultEvent>& events) {
  FddRecord r;
  for (int i = 0; i < static_cast<int>(rotors.size()); ++i) {
    if (!rotors[i].detected_s) continue;
    if (!r.detected || *rotors[i].detected_s < r.detection_s) {
      r.detected = true;
      r.rotor = i;
      r.detection_s = *rotors[i].detected_s;
      r.kind = std::string(fdd::ToString(rotors[i].health));
      r.detector = rotors[i].detector;
    }
  }
  if (!r.detected) return r;
  if (events.empty() || r.detection_s < events.front().onset_s) {
    r.false_alarm = true;
    return r;
  }
  const sim::FaultEvent& first = events.front();
  r.correct = r.rotor == first.rotor && KindMatches(first.kind, rotors[r.rotor].health);
  if (r.correct) r.latency_s = r.detection_s - first.onset_s;
  return r;
}

}  // namespace rotorguard::harness
