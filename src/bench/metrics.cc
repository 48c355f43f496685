#include "rotorguard/bench/metrics.h"

#include <algorithm>
#include <cmath>

namespace rotorguard::bench {

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

}  // namespace rotorguard::bench
