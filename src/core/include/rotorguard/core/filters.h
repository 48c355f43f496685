#pragma once
/// Discrete filters for estimation (fault detection, INDI): a second-order Butterworth low-pass (bilinear transform
/// with frequency pre-warping) applied per channel, and a filtered differentiator. Both take their
/// sample time at construction (their design depends on it) and allocate nothing when stepping.
#include <Eigen/Core>

namespace rotorguard {

/// y = H(z) x per channel with H a second-order Butterworth low-pass of cut-off `cutoff_hz` at
/// `sample_hz`. Unit DC gain; group delay at low frequency sqrt(2) / (2 pi fc) seconds.
template <int N>
class LowPass2 {
 public:
  using Vec = Eigen::Matrix<double, N, 1>;
  LowPass2() = default;
  LowPass2(double cutoff_hz, double sample_hz);
  /// Starts the filter in steady state at `x` (no transient).
  void Reset(const Vec& x);
  const Vec& Step(const Vec& x);
  const Vec& value() const { return y_; }
  /// Low-frequency group delay [s].
  double delay_s() const { return delay_s_; }

 private:
  double b0_ = 1.0, b1_ = 0.0, b2_ = 0.0, a1_ = 0.0, a2_ = 0.0;
  double delay_s_ = 0.0;
  Vec x1_ = Vec::Zero(), x2_ = Vec::Zero(), y1_ = Vec::Zero(), y2_ = Vec::Zero(), y_ = Vec::Zero();
  bool initialised_ = false;
};

/// y = H(z) x per channel with H a second-order notch (Orfanidis' design): zero gain at the
/// centre, -3 dB exactly `bandwidth` apart, unit gain far from it. The centre can move every sample
/// (an RPM-tracking notch, whose rotor speeds change); Bypass passes x unchanged, the filter's
/// memory following, so that a notch switched on later starts without a transient.
template <int N>
class Notch2 {
 public:
  using Vec = Eigen::Matrix<double, N, 1>;
  /// Centre and -3 dB width [Hz] at `sample_hz`: the centre in (0, sample_hz / 2), the width > 0.
  /// Throws std::invalid_argument (a real-time caller checks beforehand: Bypass where it would).
  void SetCentre(double centre_hz, double bandwidth_hz, double sample_hz);
  void Bypass() { bypassed_ = true; }
  bool bypassed() const { return bypassed_; }
  const Vec& Step(const Vec& x);

 private:
  double b0_ = 1.0, b1_ = 0.0, b2_ = 1.0, a1_ = 0.0, a2_ = 0.0;
  Vec x1_ = Vec::Zero(), x2_ = Vec::Zero(), y1_ = Vec::Zero(), y2_ = Vec::Zero(), y_ = Vec::Zero();
  bool bypassed_ = true, initialised_ = false;
};

/// The derivative of a signal, low-pass filtered: y = LowPass2(dx/dt) with dx/dt by backward
/// differences over the actual time between samples.
template <int N>
class FilteredDerivative {
 public:
  using Vec = Eigen::Matrix<double, N, 1>;
  FilteredDerivative() = default;
  FilteredDerivative(double cutoff_hz, double sample_hz);
  void Reset(const Vec& x);
  /// `dt` is the time since the previous sample [s] (> 0; samples may be irregular).
  const Vec& Step(const Vec& x, double dt);
  const Vec& value() const { return filter_.value(); }

 private:
  LowPass2<N> filter_;
  Vec previous_ = Vec::Zero();
  bool initialised_ = false;
};

}  // namespace rotorguard
