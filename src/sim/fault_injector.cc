#include "rotorguard/sim/fault_injector.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <limits>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/error.h"

namespace rotorguard::sim {

void FaultSpec::Validate(int index, int num_rotors, double duration_s) const {
  const std::string prefix = fmt::format("faults.{}.", index);
  if (rotor < 0 || rotor >= num_rotors) {
    ThrowValidation("FaultSpec", prefix + "rotor", rotor,
                    fmt::format("a rotor index in [0, {}] (the vehicle has {} rotors)",
                                num_rotors - 1, num_rotors));
  }
  if (kind == vehicle::FaultKind::kNone) {
    ThrowValidation("FaultSpec", prefix + "kind", "none", fmt::format("one of {}", fmt::join(NameList<vehicle::FaultKind>(), ", ")));
  }
  if (kind == vehicle::FaultKind::kLossOfEffectiveness && (!std::isfinite(eta) || eta < 0.0 || eta >= 1.0)) {
    ThrowValidation("FaultSpec", prefix + "eta", eta, "a value in [0, 1)");
  }
  const std::string onset_prefix = prefix + "onset.";
  switch (onset.kind) {
    case FaultOnset::Kind::kAtTime:
      if (!std::isfinite(onset.value) || onset.value < 0.0 || onset.value >= duration_s) {
        ThrowValidation("FaultSpec", onset_prefix + "at_time_s", onset.value,
                        fmt::format("a time in [0, {}) s (the scenario's duration_s)", duration_s));
      }
      break;
    case FaultOnset::Kind::kAtAltitude:
      if (!std::isfinite(onset.value) || onset.value <= 0.0 || onset.value > kMaxCoordinateM) {
        ThrowValidation("FaultSpec", onset_prefix + "at_altitude_m", onset.value,
                        fmt::format("an altitude in (0, {:g}] m", kMaxCoordinateM));
      }
      break;
    case FaultOnset::Kind::kDuringTakeoff:
      if (!std::isfinite(onset.value) || onset.value < 0.0 || onset.value >= duration_s) {
        ThrowValidation("FaultSpec", onset_prefix + "during_takeoff_s", onset.value,
                        fmt::format("a delay after lift-off in [0, {}) s", duration_s));
      }
      break;
  }
  if (intermittent) {
    const std::string period = fmt::format("a period in (0, {:g}] s", kMaxFlightS);
    if (!std::isfinite(intermittent->on_s) || intermittent->on_s <= 0.0 || intermittent->on_s > kMaxFlightS) {
      ThrowValidation("FaultSpec", prefix + "intermittent.on_s", intermittent->on_s, period);
    }
    if (!std::isfinite(intermittent->off_s) || intermittent->off_s <= 0.0 || intermittent->off_s > kMaxFlightS) {
      ThrowValidation("FaultSpec", prefix + "intermittent.off_s", intermittent->off_s, period);
    }
  }
}

FaultInjector::FaultInjector(std::vector<FaultSpec> specs, int num_rotors)
    : specs_(std::move(specs)), onset_ns_(specs_.size()) {
  for (std::size_t i = 0; i < specs_.size(); ++i) {
    specs_[i].Validate(static_cast<int>(i), num_rotors, std::numeric_limits<double>::infinity());
  }
}

void FaultInjector::Update(TimeNs t, double altitude_m, bool airborne, vehicle::RotorFaults* faults) {
  // Lift-off is a landed -> airborne transition: a vehicle that starts in the air never lifts off.
  if (airborne && previous_airborne_ && !*previous_airborne_ && !liftoff_ns_) liftoff_ns_ = t;
  previous_airborne_ = airborne;
  // An altitude onset fires when the vehicle climbs through it, not when it starts above it.
  const double previous_altitude = previous_altitude_.value_or(altitude_m);
  previous_altitude_ = altitude_m;
  for (auto& f : *faults) f = vehicle::RotorFaultState{};
  // Later specs override earlier ones on the same rotor.
  for (std::size_t i = 0; i < specs_.size(); ++i) {
    const FaultSpec& spec = specs_[i];
    if (!onset_ns_[i]) {
      bool triggered = false;
      switch (spec.onset.kind) {
        case FaultOnset::Kind::kAtTime:
          triggered = t >= FromSeconds(spec.onset.value);
          break;
        case FaultOnset::Kind::kAtAltitude:
          triggered = previous_altitude < spec.onset.value && altitude_m >= spec.onset.value;
          break;
        case FaultOnset::Kind::kDuringTakeoff:
          triggered = liftoff_ns_ && t >= *liftoff_ns_ + FromSeconds(spec.onset.value);
          break;
      }
      if (!triggered) continue;
      onset_ns_[i] = t;
      events_.push_back({spec.rotor, spec.kind, ToSeconds(t)});
    }
    bool active = true;
    if (spec.intermittent) {
      const TimeNs on = FromSeconds(spec.intermittent->on_s);
      const TimeNs cycle = on + FromSeconds(spec.intermittent->off_s);
      active = (t - *onset_ns_[i]) % cycle < on;
    }
    if (active) (*faults)[spec.rotor] = {spec.kind, spec.eta};
  }
}

}  // namespace rotorguard::sim
