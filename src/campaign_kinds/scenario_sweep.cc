#include "rotorguard/campaign_kinds/scenario_sweep.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "rotorguard/campaign/campaign.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/files.h"

namespace rotorguard::benchmarks {

namespace fs = std::filesystem;
using campaign::Campaign;

namespace {

/// RunSummary keys a trial may record: deterministic for a scenario and seed (wall-clock figures
/// such as wall_time_s would make merged summaries depend on the machine and the load).
const std::vector<std::string> kRecordable = {"success",
                                              "crashed",
                                              "sim_time_s",
                                              "tracking_rmse_m",
                                              "tracking_rmse_window_m",
                                              "tracking_rmse_eq37_m",
                                              "max_position_error_m",
                                              "min_altitude_m",
                                              "max_spin_rad_s",
                                              "max_tilt_rad",
                                              "crash_speed_m_s",
                                              "tilt_recovery_s",
                                              "map_voxels_occupied",
                                              "lidar_points_dropped",
                                              "physics_steps",
                                              "control_cycles",
                                              "fdd.detected",
                                              "fdd.correct",
                                              "fdd.false_alarm",
                                              "fdd.latency_s",
                                              "fdd.detection_s",
                                              "fdd.healthy_extremes.min_motor_index",
                                              "fdd.healthy_extremes.max_propeller_index",
                                              "fdd.healthy_extremes.max_takeoff_index",
                                              "fdd.healthy_extremes.debounced_motor_index",
                                              "fdd.healthy_extremes.persistent_propeller_index",
                                              "fdd.healthy_extremes.gated_takeoff_index",
                                              "fdd.healthy_extremes.second_failure_index",
                                              "fdd.healthy_extremes.debounced_motor_shortfall"};
const std::vector<std::string> kDefaultMetrics = {
    "success",        "crashed",      "tracking_rmse_m", "max_position_error_m",
    "min_altitude_m", "max_tilt_rad", "tilt_recovery_s"};

/// The value at a dotted path of `j` ("fdd.latency_s"), null when absent.
nlohmann::json AtPath(const nlohmann::json& j, const std::string& path) {
  const nlohmann::json* node = &j;
  std::size_t start = 0;
  for (;;) {
    const std::size_t dot = path.find('.', start);
    const std::string key = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (!node->is_object() || !node->contains(key)) return nullptr;
    node = &(*node)[key];
    if (dot == std::string::npos) return *node;
    start = dot + 1;
  }
}

std::vector<harness::Override> OverridesOf(const std::map<std::string, std::string>& params) {
  std::vector<harness::Override> o;
  for (const auto& [key, value] : params) o.emplace_back(key, value);
  return o;
}

}  // namespace

int CampaignSpec::trials() const {
  long long n = repeats;
  for (const auto& [key, values] : grid) n *= static_cast<long long>(values.size());
  return static_cast<int>(n);
}

std::string CampaignSeedStream(const std::string& name) { return "campaign " + name; }

CampaignSpec LoadCampaignSpec(const std::string& path) {
  const io::ConfigDocument doc = io::ConfigDocument::LoadFile(path);
  return LoadCampaignSpec(doc.root(), path);
}

CampaignSpec LoadCampaignSpec(const io::ConfigNode& root, const std::string& path) {
  CampaignSpec spec;
  spec.file = path;
  spec.name = root.Required("name").AsString();
  if (!campaign::IsValidCampaignName(spec.name)) {
    root.FailAt("name", fmt::format("'{}' is invalid; expected letters, digits, '_', '.' or '-' (it names files and "
                                    "Slurm jobs)",
                                    spec.name));
  }
  const io::ConfigNode scenario = root.Required("scenario");
  // Canonical, so that every machine and every way of naming the spec records the same path (it
  // appears in trials' error messages, part of the summary).
  spec.scenario = fs::weakly_canonical(fs::absolute(fs::path(path).parent_path() / scenario.AsString())).string();
  if (const auto s = root.Optional("seed")) spec.seed = s->AsUint64();
  if (const auto r = root.Optional("repeats")) spec.repeats = static_cast<int>(r->AsIntIn(1, 10'000'000));
  // The trials' seeds come from the stream named after the campaign (TrialParameters).
  nlohmann::json canonical = {
      {"name", spec.name}, {"seed", spec.seed}, {"repeats", spec.repeats}, {"seed_stream", CampaignSeedStream(spec.name)}};
  if (const auto grid = root.Optional("grid")) {
    for (const std::string& key : grid->Keys()) {
      const io::ConfigNode values = grid->Required(key);
      if (!values.IsSequence()) values.Fail("expected a list of values to sweep");
      if (values.size() == 0) values.Fail("an empty sweep; expected at least one value");
      std::vector<std::string> texts;
      for (std::size_t i = 0; i < values.size(); ++i) {
        const io::ConfigNode v = values.At(i);
        if (!v.IsScalar()) v.Fail("expected a scalar (number, word or boolean)");
        texts.push_back(v.AsString());
      }
      spec.grid.emplace_back(key, texts);
      canonical["grid"].push_back({key, texts});
    }
  }
  if (const auto random = root.Optional("random")) {
    for (const std::string& key : random->Keys()) {
      const io::ConfigNode draw = random->Required(key);
      RandomSweep r;
      if (draw.Has("uniform")) {
        const std::vector<double> range = draw.Required("uniform").AsDoubleList(2);
        if (!(range[0] < range[1])) draw.FailAt("uniform", "expected [lo, hi] with lo < hi");
        r.lo = range[0];
        r.hi = range[1];
      } else if (draw.Has("choice")) {
        r.kind = RandomSweep::Kind::kChoice;
        const io::ConfigNode values = draw.Required("choice");
        if (!values.IsSequence() || values.size() == 0) values.Fail("expected a non-empty list of values");
        for (std::size_t i = 0; i < values.size(); ++i) r.choices.push_back(values.At(i).AsString());
      } else {
        draw.Fail("expected {uniform: [lo, hi]} or {choice: [values]}");
      }
      draw.RejectUnknownKeys();
      for (const auto& [grid_key, values] : spec.grid) {
        if (grid_key == key) random->FailAt(key, "swept by grid too; expected each key in one sweep only");
      }
      if (key == "seed") random->FailAt(key, "the seed is the campaign's (key seed): each trial derives its own");
      spec.random.emplace_back(key, r);
      canonical["random"].push_back(
          {key, r.kind == RandomSweep::Kind::kUniform ? nlohmann::json({r.lo, r.hi}) : nlohmann::json(r.choices)});
    }
  }
  if (const auto metrics_node = root.Optional("metrics")) {
    if (!metrics_node->IsSequence() || metrics_node->size() == 0)
      metrics_node->Fail("expected a non-empty list of metrics");
    for (std::size_t i = 0; i < metrics_node->size(); ++i) {
      const std::string m = metrics_node->At(i).AsString();
      if (std::find(kRecordable.begin(), kRecordable.end(), m) == kRecordable.end()) {
        metrics_node->At(i).Fail(
            fmt::format("'{}' is not a recorded metric; expected one of {}", m, fmt::join(kRecordable, ", ")));
      }
      spec.metrics.push_back(m);
    }
  } else {
    spec.metrics = kDefaultMetrics;
  }
  canonical["metrics"] = spec.metrics;
  root.RejectUnknownKeys();
  for (const auto& [key, values] : spec.grid) {
    if (key == "seed") root.FailAt("grid.seed", "the seed is the campaign's (key seed): each trial derives its own");
  }
  if (spec.trials() > 10'000'000 || spec.trials() < 1) {
    root.Fail(fmt::format("{} trials; expected between 1 and 10^7 (grid points times repeats)", spec.trials()));
  }
  // Every swept key must exist in the scenario, and trial 0 must load: a sweep's typo fails here,
  // before any trial runs, at the spec's key.
  std::string scenario_text;
  try {
    scenario_text = io::ReadInputFile(spec.scenario);
  } catch (const std::runtime_error&) {
    scenario.Fail(fmt::format("cannot read the scenario '{}'", spec.scenario));
  }
  try {
    harness::LoadScenario(spec.scenario, OverridesOf(TrialParameters(spec, 0)));
  } catch (const io::ConfigError& e) {
    std::string where = "scenario";
    for (const auto& [key, values] : spec.grid) {
      if (e.key_path().rfind(key, 0) == 0 || key.rfind(e.key_path(), 0) == 0) where = "grid." + key;
    }
    for (const auto& [key, r] : spec.random) {
      if (e.key_path().rfind(key, 0) == 0 || key.rfind(e.key_path(), 0) == 0) where = "random." + key;
    }
    root.FailAt(where, fmt::format("the scenario rejects trial 0: {}", e.what()));
  }
  spec.hash = campaign::Fingerprint(canonical.dump() + "\n" + scenario_text);
  return spec;
}

std::map<std::string, std::string> TrialParameters(const CampaignSpec& spec, int index) {
  std::map<std::string, std::string> p;
  int point = index / spec.repeats;
  for (auto it = spec.grid.rbegin(); it != spec.grid.rend(); ++it) {  // the last key varies fastest
    const int n = static_cast<int>(it->second.size());
    p[it->first] = it->second[static_cast<std::size_t>(point % n)];
    point /= n;
  }
  const std::uint64_t seed = TrialSeed(spec.seed, CampaignSeedStream(spec.name), static_cast<std::uint64_t>(index));
  Rng draws(DeriveSeed(seed, 1));  // its own stream: the trial's seed drives the simulation
  for (const auto& [key, r] : spec.random) {
    if (r.kind == RandomSweep::Kind::kUniform) {
      p[key] = fmt::format("{}", draws.Uniform(r.lo, r.hi));
    } else {
      const auto k = static_cast<std::size_t>(draws.Uniform() * static_cast<double>(r.choices.size()));
      p[key] = r.choices[std::min(k, r.choices.size() - 1)];
    }
  }
  p["seed"] = std::to_string(seed);
  return p;
}

campaign::Campaign ScenarioCampaign(const CampaignSpec& spec) {
  campaign::Campaign c;
  c.name = spec.name;
  c.file = spec.file;
  c.hash = spec.hash;
  c.seed = spec.seed;
  c.trials = spec.trials();
  for (const auto& [key, values] : spec.grid) c.group_keys.push_back(key);
  c.metrics = spec.metrics;
  c.parameters = [spec](int index) { return TrialParameters(spec, index); };
  // The watchdog's simulated time: the scenario's duration, or the trial's where the sweep sets it
  // (the scenario file is read once here, not once more per trial).
  const double duration_s = harness::LoadScenario(spec.scenario).duration_s;
  c.simulated_s = [duration_s](int, const std::map<std::string, std::string>& params) {
    const auto swept = params.find("duration_s");
    return swept == params.end() ? duration_s : std::stod(swept->second);
  };
  c.reproduce = [spec](int, const std::map<std::string, std::string>& params) {
    std::string command = "rotorguard run " + spec.scenario;
    for (const auto& [key, value] : params) command += fmt::format(" --set '{}={}'", key, value);
    return command;
  };
  c.run = [spec](int, const std::map<std::string, std::string>& params) {
    const nlohmann::json r =
        harness::RunScenario(harness::LoadScenario(spec.scenario, OverridesOf(params)), harness::RunOptions{}).ToJson();
    campaign::TrialOutcome out;
    for (const std::string& m : spec.metrics) out.metrics[m] = AtPath(r, m);
    return out;
  };
  return c;
}

}  // namespace rotorguard::benchmarks
