
#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>

#include "rotorguard/benchmarks/campaign_bench.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/merge.h"
#include "rotorguard/campaign/registry.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/io/files.h"

namespace rotorguard::benchmarks {

namespace fs = std::filesystem;
using campaign::Campaign;

nlohmann::json RunCampaignBenchmark(const campaign::Campaign& spec, const std::string& work_dir,
                                    const std::string& version, const campaign::CampaignRegistry& kinds) {
  if (fs::exists(work_dir) && !fs::is_empty(work_dir)) {
    throw std::invalid_argument(fmt::format("bench campaign: '{}' is not empty; expected a new folder", work_dir));
  }
  const auto run = [&](const std::string& name, int jobs, campaign::Shard shard, bool resume) {
    campaign::CampaignRunOptions o;
    o.out_dir = (fs::path(work_dir) / name).string();
    o.jobs = jobs;
    o.shard = shard;
    o.resume = resume;
    o.version = version;
    const Stopwatch clock;
    campaign::RunCampaign(spec, o);
    return clock.seconds();
  };
  const auto summary = [&](const std::string& name) {
    const fs::path dir = fs::path(work_dir) / name;
    campaign::MergeCampaign({dir.string()}, dir.string(), kinds);
    return io::ReadFile((dir / "summary.json").string()) + io::ReadFile((dir / "summary.md").string());
  };
  const int trials = spec.trials;
  const double one = run("jobs1", 1, {}, false), two = run("jobs2", 2, {}, false);
  const std::string reference = summary("jobs1");
  // Kill and resume: the state a SIGKILL leaves (whole lines, one cut short, no finish time).
  run("killed", 2, {}, false);
  const std::string results = (fs::path(work_dir) / "killed" / campaign::Shard{}.ResultsFileName()).string();
  std::string text = io::ReadFile(results);
  std::size_t cut = 0;
  for (int k = 0; k < trials / 3; ++k) cut = text.find('\n', cut) + 1;
  const std::size_t next = text.find('\n', cut);
  text = text.substr(0, cut) + text.substr(cut, (next - cut) / 2);
  io::WriteFileAtomically(results, text);
  const std::string manifest = (fs::path(work_dir) / "killed" / campaign::Shard{}.ManifestFileName()).string();
  nlohmann::json m = nlohmann::json::parse(io::ReadFile(manifest));
  m["finished"] = nullptr;
  io::WriteFileAtomically(manifest, m.dump(2) + "\n");
  run("killed", 2, {}, true);
  for (int i = 0; i < 4; ++i) run("shards", 1, campaign::Shard{i, 4}, false);
  return {{"benchmark", "campaign"},
          {"campaign", spec.name},
          {"trials", trials},
          {"trials_per_s_1worker", trials / one},
          {"trials_per_s_2workers", trials / two},
          {"scaling_efficiency", one / (2.0 * two)},
          {"jobs_identical", summary("jobs2") == reference},
          {"resume_identical", summary("killed") == reference},
          {"shards_identical", summary("shards") == reference}};
}

}  // namespace rotorguard::benchmarks
