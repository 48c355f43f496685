#include "rotorguard/bench/campaign.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "rotorguard/bench/bench_campaigns.h"
#include "rotorguard/bench/parallel.h"
#include "rotorguard/bench/runner.h"
#include "rotorguard/bench/scenario.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "rotorguard_git_revision.h"  // generated at build time

namespace rotorguard::bench {

namespace fs = std::filesystem;

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
                                              "tilt_recovery_s",
                                              "map_voxels_occupied",
                                              "lidar_points_dropped",
                                              "physics_steps",
                                              "control_cycles",
                                              "fdd.detected",
                                              "fdd.correct",
                                              "fdd.false_alarm",
                                              "fdd.latency_s",
                                              "fdd.detection_s"};
const std::vector<std::string> kDefaultMetrics = {"success",        "crashed",      "tracking_rmse_m",
                                                  "max_position_error_m", "min_altitude_m", "max_tilt_rad",
                                                  "tilt_recovery_s"};

std::uint64_t Fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string Hex(std::uint64_t v) { return fmt::format("{:016x}", v); }

std::string ResultsName(const Shard& s) {
  return s.count == 1 ? "results.jsonl" : fmt::format("results.shard-{}.jsonl", s.index);
}
std::string ManifestName(const Shard& s) {
  return s.count == 1 ? "manifest.json" : fmt::format("manifest.shard-{}.json", s.index);
}

std::string Host() {
  char name[256] = {};
  if (::gethostname(name, sizeof(name) - 1) != 0) return "unknown";
  return name;
}

std::string UtcNow() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

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

std::vector<Override> OverridesOf(const std::map<std::string, std::string>& params) {
  std::vector<Override> o;
  for (const auto& [key, value] : params) o.emplace_back(key, value);
  return o;
}

/// One whole line appended and synced: after a kill the file holds whole lines, at most the last
/// one cut short.
class AppendFile {
 public:
  explicit AppendFile(const std::string& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw std::runtime_error(fmt::format("{}: cannot open for appending", path));
  }
  ~AppendFile() {
    if (fd_ >= 0) ::close(fd_);
  }
  AppendFile(const AppendFile&) = delete;
  AppendFile& operator=(const AppendFile&) = delete;
  void AppendLine(const std::string& line) {
    const std::string text = line + "\n";
    std::size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
      if (n < 0) throw std::runtime_error(fmt::format("{}: write failed", path_));
      done += static_cast<std::size_t>(n);
    }
    if (::fsync(fd_) != 0) throw std::runtime_error(fmt::format("{}: fsync failed", path_));
  }

 private:
  std::string path_;
  int fd_ = -1;
};

/// The trials recorded in a results file, by index, and where its whole lines end (a last line cut
/// short by a kill starts there). Every line must be one trial's record; anything else is corruption.
struct Recorded {
  std::map<int, nlohmann::json> trials;
  std::size_t whole_size = 0;
  bool cut = false;  ///< the file ends in a partial line
};
Recorded ReadResults(const std::string& path) {
  Recorded r;
  if (!fs::exists(path)) return r;
  std::string text = io::ReadInputFile(path);
  const std::size_t end = text.rfind('\n');
  r.whole_size = end == std::string::npos ? 0 : end + 1;
  r.cut = r.whole_size < text.size();
  text.resize(r.whole_size);
  std::size_t offset = 0;
  while (offset < text.size()) {
    const std::size_t nl = text.find('\n', offset);
    nlohmann::json j = nlohmann::json::parse(text.substr(offset, nl - offset), nullptr, false);
    const bool valid = !j.is_discarded() && j.is_object() && j.contains("trial") && j["trial"].is_number_integer() &&
                       j.contains("id") && j["id"].is_string() && j.contains("params") && j["params"].is_object() &&
                       j.contains("status") && j["status"].is_string() && j.contains("message") &&
                       j["message"].is_string() && j.contains("metrics") &&
                       (j["metrics"].is_object() || j["metrics"].is_null());
    if (!valid) {
      throw io::CorruptFileError(path, offset, "expected one trial record per line: {trial, id, params, status, "
                                               "message, metrics}");
    }
    const int index = j["trial"].get<int>();
    if (r.trials.count(index)) throw io::CorruptFileError(path, offset, fmt::format("trial {} recorded twice", index));
    r.trials.emplace(index, std::move(j));
    offset = nl + 1;
  }
  return r;
}

