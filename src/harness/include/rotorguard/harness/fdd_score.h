#pragma once
/// Fault detection scored against the faults that were injected (docs/metrics.md, "Fault
/// detection"): the run summary's `fdd` and the offline calibration's score.
#include <optional>
#include <string>
#include <vector>

#include "rotorguard/fdd/composite_fdd.h"  // RotorStatus, RotorHealth
#include "rotorguard/sim/fault_injector.h"
#include "rotorguard/stack/flight_stack.h"

namespace rotorguard::harness {

/// What fault detection concluded.
struct FddRecord {
  /// The earliest diagnosis: of which rotor, what (motor_failed, propeller_failed, degraded,
  /// failed), by which detector (motor_index, thrust_loss_observer, takeoff, ...), when [s].
  struct Diagnosis {
    int rotor = 0;
    std::string kind;
    std::string detector;
    double detection_s = 0.0;
    double eta = 0.0;  ///< the estimated loss of effectiveness at the end (degraded), else 1
  };
  std::optional<Diagnosis> diagnosis;  ///< none: no rotor left the ok state
  bool correct = false;                ///< right rotor and kind, at or after the first onset
  bool false_alarm = false;            ///< a diagnosis without a fault, or before the first onset
  std::optional<double> latency_s;     ///< detection - onset, when correct
  /// When correct: the first control cycle that flew without the diagnosed rotor - onset. It adds
  /// to latency_s the wait for the next control cycle (the telemetry's delay is in both).
  std::optional<double> reconfiguration_latency_s;
  /// The second failed rotor: the first fault event on another rotor than the first event's.
  struct Second {
    Diagnosis diagnosis;              ///< that rotor's ("ok", no detector, time 0: none)
    bool isolated = false;            ///< the detector took it out of the vehicle (any failure kind)
    bool correct = false;             ///< isolated with the injected kind, at or after the event's onset
    std::optional<double> latency_s;  ///< detection - onset, when correct
  };
  std::optional<Second> second;  ///< none: a single faulty rotor, or none at all
  /// Rotors isolated (motor, propeller or unclassified failure) on which no fault was injected:
  /// after a correct first isolation, a false second one.
  int healthy_rotors_isolated = 0;
  /// The composite detector's index extremes before the first fault's onset (over the whole flight
  /// without one, up to a first isolation): how far a healthy flight pushed its indices.
  std::optional<fdd::IndexExtremes> healthy_extremes;

  bool detected() const { return diagnosis.has_value(); }
};

/// Whether a diagnosis names the injected fault kind (stuck: any diagnosis of the rotor).
bool KindMatches(vehicle::FaultKind truth, fdd::RotorHealth diagnosis);

/// Scores the detector's per-rotor statuses against the injected fault events: the earliest
/// diagnosis counts; it is a false alarm without a fault or before the first onset, and correct
/// when it names the first fault's rotor and kind. A fault on a second rotor is scored on its own
/// (FddRecord::second).
FddRecord ScoreFdd(const std::vector<fdd::RotorStatus>& rotors, const std::vector<sim::FaultEvent>& events);

/// Sets `record`'s reconfiguration_latency_s from the stack's reconfigurations when the diagnosis
/// is correct and the controller was reconfigured for its rotor.
void AddReconfigurationLatency(const std::vector<stack::RotorReconfiguration>& reconfigurations,
                               const std::vector<sim::FaultEvent>& events, FddRecord* record);

}  // namespace rotorguard::harness
