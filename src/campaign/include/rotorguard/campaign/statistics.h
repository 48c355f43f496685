#pragma once
/// The statistics campaigns and benchmarks report: rates with Wilson intervals, paired tests
/// (quantiles: core/statistics.h).
#include <utility>
#include <vector>

namespace rotorguard::campaign {

/// Wilson score interval of `successes` in `n` at 95 %: [lo, hi] ([0, 1] for n = 0).
std::pair<double, double> WilsonInterval(int successes, int n);

/// The exact (binomial) McNemar test of a paired comparison: of the pairs whose outcomes differ,
/// `only_first` went the first method's way and `only_second` the second's. Returns the two-sided
/// p-value, the probability under "neither is better" (each discordant pair a fair coin) of a split
/// at least this uneven: min(1, 2 Σ_{i <= min(b, c)} C(b + c, i) / 2^(b + c)); 1 without discordant
/// pairs. Throws std::invalid_argument for a negative count.
double McNemarExactP(int only_first, int only_second);

}  // namespace rotorguard::campaign