nlohmann::json ReadJsonFile(const std::string& path) {
  nlohmann::json j = nlohmann::json::parse(io::ReadInputFile(path), nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw io::CorruptFileError(path, 0, "expected a JSON object");
  return j;
}

/// An exclusive lock on a shard for the life of a run: a second run of the same shard (a resubmitted
/// task whose first copy still runs) is refused instead of appending the same trials twice.
class ShardLock {
 public:
  explicit ShardLock(const std::string& path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw io::InputFileError(path, "cannot open the shard's lock file");
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw std::invalid_argument(fmt::format("{} is held: this shard is already running (wait for it, or stop "
                                              "it, then --resume)", path));
    }
  }
  ~ShardLock() { ::close(fd_); }  // closing releases the lock
  ShardLock(const ShardLock&) = delete;
  ShardLock& operator=(const ShardLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace

int CampaignSpec::trials() const {
  long long n = repeats;
  for (const auto& [key, values] : grid) n *= static_cast<long long>(values.size());
  return static_cast<int>(n);
}

bool IsValidCampaignName(const std::string& name) {
  return !name.empty() &&
         name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-") == std::string::npos;
}

CampaignSpec LoadCampaignSpec(const std::string& path) {
  io::ConfigDocument doc = io::ConfigDocument::LoadFile(path);
  const io::ConfigNode root = doc.root();
  CampaignSpec spec;
  spec.file = path;
  spec.name = root.Required("name").AsString();
  if (!IsValidCampaignName(spec.name)) {
    root.FailAt("name", fmt::format("'{}' is invalid; expected letters, digits, '_', '.' or '-' (it names files and "
                                    "Slurm jobs)", spec.name));
  }
  const io::ConfigNode scenario = root.Required("scenario");
  // Canonical, so that every machine and every way of naming the spec records the same path (it
  // appears in trials' error messages, part of the summary).
  spec.scenario = fs::weakly_canonical(fs::absolute(fs::path(path).parent_path() / scenario.AsString())).string();
  if (const auto s = root.Optional("seed")) spec.seed = s->AsUint64();
  if (const auto r = root.Optional("repeats")) spec.repeats = static_cast<int>(r->AsIntIn(1, 10'000'000));
  nlohmann::json canonical = {{"name", spec.name}, {"seed", spec.seed}, {"repeats", spec.repeats}};
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
      canonical["random"].push_back({key, r.kind == RandomSweep::Kind::kUniform ? nlohmann::json({r.lo, r.hi})
                                                                                  : nlohmann::json(r.choices)});
    }
  }
  if (const auto metrics_node = root.Optional("metrics")) {
    if (!metrics_node->IsSequence() || metrics_node->size() == 0) metrics_node->Fail("expected a non-empty list of metrics");
    for (std::size_t i = 0; i < metrics_node->size(); ++i) {
      const std::string m = metrics_node->At(i).AsString();
      if (std::find(kRecordable.begin(), kRecordable.end(), m) == kRecordable.end()) {
        metrics_node->At(i).Fail(fmt::format("'{}' is not a recorded metric; expected one of {}", m,
                                             fmt::join(kRecordable, ", ")));
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
    LoadScenario(spec.scenario, OverridesOf(TrialParameters(spec, 0)));
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
  spec.hash = Fingerprint(canonical.dump() + "\n" + scenario_text);
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
  const std::uint64_t seed = DeriveSeed(spec.seed, static_cast<std::uint64_t>(index));
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

std::string TrialId(const std::map<std::string, std::string>& parameters) {
  std::string text;
  for (const auto& [key, value] : parameters) text += key + "=" + value + "\n";
  return Fingerprint(text);
}

std::string Fingerprint(const std::string& text) { return Hex(Fnv1a(text)); }

std::string TrialFailure(const nlohmann::json& record) {
  const std::string message = record.value("message", "");
  return record.value("status", "") == "ok" ? message : record.value("status", "") + ": " + message;
}

Campaign ScenarioCampaign(const CampaignSpec& spec) {
  Campaign c;
  c.name = spec.name;
  c.file = spec.file;
  c.hash = spec.hash;
  c.seed = spec.seed;
  c.trials = spec.trials();
  for (const auto& [key, values] : spec.grid) c.group_keys.push_back(key);
  c.metrics = spec.metrics;
  c.parameters = [spec](int index) { return TrialParameters(spec, index); };
  c.run = [spec](int, const std::map<std::string, std::string>& params) {
    const nlohmann::json r = RunScenario(LoadScenario(spec.scenario, OverridesOf(params)), RunOptions{}).ToJson();
    TrialOutcome out;
    for (const std::string& m : spec.metrics) out.metrics[m] = AtPath(r, m);
    return out;
  };
  return c;
}

Shard Shard::Parse(const std::string& text) {
  const std::size_t slash = text.find('/');
  Shard s;
  try {
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    std::size_t used = 0;
    s.index = std::stoi(text.substr(0, slash), &used);
    if (used != slash) throw std::invalid_argument("trailing text");
    const std::string count = text.substr(slash + 1);
    s.count = std::stoi(count, &used);
    if (used != count.size()) throw std::invalid_argument("trailing text");
  } catch (const std::exception&) {
    throw std::invalid_argument(fmt::format("--shard '{}' is invalid; expected i/N with 0 <= i < N", text));
  }
  if (s.count < 1 || s.index < 0 || s.index >= s.count) {
    throw std::invalid_argument(fmt::format("--shard '{}' is invalid; expected i/N with 0 <= i < N (shards count from 0)", text));
  }
  return s;
}

std::pair<int, int> Shard::Range(int trials) const {
  const auto at = [&](int k) { return static_cast<int>(static_cast<long long>(trials) * k / count); };
  return {at(index), at(index + 1)};
}

CampaignRunSummary RunCampaign(const Campaign& campaign, const CampaignRunOptions& options) {
  if (options.jobs < 1 || options.jobs > 256) {
    throw std::invalid_argument(fmt::format("--jobs {} is invalid; expected a count in [1, 256]", options.jobs));
  }
  if (options.shard.count > campaign.trials) {
    throw std::invalid_argument(fmt::format("--shard {}/{}: more shards than the campaign's {} trials",
                                            options.shard.index, options.shard.count, campaign.trials));
  }
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec || !fs::is_directory(options.out_dir)) {
    throw std::invalid_argument(fmt::format("--out: cannot create the folder '{}'{}", options.out_dir,
                                            ec ? ": " + ec.message() : ""));
  }
  CampaignRunSummary summary;
  summary.results_file = (fs::path(options.out_dir) / ResultsName(options.shard)).string();
  summary.manifest_file = (fs::path(options.out_dir) / ManifestName(options.shard)).string();
  const auto [first, last] = options.shard.Range(campaign.trials);
  summary.trials = last - first;
  nlohmann::json manifest = {{"campaign", campaign.name},
                             {"spec", campaign.file},
                             {"spec_hash", campaign.hash},
                             {"version", options.version},
                             {"seed", campaign.seed},
                             {"trials_total", campaign.trials},
                             {"shard", fmt::format("{}/{}", options.shard.index, options.shard.count)},
                             {"trial_range", {first, last}},
                             {"grid_keys", campaign.group_keys},
                             {"metrics", campaign.metrics},
                             {"host", Host()},
                             {"started", UtcNow()},
                             {"finished", nullptr}};
  if (!campaign.bench.is_null()) manifest["bench"] = campaign.bench;

  const ShardLock lock(summary.manifest_file + ".lock");
  const bool exists = fs::exists(summary.results_file) || fs::exists(summary.manifest_file);
  std::map<int, nlohmann::json> done;
  if (exists && !options.resume) {
    throw std::invalid_argument(fmt::format("{} already holds this shard's results; pass --resume to continue "
                                            "it, or choose another --out", options.out_dir));
  }
  if (exists) {
    if (!fs::exists(summary.manifest_file)) {
      throw io::CorruptFileError(summary.manifest_file, 0, "missing: the results cannot be matched to a spec");
    }
    const nlohmann::json old = ReadJsonFile(summary.manifest_file);
    for (const char* key : {"spec_hash", "version", "shard"}) {
      if (!old.contains(key) || old[key] != manifest[key]) {
        throw std::invalid_argument(fmt::format(
            "--resume: {} records {} {}, this run has {}; resume only the same spec with the same program",
            summary.manifest_file, key, old.contains(key) ? old[key].dump() : "(none)", manifest[key].dump()));
      }
    }
    manifest["started"] = old.value("started", manifest["started"]);
    Recorded recorded = ReadResults(summary.results_file);
    for (const auto& [index, line] : recorded.trials) {
      if (index < first || index >= last || line["id"].get<std::string>() != TrialId(campaign.parameters(index))) {
        throw io::CorruptFileError(summary.results_file, 0,
                                   fmt::format("trial {} does not belong to this shard of this spec", index));
      }
    }
    // Only now, with every check passed, cut the line a kill left unfinished.
    if (recorded.cut) fs::resize_file(summary.results_file, recorded.whole_size);
    done = std::move(recorded.trials);
  }
  io::WriteFileAtomically(summary.manifest_file, manifest.dump(2) + "\n");

  std::vector<int> todo;
  for (int i = first; i < last; ++i) {
    if (!done.count(i)) todo.push_back(i);
  }
  summary.skipped = summary.trials - static_cast<int>(todo.size());
  AppendFile results(summary.results_file);
  std::mutex mutex;
  int errors = 0;
  std::exception_ptr write_error;
  ParallelFor(static_cast<int>(todo.size()), options.jobs, [&](int task) {
    const int index = todo[static_cast<std::size_t>(task)];
    const std::map<std::string, std::string> params = campaign.parameters(index);
    nlohmann::json line = {{"trial", index}, {"id", TrialId(params)}, {"params", params}};
    try {
      TrialOutcome r = campaign.run(index, params);
      bool finite = true;
      for (auto& [name, value] : r.metrics.items()) {
        if (value.is_number_float() && !std::isfinite(value.get<double>())) {
          finite = false;
          value = nullptr;  // JSON has no NaN
        }
      }
      line["status"] = finite ? "ok" : "diverged";
      line["message"] = finite ? r.message : "a metric is not finite" + (r.message.empty() ? "" : "; " + r.message);
      line["metrics"] = std::move(r.metrics);
    } catch (const std::exception& e) {
      line["status"] = "error";
      line["message"] = e.what();
      line["metrics"] = nullptr;
    } catch (...) {
      line["status"] = "error";
      line["message"] = "an exception of unknown type";
      line["metrics"] = nullptr;
    }
    // Invalid UTF-8 in a message is replaced rather than thrown: the trial is recorded either way.
    const std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    const std::lock_guard<std::mutex> guard(mutex);
    if (line["status"] != "ok") ++errors;
    if (write_error) return;  // the disk failed: no more lines; the run reports it below
    try {
      results.AppendLine(text);
    } catch (...) {
      write_error = std::current_exception();
    }
  }, options.progress);
  if (write_error) std::rethrow_exception(write_error);  // the manifest stays unfinished: resume later
  summary.ran = static_cast<int>(todo.size());
  summary.errors = errors;
  manifest["finished"] = UtcNow();
  io::WriteFileAtomically(summary.manifest_file, manifest.dump(2) + "\n");
  return summary;
}

namespace {

/// `text` quoted for a POSIX shell.
std::string ShellQuote(const std::string& text) {
  std::string q = "'";
  for (const char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

std::string SlurmArrayScript(const Campaign& campaign, const SlurmScriptOptions& o) {
  if (campaign.file.empty()) {
    throw std::invalid_argument(fmt::format("campaign '{}' has no spec file for the tasks to run; write it as a "
                                            "spec (docs/campaigns.md)", campaign.name));
  }
  if (o.shards < 1 || o.shards > campaign.trials) {
    throw std::invalid_argument(fmt::format("--shards {} is invalid; expected a count in [1, {}] (the campaign's "
                                            "trials)", o.shards, campaign.trials));
  }
  if (o.cpus_per_task < 1 || o.cpus_per_task > 256) {
    throw std::invalid_argument(fmt::format("--cpus-per-task {} is invalid; expected a count in [1, 256]", o.cpus_per_task));
  }
  if (o.out_dir.empty() || o.rotorguard.empty()) throw std::invalid_argument("the script needs --out and the program");
  for (const std::string* v : {&o.partition, &o.time_limit}) {
    if (v->find_first_of(" \t\n'\"\\$`") != std::string::npos) {
      throw std::invalid_argument(fmt::format("'{}' is invalid; expected a Slurm name without spaces or quotes", *v));
    }
  }
  const std::string out = fs::absolute(o.out_dir).lexically_normal().string();
  if (out.find_first_of(" \t\n%") != std::string::npos) {
    throw std::invalid_argument(fmt::format("--out '{}' is invalid; expected a folder without spaces or '%' (an "
                                            "#SBATCH line cannot quote them)", o.out_dir));
  }
  const std::string spec_path = fs::absolute(campaign.file).lexically_normal().string();
  std::string s = fmt::format(
      "#!/bin/bash\n"
      "# rotorguard campaign '{name}' (spec {hash}): {trials} trials in {n} shards, one per array task.\n"
      "# Submit: sbatch {script}\n"
      "# Each task resumes its shard, so resubmitting this script, or only the failed tasks\n"
      "# (sbatch --array=<their ids> {script}), is safe. When all are done:\n"
      "#   {exe} campaign merge {outq}\n"
      "#SBATCH --job-name=rg-{name}\n"
      "#SBATCH --array=0-{last}\n"
      "#SBATCH --cpus-per-task={cpus}\n"
      "#SBATCH --output={out}/slurm-%A_%a.out\n",
      fmt::arg("name", campaign.name), fmt::arg("hash", campaign.hash), fmt::arg("trials", campaign.trials),
      fmt::arg("n", o.shards), fmt::arg("script", ShellQuote(out + "/campaign.sbatch")),
      fmt::arg("exe", ShellQuote(o.rotorguard)), fmt::arg("outq", ShellQuote(out)), fmt::arg("last", o.shards - 1),
      fmt::arg("cpus", o.cpus_per_task), fmt::arg("out", out));
  if (!o.partition.empty()) s += "#SBATCH --partition=" + o.partition + "\n";
  if (!o.time_limit.empty()) s += "#SBATCH --time=" + o.time_limit + "\n";
  s += fmt::format("set -euo pipefail\n"
                   "exec {} campaign run {} --out {} --shard \"${{SLURM_ARRAY_TASK_ID}}/{}\" "
                   "--jobs \"${{SLURM_CPUS_PER_TASK:-{}}}\" --resume --quiet\n",
                   ShellQuote(o.rotorguard), ShellQuote(spec_path), ShellQuote(out), o.shards, o.cpus_per_task);
  return s;
}

std::string GitRevision() { return ROTORGUARD_GIT_REVISION; }

std::pair<double, double> WilsonInterval(int successes, int n) {
  if (n <= 0) return {0.0, 1.0};
  const double z = 1.959963984540054, p = static_cast<double>(successes) / n, z2 = z * z;
  const double denom = 1.0 + z2 / n;
  const double centre = (p + z2 / (2.0 * n)) / denom;
  const double half = z * std::sqrt(p * (1.0 - p) / n + z2 / (4.0 * n * n)) / denom;
  // At 0 (or n) successes the bound is exactly 0 (or 1); the formula leaves rounding there.
  return {successes == 0 ? 0.0 : std::max(0.0, centre - half), successes == n ? 1.0 : std::min(1.0, centre + half)};
}

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
      const nlohmann::json manifest = ReadJsonFile(m.string());
      for (const char* key :
           {"spec_hash", "version", "trials_total", "shard", "metrics", "grid_keys", "campaign", "finished"}) {
        if (!manifest.contains(key)) throw io::CorruptFileError(m.string(), 0, fmt::format("no key '{}'", key));
      }
      if (!manifests.empty()) {
        for (const char* key : {"spec_hash", "version"}) {
          if (manifest[key] != manifests.front()[key]) {
            throw std::invalid_argument(fmt::format("campaign merge: {} has {} {} but {} has {}; merge only shards "
                                                    "of one spec run by one program", m.string(), key,
                                                    manifest[key].dump(), manifest_files.front(),
                                                    manifests.front()[key].dump()));
          }
        }
      }
      if (manifest["finished"].is_null()) {
        throw std::invalid_argument(fmt::format("campaign merge: {} is unfinished (shard {} was stopped before its "
                                                "last trial); resume it with `campaign run ... --shard {} --resume` "
                                                "first", m.string(), manifest["shard"].dump(),
                                                manifest["shard"].dump()));
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
          throw std::invalid_argument(fmt::format("campaign merge: trial {} is in both {} and {}", index,
                                                  source[index], results));
        }
        source[index] = results;
        trials.emplace(index, std::move(line));
      }
      manifests.push_back(manifest);
      manifest_files.push_back(m.string());
    }
  }
  const int total = manifests.front()["trials_total"].get<int>();
  std::vector<int> missing;
  for (int i = 0; i < total; ++i) {
    if (!trials.count(i)) missing.push_back(i);
  }
  if (!missing.empty()) {
    std::vector<int> first(missing.begin(), missing.begin() + std::min<std::size_t>(missing.size(), 10));
    throw std::invalid_argument(fmt::format("campaign merge: {} of {} trials are missing (first: {}); run or resume "
                                            "the shards that hold them", missing.size(), total, fmt::join(first, ", ")));
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

nlohmann::json MergeCampaign(const std::vector<std::string>& dirs, const std::string& out_dir) {
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
  for (const auto& [status, n] : summary["overall"]["status"].items()) md += fmt::format("{} {}; ", status, n.get<int>());
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
    const BenchReport report = BenchResult(head["bench"], records);
    WriteBenchFiles(report, out_dir);
    summary["bench"] = report.result;
  }
  return summary;
}

std::optional<std::vector<nlohmann::json>> RunCampaignRecords(const Campaign& campaign, CampaignRunOptions options) {
  std::optional<io::TemporaryFolder> temporary;  // removed on return and on an exception
  if (options.out_dir.empty()) {
    temporary.emplace("rotorguard-" + campaign.name);
    options.out_dir = temporary->path();
    options.resume = false;
  }
  const CampaignRunSummary run = RunCampaign(campaign, options);
  if (options.shard.count > 1) return std::nullopt;
  // This run's results only: the folder may also hold another sharding's files.
  Recorded recorded = ReadResults(run.results_file);
  if (recorded.cut || static_cast<int>(recorded.trials.size()) != campaign.trials) {
    throw io::CorruptFileError(run.results_file, recorded.whole_size,
                               fmt::format("{} of {} trials recorded after the run", recorded.trials.size(),
                                           campaign.trials));
  }
  std::vector<nlohmann::json> records;
  records.reserve(recorded.trials.size());
  for (auto& [index, line] : recorded.trials) records.push_back(std::move(line));
  return records;
}

std::vector<nlohmann::json> RunWholeCampaign(const Campaign& campaign, int jobs,
                                             const std::function<void(int, int)>& progress) {
  CampaignRunOptions o;
  o.jobs = jobs;
  o.progress = progress;
  return *RunCampaignRecords(campaign, o);
}

nlohmann::json RunCampaignBenchmark(const Campaign& campaign, const std::string& work_dir, const std::string& version) {
  if (fs::exists(work_dir) && !fs::is_empty(work_dir)) {
    throw std::invalid_argument(fmt::format("bench campaign: '{}' is not empty; expected a new folder", work_dir));
  }
  const auto run = [&](const std::string& name, int jobs, Shard shard, bool resume) {
    CampaignRunOptions o;
    o.out_dir = (fs::path(work_dir) / name).string();
    o.jobs = jobs;
    o.shard = shard;
    o.resume = resume;
    o.version = version;
    const auto t0 = std::chrono::steady_clock::now();
    RunCampaign(campaign, o);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  const auto summary = [&](const std::string& name) {
    const fs::path dir = fs::path(work_dir) / name;
    MergeCampaign({dir.string()}, dir.string());
    return io::ReadFile((dir / "summary.json").string()) + io::ReadFile((dir / "summary.md").string());
  };
  const int trials = campaign.trials;
  const double one = run("jobs1", 1, {}, false), two = run("jobs2", 2, {}, false);
  const std::string reference = summary("jobs1");
  // Kill and resume: the state a SIGKILL leaves (whole lines, one cut short, no finish time).
  run("killed", 2, {}, false);
  const std::string results = (fs::path(work_dir) / "killed" / ResultsName({})).string();
  std::string text = io::ReadFile(results);
  std::size_t cut = 0;
  for (int k = 0; k < trials / 3; ++k) cut = text.find('\n', cut) + 1;
  const std::size_t next = text.find('\n', cut);
  text = text.substr(0, cut) + text.substr(cut, (next - cut) / 2);
  io::WriteFileAtomically(results, text);
  const std::string manifest = (fs::path(work_dir) / "killed" / ManifestName({})).string();
  nlohmann::json m = ReadJsonFile(manifest);
  m["finished"] = nullptr;
  io::WriteFileAtomically(manifest, m.dump(2) + "\n");
  run("killed", 2, {}, true);
  for (int i = 0; i < 4; ++i) run("shards", 1, Shard{i, 4}, false);
  return {{"benchmark", "campaign"},
          {"campaign", campaign.name},
          {"trials", trials},
          {"trials_per_s_1worker", trials / one},
          {"trials_per_s_2workers", trials / two},
          {"scaling_efficiency", one / (2.0 * two)},
          {"jobs_identical", summary("jobs2") == reference},
          {"resume_identical", summary("killed") == reference},
          {"shards_identical", summary("shards") == reference}};
}

}  // namespace rotorguard::bench
