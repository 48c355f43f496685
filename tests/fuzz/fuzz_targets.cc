#include "fuzz_targets.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <typeinfo>

#include "rotorguard/benchmarks/config_files.h"
#include "rotorguard/benchmarks/fdd_calibration.h"
#include "rotorguard/campaign_kinds/registry.h"
#include "rotorguard/campaign/merge.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/record/flight_log.h"
#include "rotorguard/record/report.h"

namespace rotorguard::fuzz {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void Finding(const std::string& path, const std::string& what) {
  std::fprintf(stderr, "FINDING in %s: %s\n", path.c_str(), what.c_str());
  std::fflush(stderr);
  std::abort();
}

// Every number of an IndexExtremes is finite, or a finding.
void RequireFiniteExtremes(const fdd::IndexExtremes& extremes, const std::string& input) {
  for (const auto& [name, field] : fdd::kIndexExtremesFields) {
    if (!std::isfinite(extremes.*field)) Finding(input, "a non-finite extreme " + std::string(name));
  }
}

// An input read by two commands is accepted when both accept it.
Outcome Both(Outcome a, Outcome b) {
  return a == Outcome::kAccepted && b == Outcome::kAccepted ? Outcome::kAccepted : Outcome::kRefused;
}

const fs::path kCorpus = fs::path(ROTORGUARD_SOURCE_DIR) / "tests/fuzz/corpus";

}  // namespace

const std::string& ScratchFolder() {
  static const io::TemporaryFolder folder("rotorguard-fuzz");  // removed when the process exits normally
  static const bool filled = [] {
    const fs::path dir(folder.path());
    for (const char* sub : {"scenarios", "vehicles", "assemblies", "campaigns"}) {
      fs::copy(fs::path(ROTORGUARD_SOURCE_DIR) / "configs" / sub, dir / sub, fs::copy_options::recursive);
    }
    for (const char* sub : {"run", "mcap", "campaign"}) fs::copy(kCorpus / sub, dir / sub, fs::copy_options::recursive);
    fs::create_directories(dir / "input");
    return true;
  }();
  (void)filled;
  return folder.path();
}

void RequireFinite(const nlohmann::json& j, const std::string& input, const std::string& where) {
  if (j.is_number_float() && !std::isfinite(j.get<double>())) {
    Finding(input, "the output holds a non-finite number at " + where);
  }
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) RequireFinite(value, input, where + "/" + key);
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) RequireFinite(j[i], input, where + "/" + std::to_string(i));
  }
}

namespace {

// Runs `read`, mapping a documented refusal to kRefused and anything else thrown to a finding. A
// refusal must name `names` (a file or folder of the input) in its message. `also_documented`
// accepts a reader's own documented refusals beyond the three file errors.
template <typename F>
Outcome Guarded(const std::string& input, const std::string& names, F&& read,
                bool (*also_documented)(const std::exception&) = nullptr) {
  const auto refused = [&](const std::exception& e) {
    const std::string message = e.what();
    if (message.empty() || message.find(names) == std::string::npos) {
      Finding(input, "a refusal that does not name '" + names + "': '" + message + "'");
    }
    return Outcome::kRefused;
  };
  try {
    read();
    return Outcome::kAccepted;
  } catch (const io::ConfigError& e) {
    return refused(e);
  } catch (const io::InputFileError& e) {
    return refused(e);
  } catch (const io::CorruptFileError& e) {
    return refused(e);
  } catch (const std::exception& e) {
    if (also_documented != nullptr && also_documented(e)) return Outcome::kRefused;
    Finding(input, std::string("an undocumented ") + typeid(e).name() + ": '" + e.what() + "'");
  }
}

// `rotorguard validate`: any config file, its kind recognised from its keys. A refusal may name the
// file it references (a scenario's vehicle), so it must name the scratch folder.
Outcome ValidateConfig(const std::string& path) {
  return Guarded(path, ScratchFolder(), [&] {
    const benchmarks::ValidationReport r = benchmarks::ValidateConfigFile(path);
    if (r.kind.empty() || r.summary.empty()) Finding(path, "an accepted file without a kind or summary");
  });
}

// `rotorguard report`: a saved run read back and turned into the report's data.
Outcome ReadRun(const std::string& path) {
  const std::string dir = fs::path(path).parent_path().string();
  return Guarded(path, dir, [&] {
    const record::FlightLog log = record::ReadFlightLog(dir);
    RequireFinite(record::FlightReportData(log), path, "report data");
  });
}

// `fdd-calibrate RUN`: the run's sensor log replayed through the composite FDD with the settings
// it recorded.
Outcome ReplayRun(const std::string& path) {
  const std::string dir = fs::path(path).parent_path().string();
  return Guarded(path, dir, [&] {
    const benchmarks::CalibrationLog log = benchmarks::LoadCalibrationLog(dir);
    const benchmarks::ReplayOutcome outcome =
        benchmarks::ReplayCompositeFdd(log, benchmarks::RecordedFddOptions({log}, nullptr));
    RequireFiniteExtremes(outcome.extremes, path);
  });
}

// A run's summary.json is read by both.
Outcome ReadAndReplayRun(const std::string& path) { return Both(ReadRun(path), ReplayRun(path)); }

// `campaign merge DIR` and `fdd-calibrate --healthy DIR`: a campaign's results. Shards that do not
// form one whole campaign (a trial missing or twice, two specs) are the command line's fault, which
// `campaign merge` reports as a usage error (exit 2, docs/campaigns.md).
bool IsMergeUsageError(const std::exception& e) {
  return dynamic_cast<const std::invalid_argument*>(&e) != nullptr &&
         std::string_view(e.what()).starts_with("campaign merge: ");
}

Outcome ReadCampaign(const std::string& path) {
  const std::string dir = fs::path(path).parent_path().string();
  const Outcome merged = Guarded(
      path, dir,
      [&] {
        RequireFinite(campaign::MergeCampaign({dir}, (fs::path(ScratchFolder()) / "merged").string(),
                                              benchmarks::CampaignKinds()),
                      path, "merged summary");
      },
      IsMergeUsageError);
  const Outcome flights = Guarded(
      path, dir,
      [&] {
        for (const benchmarks::FlightExtremes& f : benchmarks::LoadCampaignFlights(dir).flights) {
          RequireFiniteExtremes(f.extremes, path);
        }
      },
      IsMergeUsageError);
  return Both(merged, flights);
}

}  // namespace

