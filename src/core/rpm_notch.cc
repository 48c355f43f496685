#include "rotorguard/core/rpm_notch.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard {

void RpmNotchOptions::Validate() const {
  CheckDeclaredRanges("RpmNotchOptions", *this);
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    ThrowValidation("RpmNotchOptions", "sample_rate_hz", sample_rate_hz, "a rate > 0 [Hz]");
  }
}

double AliasedFrequency(double f, double fs) { return std::abs(f - fs * std::round(f / fs)); }

template <int N>
RpmNotchBank<N>::RpmNotchBank(int num_rotors, const RpmNotchOptions& options)
    : options_((options.Validate(), options)), num_rotors_(num_rotors) {
  if (num_rotors < 1 || num_rotors > kMaxRotors) {
    ThrowInvalidArgument("RpmNotchBank", "num_rotors", num_rotors, fmt::format("a count in [1, {}]", kMaxRotors));
  }
  notches_.resize(static_cast<std::size_t>(num_rotors * options_.harmonics));
  centres_.reserve(notches_.size());
  speed_rad_s_ = RotorVector::Zero(num_rotors);
}

template <int N>
void RpmNotchBank<N>::OnRotorSpeeds(TimeNs t, const RotorVector& speed_rad_s) {
  if (!options_.enabled || speed_rad_s.size() != num_rotors_ || !speed_rad_s.allFinite()) return;
  if (!last_ns_) {
    speed_rad_s_ = speed_rad_s;
  } else if (t > *last_ns_) {
    const double blend = 1.0 - std::exp(-ToSeconds(t - *last_ns_) / options_.speed_time_constant_s);
    speed_rad_s_ += blend * (speed_rad_s - speed_rad_s_);
  } else {
    return;  // late or repeated: the speeds stay
  }
  last_ns_ = t;
  const double fs = options_.sample_rate_hz;
  // Within a width of Nyquist a notch's poles close on the unit circle (the RBJ design's damping
  // sin(w0) B / 2 f0 vanishes at w0 = pi): left alone there too.
  const double highest = 0.5 * fs - options_.bandwidth_hz;
  centres_.clear();
  for (int i = 0; i < num_rotors_; ++i) {
    const double rotor_hz = speed_rad_s_[i] / (2.0 * std::numbers::pi);
    for (int h = 1; h <= options_.harmonics; ++h) {
      const double f = AliasedFrequency(h * rotor_hz, fs);
      if (std::isfinite(f) && f > 0.0 && f >= options_.min_frequency_hz && f <= highest) centres_.push_back(f);
    }
  }
  // One notch per group of frequencies within half a width of the group's lowest, at their mean:
  // rotors that turn alike (a hover; the rotors of an assembly) share one, and every notch costs
  // phase at the control's frequencies.
  std::sort(centres_.begin(), centres_.end());
  std::size_t slot = 0;
  for (std::size_t k = 0; k < centres_.size();) {
    std::size_t end = k;
    double sum = 0.0;
    while (end < centres_.size() && centres_[end] - centres_[k] <= 0.5 * options_.bandwidth_hz) sum += centres_[end++];
    notches_[slot++].SetCentre(sum / static_cast<double>(end - k), options_.bandwidth_hz, fs);
    k = end;
  }
  for (; slot < notches_.size(); ++slot) notches_[slot].Bypass();
}

template <int N>
typename RpmNotchBank<N>::Vec RpmNotchBank<N>::Filter(const Vec& x) {
  if (!options_.enabled || !x.allFinite()) return x;  // a non-finite sample leaves the memory clean
  Vec y = x;
  for (Notch2<N>& notch : notches_) y = notch.Step(y);
  return y;
}

template class RpmNotchBank<4>;
template class RpmNotchBank<6>;

}  // namespace rotorguard
