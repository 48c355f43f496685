#include "rotorguard/campaign/merge.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>

#include "results_file.h"
#include "rotorguard/campaign/statistics.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/json_file.h"

namespace rotorguard::campaign {

namespace fs = std::filesystem;

namespace {

/// Statistics of one metric over `trials` (booleans as rates with Wilson intervals, numbers as a
/// mean with a normal-approximation 95 % interval); null values are left out of n.
nlohmann::json MetricStats(const std::vector<const nlohmann::json*>& trials, const std::string& metric) {
  std::vector<double> values;
  int trues = 0, bools = 0;
  for (const nlohmann::json* t : trials) {
    if ((*t)["status"] != "ok") continue;
    // A trial may lack a metric (a benchmark's parts record different ones): find, never operator[]
    // on a const object, which does not check.
    const nlohmann::json& m = (*t)["metrics"];
    const auto it = m.find(metric);
    if (it == m.end()) continue;
    const nlohmann::json& v = *it;
    if (v.is_boolean()) {
      ++bools;
      trues += v.get<bool>();
    } else if (v.is_number()) {
      values.push_back(v.get<double>());
    }
  }
  if (bools > 0) {
    const auto [lo, hi] = WilsonInterval(trues, bools);
    return {{"n", bools}, {"rate", static_cast<double>(trues) / bools}, {"wilson95", {lo, hi}}};
  }
  if (values.empty()) return {{"n", 0}};
  // Welford's running mean and squared deviations: no sum of raw values that could overflow.
  double mean = 0.0, m2 = 0.0;
  for (std::size_t k = 0; k < values.size(); ++k) {
    const double delta = values[k] - mean;
    mean += delta / static_cast<double>(k + 1);
    m2 += delta * (values[k] - mean);
  }
  const double n = static_cast<double>(values.size());
  const double sd = values.size() > 1 ? std::sqrt(m2 / (n - 1.0)) : 0.0;
  const double half = 1.959963984540054 * sd / std::sqrt(n);
  if (!std::isfinite(mean) || !std::isfinite(sd) || !std::isfinite(half)) {
    return {{"n", values.size()}, {"overflow", true}};  // never a NaN in the summary
  }
  return {{"n", values.size()},
          {"mean", mean},
          {"std", sd},
          {"ci95", {mean - half, mean + half}},
          {"min", *std::min_element(values.begin(), values.end())},
          {"max", *std::max_element(values.begin(), values.end())}};
}

nlohmann::json GroupStats(const std::vector<const nlohmann::json*>& trials, const std::vector<std::string>& metrics) {
  nlohmann::json g = {{"trials", trials.size()}};
  std::map<std::string, int> status;
  for (const nlohmann::json* t : trials) ++status[(*t)["status"].get<std::string>()];
  g["status"] = status;
  for (const std::string& m : metrics) g["metrics"][m] = MetricStats(trials, m);
  return g;
}

std::string StatsCell(const nlohmann::json& s) {
  if (s["n"].get<int>() == 0 || s.contains("overflow")) return "-";
  if (s.contains("rate")) {
    return fmt::format("{:.3f} [{:.3f}, {:.3f}]", s["rate"].get<double>(), s["wilson95"][0].get<double>(),
                       s["wilson95"][1].get<double>());
  }
  return fmt::format("{:.4g} ± {:.2g}", s["mean"].get<double>(),
                     0.5 * (s["ci95"][1].get<double>() - s["ci95"][0].get<double>()));
}

// A manifest's keys and their types, as RunCampaign writes them (found by fuzzing: a null
// trials_total escaped as the JSON library's type_error).
void CheckManifest(const nlohmann::json& manifest, const std::string& path) {
  const auto fail = [&path](const char* key, const char* expected) {
    throw io::CorruptFileError(path, 0, fmt::format("'{}' is missing or not {}", key, expected));
  };
  for (const char* key : {"spec_hash", "version", "campaign"}) {
    if (!manifest.contains(key) || !manifest[key].is_string()) fail(key, "text");
  }
  const auto it = manifest.find("trials_total");
  if (it == manifest.end() || !it->is_number_integer() || it->get<std::int64_t>() < 0 ||
      it->get<std::int64_t>() > std::numeric_limits<int>::max()) {
    fail("trials_total", "a count");
  }
  const auto shard = manifest.find("shard");
  if (shard == manifest.end() || !shard->is_string() || shard->get<std::string>().find('/') == std::string::npos) {
    fail("shard", "text 'i/N'");
  }
  for (const char* key : {"metrics", "grid_keys"}) {
    if (!manifest.contains(key) || !manifest[key].is_array()) fail(key, "a list of names");
    for (const nlohmann::json& name : manifest[key]) {
      if (!name.is_string()) fail(key, "a list of names");
    }
  }
  if (!manifest.contains("finished") || !(manifest["finished"].is_string() || manifest["finished"].is_null())) {
    fail("finished", "a time or null");
  }
}

}  // namespace

std::vector<nlohmann::json> ReadCampaignRecords(const std::vector<std::string>& dirs, nlohmann::json* manifest_out) {
  if (dirs.empty()) throw std::invalid_argument("campaign merge: expected at least one results folder");
  std::vector<nlohmann::json> manifests;
  std::vector<std::string> manifest_files;
  std::map<int, nlohmann::json> trials;
  std::map<int, std::string> source;
  for (const std::string& dir : dirs) {
    if (!fs::is_directory(dir)) throw io::InputFileError(dir, "not a folder of campaign results");
    std::vector<fs::path> found;
    for (const auto& entry : fs::directory_iterator(dir)) {
      const std::string name = entry.path().filename().string();
      if (name == "manifest.json" || (name.rfind("manifest.shard-", 0) == 0 && entry.path().extension() == ".json")) {
        found.push_back(entry.path());
      }
    }
    if (found.empty()) throw io::InputFileError(dir, "no manifest.json or manifest.shard-*.json");
    std::sort(found.begin(), found.end());
    for (const fs::path& m : found) {
      const nlohmann::json manifest = io::ReadJsonObject(m.string());
      CheckManifest(manifest, m.string());
      if (!manifests.empty()) {
        for (const char* key : {"spec_hash", "version"}) {
          if (manifest[key] != manifests.front()[key]) {
            throw std::invalid_argument(fmt::format(
                "campaign merge: {} has {} {} but {} has {}; merge only shards "
                "of one spec run by one program",
                m.string(), key, manifest[key].dump(), manifest_files.front(), manifests.front()[key].dump()));
          }
        }
      }
      if (manifest["finished"].is_null()) {
        throw std::invalid_argument(
            fmt::format("campaign merge: {} is unfinished (shard {} was stopped before its "
                        "last trial); resume it with `campaign run ... --shard {} --resume` "
                        "first",
                        m.string(), manifest["shard"].dump(), manifest["shard"].dump()));
      }
      const std::string shard = manifest["shard"].get<std::string>();
      const std::string results =
          (m.parent_path() / (shard.substr(shard.find('/') + 1) == "1"
                                  ? std::string("results.jsonl")
                                  : "results.shard-" + shard.substr(0, shard.find('/')) + ".jsonl"))
              .string();
      Recorded recorded = ReadResults(results);
      if (recorded.cut) {
        throw io::CorruptFileError(results, recorded.whole_size, "the last line is cut short (resume the shard first)");
      }
      for (auto& [index, line] : recorded.trials) {
        if (trials.count(index)) {
          throw std::invalid_argument(
              fmt::format("campaign merge: trial {} is in both {} and {}", index, source[index], results));
        }
        source[index] = results;
        trials.emplace(index, std::move(line));
      }
      manifests.push_back(manifest);
      manifest_files.push_back(m.string());
    }
  }
  const int total = manifests.front()["trials_total"].get<int>();
  // Counted from the recorded trials, not by walking [0, total): a damaged manifest's trials_total
  // must cost neither its size in memory nor its count in lookups.
  const auto recorded = std::distance(trials.lower_bound(0), trials.lower_bound(total));
  const std::int64_t missing = total - recorded;
  if (missing > 0) {
    std::vector<int> first;  // at most trials.size() + 10 lookups
    for (int i = 0; i < total && first.size() < 10; ++i) {
      if (!trials.count(i)) first.push_back(i);
    }
    throw std::invalid_argument(
        fmt::format("campaign merge: {} of {} trials are missing (first: {}); run or resume "
                    "the shards that hold them",
                    missing, total, fmt::join(first, ", ")));
  }
  if (static_cast<int>(trials.size()) != total) {
    throw std::invalid_argument(fmt::format("campaign merge: trials beyond the campaign's {}", total));
  }
  if (manifest_out != nullptr) *manifest_out = manifests.front();
  std::vector<nlohmann::json> records;
  records.reserve(trials.size());
  for (auto& [index, t] : trials) records.push_back(std::move(t));
  return records;
}

nlohmann::json MergeCampaign(const std::vector<std::string>& dirs, const std::string& out_dir,
                             const CampaignRegistry& kinds) {
  nlohmann::json head;
  const std::vector<nlohmann::json> records = ReadCampaignRecords(dirs, &head);
  const int total = static_cast<int>(records.size());
  const std::vector<std::string> metrics = head["metrics"].get<std::vector<std::string>>();
  const std::vector<std::string> grid_keys = head["grid_keys"].get<std::vector<std::string>>();
  std::vector<const nlohmann::json*> all;
  std::map<std::vector<std::string>, std::vector<const nlohmann::json*>> groups;  // by grid values
  std::vector<std::vector<std::string>> group_order;
  nlohmann::json errors = nlohmann::json::array();
  for (const nlohmann::json& t : records) {
    all.push_back(&t);
    std::vector<std::string> point;
    for (const std::string& k : grid_keys) point.push_back(t["params"].value(k, ""));
    if (!groups.count(point)) group_order.push_back(point);
    groups[point].push_back(&t);
    if (t["status"] != "ok" && errors.size() < 20) {
      errors.push_back({{"trial", t["trial"]}, {"status", t["status"]}, {"message", t["message"]}});
    }
  }
  nlohmann::json summary = {{"campaign", head["campaign"]},
                            {"spec_hash", head["spec_hash"]},
                            {"version", head["version"]},
                            {"trials", total},
                            {"overall", GroupStats(all, metrics)},
                            {"by_grid_point", nlohmann::json::array()},
                            {"errors", errors}};
  for (const auto& point : group_order) {
    nlohmann::json g = GroupStats(groups[point], metrics);
    for (std::size_t k = 0; k < grid_keys.size(); ++k) g["grid"][grid_keys[k]] = point[k];
    summary["by_grid_point"].push_back(g);
  }
  // summary.md: the same figures as a table, one row per grid point.
  std::string md = fmt::format("# Campaign {}\n\n{} trials (spec {}, {}): ", head["campaign"].get<std::string>(), total,
                               head["spec_hash"].get<std::string>(), head["version"].get<std::string>());
  for (const auto& [status, n] : summary["overall"]["status"].items())
    md += fmt::format("{} {}; ", status, n.get<int>());
  md += "\nRates: value [Wilson 95 % interval]; numbers: mean ± 95 % half-width (normal approximation).\n\n|";
  for (const std::string& k : grid_keys) md += fmt::format(" {} |", k);
  md += " trials |";
  for (const std::string& m : metrics) md += fmt::format(" {} |", m);
  md += "\n|";
  for (std::size_t k = 0; k < grid_keys.size() + 1 + metrics.size(); ++k) md += "---|";
  md += "\n";
  const auto row = [&](const nlohmann::json& g, const std::vector<std::string>& labels) {
    md += "|";
    for (const std::string& l : labels) md += fmt::format(" {} |", l);
    md += fmt::format(" {} |", g["trials"].get<int>());
    for (const std::string& m : metrics) md += fmt::format(" {} |", StatsCell(g["metrics"][m]));
    md += "\n";
  };
  for (std::size_t i = 0; i < group_order.size(); ++i) row(summary["by_grid_point"][i], group_order[i]);
  if (!grid_keys.empty()) {
    std::vector<std::string> labels(grid_keys.size(), "");
    labels[0] = "**all**";
    row(summary["overall"], labels);
  }
  fs::create_directories(out_dir);
  io::WriteFileAtomically((fs::path(out_dir) / "summary.json").string(), summary.dump(2) + "\n");
  io::WriteFileAtomically((fs::path(out_dir) / "summary.md").string(), md);
  if (head.contains("bench")) {  // a benchmark's campaign: its own tables too
    const BenchReport report = CampaignResult(head["bench"], records, kinds);
    WriteBenchFiles(report, out_dir);
    summary["bench"] = report.result;
  }
  return summary;
}

}  // namespace rotorguard::campaign
