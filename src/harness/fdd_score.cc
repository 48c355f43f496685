#include "rotorguard/harness/fdd_score.h"

namespace rotorguard::harness {

bool KindMatches(vehicle::FaultKind truth, fdd::RotorHealth diagnosis) {
  switch (truth) {
    // kFailed: a method that cannot tell the motor from the propeller isolates either correctly.
    case vehicle::FaultKind::kMotorStop:
      return diagnosis == fdd::RotorHealth::kMotorFailed || diagnosis == fdd::RotorHealth::kFailed;
    case vehicle::FaultKind::kPropellerLoss:
      return diagnosis == fdd::RotorHealth::kPropellerFailed || diagnosis == fdd::RotorHealth::kFailed;
    case vehicle::FaultKind::kLossOfEffectiveness:
      return diagnosis == fdd::RotorHealth::kDegraded;
    case vehicle::FaultKind::kStuck:
      return diagnosis != fdd::RotorHealth::kOk;
    case vehicle::FaultKind::kNone:
      return false;
  }
  return false;
}

FddRecord ScoreFdd(const std::vector<fdd::RotorStatus>& rotors, const std::vector<sim::FaultEvent>& events) {
  FddRecord r;
  for (int i = 0; i < static_cast<int>(rotors.size()); ++i) {
    const fdd::RotorStatus& status = rotors[static_cast<std::size_t>(i)];
    if (!status.detected_s) continue;
    if (!r.diagnosis || *status.detected_s < r.diagnosis->detection_s) {
      r.diagnosis = FddRecord::Diagnosis{i, std::string(fdd::ToString(status.health)), status.detector,
                                         *status.detected_s, status.eta};
    }
  }
  if (!r.diagnosis) return r;
  if (events.empty() || r.diagnosis->detection_s < events.front().onset_s) {
    r.false_alarm = true;
    return r;
  }
  const sim::FaultEvent& first = events.front();
  r.correct = r.diagnosis->rotor == first.rotor &&
              KindMatches(first.kind, rotors[static_cast<std::size_t>(r.diagnosis->rotor)].health);
  if (r.correct) r.latency_s = r.diagnosis->detection_s - first.onset_s;
  return r;
}

void AddReconfigurationLatency(const std::vector<stack::RotorReconfiguration>& reconfigurations,
                               const std::vector<sim::FaultEvent>& events, FddRecord* record) {
  record->reconfiguration_latency_s.reset();
  if (!record->correct || events.empty()) return;
  for (const stack::RotorReconfiguration& c : reconfigurations) {
    if (c.rotor == record->diagnosis->rotor) {
      record->reconfiguration_latency_s = c.t_s - events.front().onset_s;
      return;
    }
  }
}

}  // namespace rotorguard::harness
