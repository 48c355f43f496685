#include "rotorguard/core/statistics.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rotorguard {

double Percentile(std::vector<double> v, double p) {
  if (!(p >= 0.0 && p <= 1.0)) {
    throw std::invalid_argument(
        fmt::format("Percentile: p = {} is invalid; expected a fraction in [0, 1] (0.99 for the 99th percentile)", p));
  }
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double position = p * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(position));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (position - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

double Mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (const double v : values) sum += v;
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

}  // namespace rotorguard
