#pragma once
/// The statistics campaigns and benchmarks report: rates with Wilson intervals, quantiles.
#include <utility>
#include <vector>

namespace rotorguard::campaign {

/// Wilson score interval of `successes` in `n` at 95 %: [lo, hi] ([0, 1] for n = 0).
std::pair<double, double> WilsonInterval(int successes, int n);

/// The p-quantile (p in [0, 1]) of a sample by nearest rank on the sorted values: index
/// round(p (n - 1)); 0 for an empty sample. Benchmarks report medians and 99th percentiles with it.
double Percentile(std::vector<double> values, double p);

}  // namespace rotorguard::campaign
