#pragma once
/// The benchmarks that run as campaigns (`bench ftc`, `bench nav`, `bench mars`): their specs and
/// their results from a campaign's records, so that a benchmark shards, resumes, runs on Slurm and
/// merges like a scenario sweep (docs/campaigns.md, "Benchmarks as campaigns").
///
/// A benchmark spec names the benchmark instead of a scenario:
///
///     name: bench_ftc_100
///     bench: ftc                     # ftc, nav or mars
///     trials: 100                    # per cell (ftc), world kind (nav), row and method (mars)
///     seed: 1
///     vehicle: ../vehicles/zhou2025_quad.yaml   # ftc; and methods: [rotorguard, ...]
///
/// nav takes `base` (the navigate scenario every trial flies) and `kinds`; mars takes `spiral`,
/// `nine_units`, `alloc_samples` and, optionally, `reconfigure` and (both or neither) `plan_4x1` and
/// `plan_3x2`. Paths are relative to the spec's folder; a file that cannot be read is an error at
/// its key.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/bench/campaign.h"

namespace rotorguard::bench {

/// A benchmark's result and its tables.
struct BenchReport {
  nlohmann::json result;  ///< what `rotorguard bench NAME --json` prints
  std::string markdown;   ///< its tables
};

/// The result of the benchmark `bench` ({"name", "options"}, as `Campaign::bench` and the
/// manifests record it) from its campaign's records, in trial order. Throws std::invalid_argument
/// for an unknown benchmark or records that do not fit its options.
BenchReport BenchResult(const nlohmann::json& bench, const std::vector<nlohmann::json>& records);

/// Writes `report` as bench.json and bench.md into `dir` (atomically).
void WriteBenchFiles(const BenchReport& report, const std::string& dir);

/// Loads any campaign spec: a benchmark's (key `bench`) or a scenario sweep (LoadCampaignSpec).
/// Throws io::ConfigError naming file, line and key, or io::InputFileError.
Campaign LoadCampaign(const std::string& path);

}  // namespace rotorguard::bench
