#pragma once
/// The statistics campaigns and benchmarks report: rates with Wilson intervals, quantiles.
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

/// The p-quantile of a sample, p a fraction in [0, 1] (0.99 for the 99th percentile), by linear
/// interpolation between the closest ranks of the sorted values at position p (n - 1) (Hyndman and
/// Fan's type 7, numpy's default: the median of an even sample is the mean of its middle two); 0
/// for an empty sample. Every median and percentile a benchmark reports comes from here. Throws
/// std::invalid_argument for p outside [0, 1].
double Percentile(std::vector<double> values, double p);

}  // namespace rotorguard::campaign
