#pragma once
/// Flight metrics as defined in DESIGN.md ("Metrics"), accumulated sample by sample.
#include <limits>
#include <string>
#include <vector>

#include "rotorguard/core/types.h"
#include "rotorguard/fdd/composite_fdd.h"
#include "rotorguard/sim/fault_injector.h"

namespace rotorguard::harness {

/// Tracking error over [t1, t2]: RMSE = sqrt( (1/(t2-t1)) * integral |p - p_ref|^2 dt ), and
/// paper 000's eq. (37), which divides outside the root: sqrt( integral |p - p_ref|^2 dt ) / (t2-t1).
/// Integrated with the rectangle rule at the sampling step.
class TrackingErrorAccumulator {
 public:
  void Add(double dt, const Vector3& p, const Vector3& p_ref);
  double rmse() const;
  double rmse_eq37() const;
  double max_error() const { return max_error_; }
  double duration() const { return duration_; }

 private:
  double integral_ = 0.0;
  double duration_ = 0.0;
  double max_error_ = 0.0;
};

/// What fault detection concluded, scored against the injected faults (DESIGN.md, Metrics).
struct FddRecord {
  bool detected = false;      ///< some rotor left the ok state
  int rotor = -1;             ///< the first rotor diagnosed
  std::string kind;           ///< motor_failed, propeller_failed or degraded
  std::string detector;       ///< motor_index, thrust_loss_observer or takeoff
  double detection_s = 0.0;
  bool correct = false;       ///< right rotor and kind, at or after the first onset
  bool false_alarm = false;   ///< a diagnosis without a fault, or before the first onset
  double latency_s = -1.0;    ///< detection - onset when correct, else negative
};

/// Whether a diagnosis names the injected fault kind (stuck: any diagnosis of the rotor).
bool KindMatches(vehicle::FaultKind truth, fdd::RotorHealth diagnosis);

/// Scores the detector's per-rotor statuses against the injected fault events: the earliest
/// diagnosis counts; it is a false alarm without a fault or before the first onset, and correct
/// when it names the first fault's rotor and kind.
FddRecord ScoreFdd(const std::vector<fdd::RotorStatus>& rotors, const std::vector<sim::FaultEvent>& events);

}  // namespace rotorguard::harness
