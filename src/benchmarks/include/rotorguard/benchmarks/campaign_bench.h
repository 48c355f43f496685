#pragma once
/// `rotorguard bench campaign`: the campaign engine's own benchmark, its throughput and whether a
/// run's summary survives more workers, a kill and a resume, and sharding, byte for byte.
#include <string>

#include <nlohmann/json.hpp>

#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/registry.h"

namespace rotorguard::benchmarks {

/// `rotorguard bench campaign`: runs `spec` in `work_dir` (which it fills) with one worker and
/// with two, then a kill-and-resume (a run cut after a third of its trials, mid-line, unfinished,
/// then resumed) and 4 shards, and compares their merged summaries (merged with `kinds`) with the uninterrupted one's:
/// {trials, trials_per_s_1worker, trials_per_s_2workers, scaling_efficiency (the 2-worker rate over
/// twice the 1-worker rate), resume_identical, shards_identical, jobs_identical}.
nlohmann::json RunCampaignBenchmark(const campaign::Campaign& spec, const std::string& work_dir, const std::string& version,
                                    const campaign::CampaignRegistry& kinds);

}  // namespace rotorguard::benchmarks
