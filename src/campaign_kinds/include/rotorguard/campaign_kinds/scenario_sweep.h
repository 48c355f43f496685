#pragma once
/// Scenario sweeps (docs/campaigns.md): a spec names a base scenario and sweeps over its keys (a
/// grid, and random draws per trial); every trial is one run of the scenario with the sweep's
/// values set (as `--set` would) and its own seed, derived counter-style from the campaign's seed
/// and the trial's index. The campaign engine runs them like any other campaign.
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "rotorguard/campaign/campaign.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::benchmarks {

/// A key's random draw per trial: uniform in [lo, hi), or one of a list's values with equal odds.
struct RandomSweep {
  enum class Kind { kUniform, kChoice };
  Kind kind = Kind::kUniform;
  double lo = 0.0, hi = 0.0;
  std::vector<std::string> choices;  ///< YAML values, as written in the spec
};

struct CampaignSpec {
  std::string name;
  std::string file;      ///< the spec's path
  std::string scenario;  ///< the base scenario's path (resolved against the spec's folder)
  std::uint64_t seed = 1;
  int repeats = 1;  ///< trials per grid point, >= 1
  /// Key path -> values (YAML text), in the spec's order; the trials cover their product, the
  /// last key varying fastest.
  std::vector<std::pair<std::string, std::vector<std::string>>> grid;
  std::vector<std::pair<std::string, RandomSweep>> random;
  /// RunSummary::ToJson keys recorded per trial (numbers or booleans; deterministic ones only).
  std::vector<std::string> metrics;
  /// The spec's canonical content (with the base scenario's text): what shards must share.
  std::string hash;

  int trials() const;
};

/// The seed stream a campaign named `name` draws its trials' vehicles from (TrialSeed's
/// workload): its own, so that no other campaign or benchmark flies them.
std::string CampaignSeedStream(const std::string& name);

/// Loads and validates a spec. Throws io::ConfigError naming file, line and key (an unknown key,
/// an empty sweep, a sweep over a key the scenario does not have, an unknown metric) or
/// io::InputFileError.
CampaignSpec LoadCampaignSpec(const std::string& path);
/// The same from a spec already open: its document's `root`, `path` naming it.
CampaignSpec LoadCampaignSpec(const io::ConfigNode& root, const std::string& path);

/// Trial `index`'s resolved parameters: every swept key's value (YAML text) and "seed".
std::map<std::string, std::string> TrialParameters(const CampaignSpec& spec, int index);

/// The spec's trials: each one run of the scenario with its parameters set (as `--set` would),
/// recording the spec's metrics from RunSummary::ToJson.
campaign::Campaign ScenarioCampaign(const CampaignSpec& spec);

}  // namespace rotorguard::benchmarks