const std::vector<Target>& Targets() {
  static const std::vector<Target> targets = {
      {"config",
       "input/fuzz.yaml",
       {"configs", "tests/fuzz/corpus/run/vehicle.yaml"},
       "rotorguard validate: scenario, vehicle, assembly, campaign spec, FDD thresholds",
       ValidateConfig},
      {"log_csv", "run/log.csv", {}, "rotorguard report: a run's log.csv", ReadRun},
      {"scene_json", "run/scene.json", {}, "rotorguard report: a run's scene.json", ReadRun},
      {"summary_json",
       "run/summary.json",
       {},
       "rotorguard report and fdd-calibrate: a run's summary.json",
       ReadAndReplayRun},
      {"sensors_csv",
       "run/sensors.csv",
       {},
       "rotorguard fdd-calibrate: a run's sensors.csv, replayed through the composite FDD",
       ReplayRun},
      {"flight_mcap", "mcap/flight.mcap", {}, "rotorguard report: a run's flight.mcap", ReadRun},
      {"results_jsonl",
       "campaign/results.jsonl",
       {},
       "rotorguard campaign merge and fdd-calibrate --healthy: a campaign's results.jsonl",
       ReadCampaign},
      {"manifest_json",
       "campaign/manifest.json",
       {},
       "rotorguard campaign merge and fdd-calibrate --healthy: a campaign's manifest.json",
       ReadCampaign},
  };
  return targets;
}

const Target* FindTarget(std::string_view name) {
  for (const Target& t : Targets()) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

Outcome RunOne(const Target& target, std::string_view bytes) {
  const std::string path = (fs::path(ScratchFolder()) / target.file).string();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) {
      std::fprintf(stderr, "rotorguard fuzz: cannot write %s\n", path.c_str());
      std::exit(2);
    }
  }
  return target.run(path);
}

std::vector<std::string> SeedFiles(const Target& target) {
  const fs::path source(ROTORGUARD_SOURCE_DIR);
  const std::string extension = fs::path(target.file).extension().string();
  std::vector<std::string> files;
  if (fs::is_regular_file(kCorpus / target.file)) files.push_back((kCorpus / target.file).string());
  for (std::string_view seed : target.seeds) {
    const fs::path p = source / seed;
    if (fs::is_directory(p)) {
      for (const auto& entry : fs::recursive_directory_iterator(p)) {
        if (entry.is_regular_file() && entry.path().extension() == extension) files.push_back(entry.path().string());
      }
    } else {
      files.push_back(p.string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace rotorguard::fuzz
