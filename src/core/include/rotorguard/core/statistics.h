#pragma once
/// Quantiles and the mean of a sample: every median and percentile the project reports (benchmarks, campaigns,
/// the flight stack's own accounts) comes from here, so that a p99 means one thing everywhere.
#include <vector>

namespace rotorguard {

/// The p-quantile of a sample, p a fraction in [0, 1] (0.99 for the 99th percentile), by linear
/// interpolation between the closest ranks of the sorted values at position p (n - 1) (Hyndman and
/// Fan's type 7, numpy's default: the median of an even sample is the mean of its middle two); 0
/// for an empty sample. Throws std::invalid_argument for p outside [0, 1].
double Percentile(std::vector<double> values, double p);

/// The arithmetic mean of a sample; 0 for an empty sample.
double Mean(const std::vector<double>& values);

}  // namespace rotorguard
