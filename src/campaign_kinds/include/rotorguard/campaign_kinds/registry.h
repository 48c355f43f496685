#pragma once
/// The kinds of campaign this project defines, registered with the campaign engine: the scenario
/// sweep (specs without a `bench` key, scenario_sweep.h) and the benchmarks that run as campaigns
/// (`bench ftc`, `bench nav`, `bench mars`), so that a benchmark shards, resumes, runs on Slurm and
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
#include "rotorguard/campaign/registry.h"

namespace rotorguard::benchmarks {

/// Every kind: the scenario sweep, ftc, nav and mars, in that order.
const campaign::CampaignRegistry& CampaignKinds();

}  // namespace rotorguard::benchmarks
