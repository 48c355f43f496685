#pragma once
/// The statistics campaigns and benchmarks report: rates with Wilson intervals, quantiles.
#include <utility>
#include <vector>

namespace rotorguard::campaign {

/// Wilson score interval of `successes` in `n` at 95 %: [lo, hi] ([0, 1] for n = 0).
std::pair<double, double> WilsonInterval(int successes, int n);

/// The p-quantile of a sample, p a fraction in [0, 1] (0.99 for the 99th percentile), by linear
/// interpolation between the closest ranks of the sorted values at position p (n - 1) (Hyndman and
/// Fan's type 7, numpy's default: the median of an even sample is the mean of its middle two); 0
/// for an empty sample. Every median and percentile a benchmark reports comes from here. Throws
/// std::invalid_argument for p outside [0, 1].
double Percentile(std::vector<double> values, double p);

}  // namespace rotorguard::campaign
