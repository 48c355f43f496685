#include "rotorguard/core/filters.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"

namespace rotorguard {

template <int N>
LowPass2<N>::LowPass2(double cutoff_hz, double sample_hz) {
  if (!(cutoff_hz > 0.0) || !(sample_hz > 2.0 * cutoff_hz) || !std::isfinite(sample_hz)) {
    ThrowInvalidArgument("LowPass2", "cutoff_hz", cutoff_hz, fmt::format("a cut-off in (0, {}) Hz (below Nyquist)", sample_hz / 2));
  }
  // Bilinear transform of w^2 / (s^2 + sqrt(2) w s + w^2) with pre-warped w.
  const double k = std::tan(std::numbers::pi * cutoff_hz / sample_hz);
  const double norm = 1.0 / (1.0 + std::sqrt(2.0) * k + k * k);
  b0_ = k * k * norm;
  b1_ = 2.0 * b0_;
  b2_ = b0_;
  a1_ = 2.0 * (k * k - 1.0) * norm;
  a2_ = (1.0 - std::sqrt(2.0) * k + k * k) * norm;
  delay_s_ = std::sqrt(2.0) / (2.0 * std::numbers::pi * cutoff_hz);
}

template <int N>
void LowPass2<N>::Reset(const Vec& x) {
  x1_ = x2_ = y1_ = y2_ = y_ = x;
  initialised_ = true;
}

template <int N>
const typename LowPass2<N>::Vec& LowPass2<N>::Step(const Vec& x) {
  if (!initialised_) Reset(x);
  y_ = b0_ * x + b1_ * x1_ + b2_ * x2_ - a1_ * y1_ - a2_ * y2_;
  x2_ = x1_;
  x1_ = x;
  y2_ = y1_;
  y1_ = y_;
  return y_;
}

template <int N>
FilteredDerivative<N>::FilteredDerivative(double cutoff_hz, double sample_hz) : filter_(cutoff_hz, sample_hz) {}

template <int N>
void FilteredDerivative<N>::Reset(const Vec& x) {
  previous_ = x;
  filter_.Reset(Vec::Zero());
  initialised_ = true;
}

template <int N>
const typename FilteredDerivative<N>::Vec& FilteredDerivative<N>::Step(const Vec& x, double dt) {
  if (!initialised_) Reset(x);
  const Vec derivative = dt > 0.0 ? Vec((x - previous_) / dt) : Vec(Vec::Zero());
  previous_ = x;
  return filter_.Step(derivative);
}

template <int N>
void Notch2<N>::SetCentre(double centre_hz, double bandwidth_hz, double sample_hz) {
  if (!(sample_hz > 0.0) || !std::isfinite(sample_hz)) {
    ThrowInvalidArgument("Notch2", "sample_hz", sample_hz, "a rate > 0 [Hz]");
  }
  if (!(centre_hz > 0.0) || !(centre_hz < 0.5 * sample_hz)) {
    ThrowInvalidArgument("Notch2", "centre_hz", centre_hz, fmt::format("a centre in (0, {}) Hz (below Nyquist)", sample_hz / 2));
  }
  if (!(bandwidth_hz > 0.0) || !std::isfinite(bandwidth_hz)) {
    ThrowInvalidArgument("Notch2", "bandwidth_hz", bandwidth_hz, "a width > 0 [Hz]");
  }
  // Orfanidis' second-order notch (Introduction to Signal Processing, sec. 11.3): zeros on the unit
  // circle at w0 = 2 pi f0 / fs, poles on their rays at radius sqrt(2 beta - 1), beta =
  // 1 / (1 + tan(dw / 2)) with dw = 2 pi B / fs: the -3 dB points lie exactly dw apart in the
  // digital domain (the RBJ cookbook's Q gives the analogue width, which the bilinear transform
  // narrows near Nyquist).
  const double w0 = 2.0 * std::numbers::pi * centre_hz / sample_hz;
  const double dw = std::min(2.0 * std::numbers::pi * bandwidth_hz / sample_hz, 0.99 * std::numbers::pi);
  const double beta = 1.0 / (1.0 + std::tan(0.5 * dw)), c = std::cos(w0);
  b0_ = beta;
  b1_ = -2.0 * beta * c;
  b2_ = beta;
  a1_ = -2.0 * beta * c;
  a2_ = 2.0 * beta - 1.0;
  bypassed_ = false;
}

template <int N>
const typename Notch2<N>::Vec& Notch2<N>::Step(const Vec& x) {
  if (!initialised_) {  // as if x had always been the input: no start-up transient
    x1_ = x2_ = y1_ = y2_ = x;
    initialised_ = true;
  }
  y_ = bypassed_ ? x : Vec(b0_ * x + b1_ * x1_ + b2_ * x2_ - a1_ * y1_ - a2_ * y2_);
  x2_ = x1_;
  x1_ = x;
  y2_ = y1_;
  y1_ = y_;
  return y_;
}

template class Notch2<4>;
template class Notch2<6>;
template class LowPass2<1>;
template class LowPass2<3>;
template class LowPass2<4>;
template class FilteredDerivative<3>;

}  // namespace rotorguard
