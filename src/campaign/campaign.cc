#include "rotorguard/campaign/campaign.h"

#include <fcntl.h>
#include <fmt/format.h>
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

#include "results_file.h"
#include "rotorguard/campaign/parallel.h"
#include "rotorguard/core/error.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/json_file.h"
#include "watchdog.h"

namespace rotorguard::campaign {

namespace fs = std::filesystem;

namespace {

std::uint64_t Fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string Hex(std::uint64_t v) { return fmt::format("{:016x}", v); }

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

/// An exclusive lock on a shard for the life of a run: a second run of the same shard (a resubmitted
/// task whose first copy still runs) is refused instead of appending the same trials twice.
class ShardLock {
 public:
  explicit ShardLock(const std::string& path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw io::InputFileError(path, "cannot open the shard's lock file");
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw std::invalid_argument(
          fmt::format("{} is held: this shard is already running (wait for it, or stop "
                      "it, then --resume)",
                      path));
    }
  }
  ~ShardLock() { ::close(fd_); }  // closing releases the lock
  ShardLock(const ShardLock&) = delete;
  ShardLock& operator=(const ShardLock&) = delete;

 private:
  int fd_ = -1;
};

std::string Dump(const nlohmann::json& j) { return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace); }

/// Runs the trial in this thread: its status, message and metrics.
nlohmann::json RecordTrial(const Campaign& campaign, int index, const std::map<std::string, std::string>& params) {
  nlohmann::json record;
  try {
    TrialOutcome r = campaign.run(index, params);
    bool finite = true;
    for (auto& [name, value] : r.metrics.items()) {
      if (value.is_number_float() && !std::isfinite(value.get<double>())) {
        finite = false;
        value = nullptr;  // JSON has no NaN
      }
    }
    record["status"] = finite ? "ok" : "diverged";
    record["message"] = finite ? r.message : "a metric is not finite" + (r.message.empty() ? "" : "; " + r.message);
    record["metrics"] = std::move(r.metrics);
  } catch (const std::exception& e) {
    record = {{"status", "error"}, {"message", e.what()}, {"metrics", nullptr}};
  } catch (...) {
    record = {{"status", "error"}, {"message", "an exception of unknown type"}, {"metrics", nullptr}};
  }
  return record;
}

/// Runs the trial in a child process under its wall-clock budget, `factor` times its simulated
/// time: the record it made, or a timeout or a crash recorded in its place.
nlohmann::json WatchedTrial(const Campaign& campaign, int index, const std::map<std::string, std::string>& params,
                            double factor) {
  double simulated_s = 0.0;  // unknown: no budget (a trial that cannot say will fail to run too)
  if (campaign.simulated_s) {
    try {
      simulated_s = campaign.simulated_s(index, params);
    } catch (const std::exception&) {
    }
  }
  const double budget_s = factor * simulated_s;
  internal::IsolatedRun run;
  try {
    run = internal::RunIsolated([&] { return Dump(RecordTrial(campaign, index, params)); }, budget_s);
  } catch (const std::exception& e) {
    return {{"status", "error"}, {"message", e.what()}, {"metrics", nullptr}};
  }
  switch (run.kind) {
    case internal::IsolatedRun::Kind::kFinished:
      return nlohmann::json::parse(run.text);
    case internal::IsolatedRun::Kind::kCrashed:
      return {{"status", "error"}, {"message", run.message}, {"metrics", nullptr}};
    case internal::IsolatedRun::Kind::kTimeout:
      break;
  }
  const std::string seed = params.count("seed") ? params.at("seed") : "?";
  const std::string reproduce = campaign.reproduce
                                    ? campaign.reproduce(index, params)
                                    : fmt::format("trial {} (seed {}) of campaign {}", index, seed, campaign.name);
  return {
      {"status", "timeout"},
      {"message", fmt::format("stopped after {:.1f} s of wall-clock time, its budget ({:g} x its {:g} s simulated); "
                              "seed {}; reproduce: {}",
                              run.wall_s, factor, simulated_s, seed, reproduce)},
      {"metrics", nullptr}};
}

}  // namespace

