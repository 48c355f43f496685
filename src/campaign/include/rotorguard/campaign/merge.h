#pragma once
/// Joining a campaign's shards: every trial exactly once, one spec, one program; then the
/// statistics of its metrics per grid point (summary.json, summary.md) and its kind's own result.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorguard/campaign/registry.h"

namespace rotorguard::campaign {

/// Every trial record of a whole campaign, in trial order, read from `dirs` (every shard's manifest
/// and results) once checked to form the campaign exactly once, with one spec and one version;
/// `manifest` receives the first shard's manifest. Throws io::CorruptFileError, io::InputFileError
/// or std::invalid_argument naming the file.
std::vector<nlohmann::json> ReadCampaignRecords(const std::vector<std::string>& dirs, nlohmann::json* manifest);

/// Joins the results of `dirs` (ReadCampaignRecords) and writes summary.json and summary.md into
/// `out_dir`; for a benchmark's campaign also its kind's result, bench.json and bench.md, from
/// `kinds` (registry.h). Returns the summary, with the kind's result under "bench" when there is one.
nlohmann::json MergeCampaign(const std::vector<std::string>& dirs, const std::string& out_dir,
                             const CampaignRegistry& kinds);

}  // namespace rotorguard::campaign
