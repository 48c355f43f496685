#pragma once
/// Notches that follow the rotors' speeds, at each rotor's frequency and its harmonics, where they
/// land after sampling (aliased into [0, f_s / 2]). A rotor's imbalance shakes the airframe at its
/// own frequency and the propeller's blades at multiples of it; on a 333 Hz IMU without an
/// anti-aliasing filter these land anywhere in its band. The flight controllers of the field
/// filter the same way (Betaflight's RPM filter, PX4's ESC-RPM dynamic notch, ArduPilot's
/// harmonic notch on ESC telemetry); docs/control.md, "Delay".
///
/// Every notch delays what it passes (at 20 Hz of width, 0.6 ms about a 74 Hz centre, more nearer
/// the band's foot): a signal compared with the notched IMU passes an identical bank fed the same
/// speeds, so that both carry the same delay (the composite FDD's wrench from telemetry).
#include <optional>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/filters.h"
#include "rotorguard/core/types.h"

namespace rotorguard {

struct RpmNotchOptions {
  bool enabled = true;
  /// Notches at 1x .. harmonics x each rotor's frequency, in [1, 8].
  int harmonics = 2;
  /// Each notch's -3 dB width [Hz], > 0: wide enough for the telemetry's speed error. An ESC's
  /// reported speed is good to a few per cent (its clock, its scaling): ±2 % of the second
  /// harmonic of a 250 Hz rotor is ±10 Hz.
  double bandwidth_hz = 20.0;
  /// A harmonic that aliases below this [Hz] is left alone: a notch there would cut the flight's
  /// own motion (and the vibration there is a slowly turning bias no filter separates).
  double min_frequency_hz = 20.0;
  /// The rotors' speeds are smoothed with this time constant before the notches follow them [s],
  /// > 0: a notch whose centre jumps with the telemetry's noise sample by sample is a time-varying
  /// filter, and one with its poles near the unit circle can then grow without bound.
  double speed_time_constant_s = 0.01;
  /// The rate of the samples filtered [Hz]: a hardware fact, set from the sensors (not a key).
  double sample_rate_hz = 333.0;
  /// Throws ValidationError naming the field.
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("enabled", &enabled, {.meaning = "notch the IMU at the rotors' frequencies from their telemetry"});
    a->Visit("harmonics", &harmonics, {.meaning = "notches at 1x .. this x each rotor's frequency", .min = 1, .max = 8});
    a->Visit("bandwidth_hz", &bandwidth_hz, {.meaning = "each notch's -3 dB width [Hz]", .max = 100.0, .positive = true});
    a->Visit("min_frequency_hz", &min_frequency_hz,
             {.meaning = "a harmonic aliased below this is not notched [Hz]", .min = 0.0, .max = 1000.0});
    a->Visit("speed_time_constant_s", &speed_time_constant_s,
             {.meaning = "the rotors' speeds are smoothed with this time constant [s]", .max = 1.0, .positive = true});
  }
};

/// The aliased frequency [Hz] of a frequency f [Hz] sampled at fs [Hz]: in [0, fs / 2].
double AliasedFrequency(double f, double fs);

/// N channels notched at the rotors' harmonics. Nothing is allocated after construction.
template <int N>
class RpmNotchBank {
 public:
  using Vec = Eigen::Matrix<double, N, 1>;
  /// Throws ValidationError for invalid options, std::invalid_argument for a rotor count outside
  /// [1, kMaxRotors].
  RpmNotchBank(int num_rotors, const RpmNotchOptions& options);
  /// The rotors' speeds [rad/s] measured at time t: the notches move to their frequencies.
  /// Non-finite, mis-sized, late or repeated measurements are ignored.
  void OnRotorSpeeds(TimeNs t, const RotorVector& speed_rad_s);
  /// One sample through the notches (unchanged before the first speeds, or when disabled).
  Vec Filter(const Vec& x);
  const RpmNotchOptions& options() const { return options_; }

 private:
  RpmNotchOptions options_;
  int num_rotors_;
  RotorVector speed_rad_s_;  // smoothed
  std::optional<TimeNs> last_ns_;
  std::vector<Notch2<N>> notches_;  // in ascending frequency; the unused ones bypassed
  std::vector<double> centres_;     // scratch: the harmonics' aliased frequencies (reserved once)
};

extern template class RpmNotchBank<4>;
extern template class RpmNotchBank<6>;

}  // namespace rotorguard
