#include "rotorguard/sim/wind.h"

#include <cmath>

#include "rotorguard/core/key_ranges.h"

namespace rotorguard::sim {

void WindOptions::Validate() const { CheckDeclaredRanges("WindOptions", *this); }

WindModel::WindModel(const WindOptions& options, std::uint64_t seed) : options_(options), rng_(seed) {
  // Start the gust process in its stationary distribution.
  for (int i = 0; i < 3; ++i) gust_[i] = options_.gust_std_m_s * rng_.Normal();
  velocity_ = options_.mean_m_s + gust_;
}

const Vector3& WindModel::Step(double dt) {
  if (options_.gust_std_m_s > 0.0) {
    // Exact discretisation of dg = -g/tau dt + sigma*sqrt(2/tau) dW.
    const double phi = std::exp(-dt / options_.gust_time_constant_s);
    const double q = options_.gust_std_m_s * std::sqrt(1.0 - phi * phi);
    for (int i = 0; i < 3; ++i) gust_[i] = phi * gust_[i] + q * rng_.Normal();
  }
  velocity_ = options_.mean_m_s + gust_;
  return velocity_;
}

}  // namespace rotorguard::sim
