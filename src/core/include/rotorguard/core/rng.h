#pragma once
/// Seeded random numbers with algorithms specified here (not std::*_distribution, whose algorithms
/// differ between standard libraries), so that a seed gives the same numbers everywhere.
#include <cstdint>
#include <string_view>

namespace rotorguard {

/// splitmix64 finaliser: a bijective 64-bit mix. Used to derive seeds counter-style.
std::uint64_t SplitMix64(std::uint64_t x);

/// Seed of stream `index` under `seed` (e.g. trial i of a campaign, or one sensor of a run).
/// Independent of thread count or sharding: a pure function of its arguments.
std::uint64_t DeriveSeed(std::uint64_t seed, std::uint64_t index);

/// Seed of the stream named `name` under `seed`: DeriveSeed(seed, FNV-1a 64 of the name). Every
/// workload that draws trials names its own stream, so that two workloads on one seed never fly
/// the same draws (a calibration and the evaluation of what it calibrated, say).
std::uint64_t DeriveSeed(std::uint64_t seed, std::string_view name);

/// Trial `trial` of the workload named `workload` ("bench ftc", "campaign fdd_far_takeoff") under
/// `seed`: DeriveSeed(DeriveSeed(seed, workload), trial). No two workloads share a trial's seed,
/// nor a trial's seed a scenario's own small seeds (1, 2, 3...).
std::uint64_t TrialSeed(std::uint64_t seed, std::string_view workload, std::uint64_t trial);

/// xoshiro256** generator (Blackman & Vigna) with uniform and normal transforms of its own.
class Rng {
 public:
  explicit Rng(std::uint64_t seed);
  std::uint64_t NextU64();
  /// Uniform in [0, 1) with 53 random bits.
  double Uniform();
  /// Uniform in [lo, hi).
  double Uniform(double lo, double hi);
  /// Standard normal by the Box-Muller transform (both outputs used).
  double Normal();
  double Normal(double mean, double stddev) { return mean + stddev * Normal(); }

 private:
  std::uint64_t s_[4];
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace rotorguard
