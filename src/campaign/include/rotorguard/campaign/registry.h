#pragma once
/// The kinds of campaign the engine can load from a spec file and summarise. The engine knows none
/// of them: the code that defines a kind (a scenario sweep, a benchmark's trial set) registers it,
/// and the engine reaches it only through this table.
///
/// A spec names its kind with the key `bench` (docs/campaigns.md, "Benchmarks as campaigns"); a
/// spec without that key is read by the kind registered without a name (the scenario sweep).
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorguard/campaign/campaign.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::campaign {

/// A kind's result: what `rotorguard bench NAME --json` prints, and its Markdown tables.
struct BenchReport {
  nlohmann::json result;
  std::string markdown;
};

struct CampaignKind {
  /// What the spec's `bench` key says; "" for the kind that reads specs without that key.
  std::string name;
  /// Builds the campaign from its spec: the document's `root` (`name` and `bench` already read by
  /// the engine for a named kind, which then rejects the keys nobody read) and the spec's `path`
  /// (relative paths in it are relative to its folder). Throws io::ConfigError naming file, line
  /// and key.
  std::function<Campaign(const io::ConfigNode& root, const std::string& path)> load;
  /// The kind's result from its records (in trial order) and its options (Campaign::bench's
  /// "options"). Throws std::invalid_argument for records that do not fit the options. Empty for
  /// a kind without a result of its own.
  std::function<BenchReport(const nlohmann::json& options, const std::vector<nlohmann::json>& records)> result;
};

class CampaignRegistry {
 public:
  /// Adds a kind. Throws std::logic_error for a second kind of the same name.
  void Add(CampaignKind kind);
  /// The kind of that name; null when there is none.
  const CampaignKind* Find(const std::string& name) const;
  /// The named kinds, in the order they were added: the values the `bench` key accepts.
  std::vector<std::string> names() const;

 private:
  std::vector<CampaignKind> kinds_;
};

/// Loads a campaign spec of any registered kind. Throws io::ConfigError naming file, line and key,
/// or io::InputFileError.
Campaign LoadCampaign(const std::string& path, const CampaignRegistry& kinds);

/// The result of the campaign `bench` ({"name", "options"}, as Campaign::bench and the manifests
/// record it) from its records, in trial order. Throws std::invalid_argument for an unknown kind
/// or records that do not fit its options.
BenchReport CampaignResult(const nlohmann::json& bench, const std::vector<nlohmann::json>& records,
                           const CampaignRegistry& kinds);

/// Writes `report` as bench.json and bench.md into `dir` (atomically).
void WriteBenchFiles(const BenchReport& report, const std::string& dir);

}  // namespace rotorguard::campaign
