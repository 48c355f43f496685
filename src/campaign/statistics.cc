#include "rotorguard/campaign/statistics.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rotorguard::campaign {

std::pair<double, double> WilsonInterval(int successes, int n) {
  if (n <= 0) return {0.0, 1.0};
  const double z = 1.959963984540054, p = static_cast<double>(successes) / n, z2 = z * z;
  const double denom = 1.0 + z2 / n;
  const double centre = (p + z2 / (2.0 * n)) / denom;
  const double half = z * std::sqrt(p * (1.0 - p) / n + z2 / (4.0 * n * n)) / denom;
  // At 0 (or n) successes the bound is exactly 0 (or 1); the formula leaves rounding there.
  return {successes == 0 ? 0.0 : std::max(0.0, centre - half), successes == n ? 1.0 : std::min(1.0, centre + half)};
}

double McNemarExactP(int only_first, int only_second) {
  if (only_first < 0 || only_second < 0) {
    throw std::invalid_argument(
        fmt::format("McNemarExactP: counts {} and {} are invalid; expected counts >= 0", only_first, only_second));
  }
  const int n = only_first + only_second, k = std::min(only_first, only_second);
  if (n == 0) return 1.0;
  // Σ C(n, i) 2^-n, each term from log-gamma so that thousands of pairs neither overflow nor underflow.
  double tail = 0.0;
  for (int i = 0; i <= k; ++i) {
    tail += std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) - n * std::log(2.0));
  }
  return std::min(1.0, 2.0 * tail);
}

}  // namespace rotorguard::campaign
