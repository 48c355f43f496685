#include "rotorguard/harness/fdd_score.h"

#include <algorithm>

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

namespace {

std::optional<FddRecord::Second> ScoreSecond(const std::vector<fdd::RotorStatus>& rotors,
                                             const std::vector<sim::FaultEvent>& events) {
  if (events.empty()) return std::nullopt;
  const auto other = std::find_if(events.begin(), events.end(),
                                  [&events](const sim::FaultEvent& e) { return e.rotor != events.front().rotor; });
  if (other == events.end() || other->rotor < 0 || other->rotor >= static_cast<int>(rotors.size())) return std::nullopt;
  const fdd::RotorStatus& status = rotors[static_cast<std::size_t>(other->rotor)];
  FddRecord::Second second;
  second.diagnosis = {other->rotor, std::string(fdd::ToString(status.health)), status.detector,
                      status.detected_s.value_or(0.0), status.eta};
  second.isolated = fdd::IsIsolated(status.health);
  second.correct = second.isolated && status.detected_s && *status.detected_s >= other->onset_s &&
                   KindMatches(other->kind, status.health);
  if (second.correct) second.latency_s = *status.detected_s - other->onset_s;
  return second;
}

}  // namespace

FddRecord ScoreFdd(const std::vector<fdd::RotorStatus>& rotors, const std::vector<sim::FaultEvent>& events) {
  FddRecord r;
  r.second = ScoreSecond(rotors, events);
  for (int i = 0; i < static_cast<int>(rotors.size()); ++i) {
    const bool faulty = std::any_of(events.begin(), events.end(), [i](const sim::FaultEvent& e) { return e.rotor == i; });
    if (!faulty && fdd::IsIsolated(rotors[static_cast<std::size_t>(i)].health)) ++r.healthy_rotors_isolated;
  }
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