bool IsValidCampaignName(const std::string& name) {
  return !name.empty() && name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-") ==
                              std::string::npos;
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

std::string Shard::ResultsFileName() const {
  return count == 1 ? "results.jsonl" : fmt::format("results.shard-{}.jsonl", index);
}

std::string Shard::ManifestFileName() const {
  return count == 1 ? "manifest.json" : fmt::format("manifest.shard-{}.json", index);
}

std::pair<int, int> Shard::Range(int trials) const {
  const auto at = [&](int k) { return static_cast<int>(static_cast<long long>(trials) * k / count); };
  return {at(index), at(index + 1)};
}

CampaignRunSummary RunCampaign(const Campaign& campaign, const CampaignRunOptions& options) {
  const std::string shard_text = fmt::format("{}/{}", options.shard.index, options.shard.count);
  if (options.jobs < 1 || options.jobs > 256) {
    ThrowValidation("CampaignRunOptions", "jobs", options.jobs, "a count in [1, 256]");
  }
  if (!(options.trial_timeout_factor >= 0.0 && options.trial_timeout_factor <= 1e6)) {
    ThrowValidation("CampaignRunOptions", "trial_timeout_factor", options.trial_timeout_factor,
                    "a factor in [0, 1e6] (0: no watchdog)");
  }
  if (options.shard.count < 1 || options.shard.index < 0 || options.shard.index >= options.shard.count) {
    ThrowValidation("CampaignRunOptions", "shard", shard_text, "i/N with 0 <= i < N (shards count from 0)");
  }
  if (options.shard.count > campaign.trials) {
    ThrowValidation("CampaignRunOptions", "shard", shard_text,
                    fmt::format("at most as many shards as the campaign's {} trials", campaign.trials));
  }
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec || !fs::is_directory(options.out_dir)) {
    throw ValidationError("out_dir", fmt::format("CampaignRunOptions::out_dir: cannot create the folder '{}'{}",
                                                 options.out_dir, ec ? ": " + ec.message() : ""));
  }
  CampaignRunSummary summary;
  summary.results_file = (fs::path(options.out_dir) / options.shard.ResultsFileName()).string();
  summary.manifest_file = (fs::path(options.out_dir) / options.shard.ManifestFileName()).string();
  const auto [first, last] = options.shard.Range(campaign.trials);
  summary.trials = last - first;
  nlohmann::json manifest = {{"campaign", campaign.name},
                             {"spec", campaign.file},
                             {"spec_hash", campaign.hash},
                             {"version", options.version},
                             {"seed", campaign.seed},
                             {"trials_total", campaign.trials},
                             {"shard", shard_text},
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
    throw ValidationError("resume", fmt::format("CampaignRunOptions::out_dir '{}' already holds this shard's results; "
                                                "set CampaignRunOptions::resume to continue it, or choose another "
                                                "CampaignRunOptions::out_dir",
                                                options.out_dir));
  }
  if (exists) {
    if (!fs::exists(summary.manifest_file)) {
      throw io::CorruptFileError(summary.manifest_file, 0, "missing: the results cannot be matched to a spec");
    }
    const nlohmann::json old = io::ReadJsonObject(summary.manifest_file);
    for (const char* key : {"spec_hash", "version", "shard"}) {
      if (!old.contains(key) || old[key] != manifest[key]) {
        throw ValidationError("resume",
                              fmt::format("CampaignRunOptions::resume: {} records {} {}, this run has {}; resume only "
                                          "the same spec with the same "
                                          "program",
                                          summary.manifest_file, key, old.contains(key) ? old[key].dump() : "(none)",
                                          manifest[key].dump()));
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
  int errors = 0, timeouts = 0;
  std::exception_ptr write_error;
  ParallelFor(
      static_cast<int>(todo.size()), options.jobs,
      [&](int task) {
        const int index = todo[static_cast<std::size_t>(task)];
        const std::map<std::string, std::string> params = campaign.parameters(index);
        nlohmann::json line = {{"trial", index}, {"id", TrialId(params)}, {"params", params}};
        line.update(options.trial_timeout_factor > 0.0
                        ? WatchedTrial(campaign, index, params, options.trial_timeout_factor)
                        : RecordTrial(campaign, index, params));
        // Invalid UTF-8 in a message is replaced rather than thrown: the trial is recorded either way.
        const std::string text = Dump(line);
        const std::lock_guard<std::mutex> guard(mutex);
        if (line["status"] == "timeout") {
          ++timeouts;
        } else if (line["status"] != "ok") {
          ++errors;
        }
        if (write_error) return;  // the disk failed: no more lines; the run reports it below
        try {
          results.AppendLine(text);
        } catch (...) {
          write_error = std::current_exception();
        }
      },
      options.progress);
  if (write_error) std::rethrow_exception(write_error);  // the manifest stays unfinished: resume later
  summary.ran = static_cast<int>(todo.size());
  summary.errors = errors;
  summary.timeouts = timeouts;
  manifest["finished"] = UtcNow();
  io::WriteFileAtomically(summary.manifest_file, manifest.dump(2) + "\n");
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
    throw io::CorruptFileError(
        run.results_file, recorded.whole_size,
        fmt::format("{} of {} trials recorded after the run", recorded.trials.size(), campaign.trials));
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

}  // namespace rotorguard::campaign
