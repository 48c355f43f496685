#include "cli.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>
#include <utility>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::cli {

namespace fs = std::filesystem;

namespace {

/// Library errors name the option fields they reject ("CampaignRunOptions::jobs = 0 is invalid");
/// on the command line the user set them with these flags.
constexpr std::pair<const char*, const char*> kFlagOfField[] = {
    {"CampaignRunOptions::out_dir", "--out"},
    {"CampaignRunOptions::resume", "--resume"},
    {"CampaignRunOptions::jobs", "--jobs"},
    {"CampaignRunOptions::shard", "--shard"},
    {"SlurmScriptOptions::shards", "--shards"},
    {"SlurmScriptOptions::cpus_per_task", "--cpus-per-task"},
    {"SlurmScriptOptions::out_dir", "--out"},
    {"SlurmScriptOptions::partition", "--partition"},
    {"SlurmScriptOptions::time_limit", "--time"},
    {"FddCalibrationOptions::margin", "--margin"},
    {"CampaignRunOptions::trial_timeout_factor", "--trial-timeout"},
};

}  // namespace

int ExitCodeOf(const std::exception& e) {
  if (dynamic_cast<const UsageError*>(&e) != nullptr) return kUsage;
  if (dynamic_cast<const io::ConfigError*>(&e) != nullptr) return kUsage;
  if (dynamic_cast<const io::InputFileError*>(&e) != nullptr) return kUnreadable;
  if (dynamic_cast<const io::CorruptFileError*>(&e) != nullptr) return kUnreadable;
  // Library validation of values the loaders did not locate (a programming-interface misuse).
  if (dynamic_cast<const std::invalid_argument*>(&e) != nullptr) return kUsage;
  return kRunFailed;
}

std::string MessageOf(const std::exception& e) {
  std::string message = e.what();
  const auto replace_all = [&message](const std::string& from, const std::string& to) {
    for (std::size_t at = message.find(from); at != std::string::npos; at = message.find(from, at + to.size())) {
      message.replace(at, from.size(), to);
    }
  };
  for (const auto& [field, flag] : kFlagOfField) {
    replace_all(std::string(field) + " = ", std::string(flag) + " ");  // "--jobs 0 is invalid", as typed
    replace_all(field, flag);
  }
  return message;
}

std::uint64_t ParseUnsigned(const std::string& option, const std::string& text, std::uint64_t lo, std::uint64_t hi) {
  std::uint64_t v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || v < lo || v > hi) {
    throw UsageError(fmt::format("{}: '{}' is invalid; expected an integer in [{}, {}]", option, text, lo, hi));
  }
  return v;
}

double ParseFinite(const std::string& option, const std::string& text, double lo, double hi) {
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v) || v < lo || v > hi) {
    throw UsageError(
        fmt::format("{}: '{}' is invalid; expected a finite number in [{:g}, {:g}]", option, text, lo, hi));
  }
  return v;
}

int ParseJobs(const std::string& text) {
  if (text.empty()) return static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 256u));
  return static_cast<int>(ParseUnsigned("--jobs", text, 1, 256));
}

campaign::Shard ParseShard(const std::string& text) {
  const std::size_t slash = text.find('/');
  campaign::Shard s;
  const auto whole_int = [](const std::string& part, int* value) {
    const auto [ptr, ec] = std::from_chars(part.data(), part.data() + part.size(), *value);
    return !part.empty() && ec == std::errc() && ptr == part.data() + part.size();
  };
  if (slash == std::string::npos || !whole_int(text.substr(0, slash), &s.index) ||
      !whole_int(text.substr(slash + 1), &s.count)) {
    throw UsageError(fmt::format("--shard '{}' is invalid; expected i/N with 0 <= i < N", text));
  }
  if (s.count < 1 || s.index < 0 || s.index >= s.count) {
    throw UsageError(fmt::format("--shard '{}' is invalid; expected i/N with 0 <= i < N (shards count from 0)", text));
  }
  return s;
}

std::vector<std::string> SplitFields(const std::string& text, char separator) {
  std::vector<std::string> fields;
  for (std::size_t start = 0;;) {
    const std::size_t end = text.find(separator, start);
    fields.push_back(text.substr(start, end == std::string::npos ? end : end - start));
    if (end == std::string::npos) return fields;
    start = end + 1;
  }
}

std::vector<double> ParseFiniteList(const std::string& option, const std::string& text, double lo, double hi) {
  std::vector<double> values;
  for (const std::string& field : SplitFields(text, ',')) values.push_back(ParseFinite(option, field, lo, hi));
  return values;
}

std::vector<std::string> ParseWordList(const std::string& option, const std::string& text,
                                       const std::vector<std::string>& allowed) {
  const std::vector<std::string> words = SplitFields(text, ',');
  for (const std::string& word : words) {
    if (std::find(allowed.begin(), allowed.end(), word) == allowed.end()) {
      throw UsageError(fmt::format("{}: '{}' is invalid; expected a comma-separated list of {}", option, word,
                                   fmt::join(allowed, ", ")));
    }
  }
  return words;
}

std::vector<harness::Override> ParseOverrides(const std::vector<std::string>& sets) {
  std::vector<harness::Override> out;
  for (const std::string& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw UsageError(fmt::format("--set: '{}' is invalid; expected key.path=value", s));
    }
    out.emplace_back(s.substr(0, eq), s.substr(eq + 1));
  }
  return out;
}

void ScenarioArguments::Register(CLI::App* command) {
  app = command;
  command->add_option("scenario", path, "Scenario file (YAML), e.g. configs/scenarios/hover.yaml")->required();
  command->add_option("--set", sets,
                      "Override a value: key.path=value (e.g. duration_s=5, faults.0.rotor=2, vehicle.mass_kg=1.2); "
                      "any key `rotorguard keys` lists, written in the file or not. Repeatable.");
  command->add_option("--seed", seed_text, "Random seed, an integer in [0, 2^64-1] (overrides the file's seed)");
}

harness::Scenario ScenarioArguments::Load() const {
  const std::vector<harness::Override> overrides = ParseOverrides(sets);
  std::optional<std::uint64_t> seed;
  if (app->count("--seed") > 0) seed = ParseUnsigned("--seed", seed_text, 0, UINT64_MAX);
  harness::Scenario scenario = harness::LoadScenario(path, overrides);
  if (seed) scenario.seed = *seed;
  return scenario;
}

std::string SelfPath() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find this program's path (/proc/self/exe): " + ec.message());
  return self.string();
}

void CreateOutputFolder(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw UsageError(fmt::format("--out: cannot create folder '{}'{}", dir, ec ? ": " + ec.message() : ""));
  }
}

const char* const kTrialTimeoutHelp =
    "The watchdog: a trial that takes more than this many wall-clock seconds per simulated\n"
    "second is stopped and recorded as `timeout` (default 100; 0: trials unwatched, in-process)";

campaign::CampaignRunOptions CampaignRunOptionsOf(const std::string& out, const std::string& jobs_text,
                                                  const std::string& shard, bool resume,
                                                  const std::string& trial_timeout_text) {
  campaign::CampaignRunOptions o;
  if (!trial_timeout_text.empty())
    o.trial_timeout_factor = ParseFinite("--trial-timeout", trial_timeout_text, 0.0, 1e6);
  o.out_dir = out;
  o.jobs = ParseJobs(jobs_text);
  o.shard = ParseShard(shard);
  o.resume = resume;
  o.version = buildinfo::ProgramVersion();
  return o;
}

std::string ConfigPath(const std::string& relative) {
  const fs::path local = fs::path("configs") / relative;
  if (fs::exists(local)) return local.string();
  return (fs::path(ROTORGUARD_SOURCE_DIR) / "configs" / relative).string();
}

std::function<void(double)> FlightProgress(bool enabled, double duration_s) {
  if (!enabled || !::isatty(STDERR_FILENO)) return [](double) {};
  return [duration_s](double fraction) {
    const int width = 40;
    const int filled = static_cast<int>(fraction * width + 0.5);
    std::fprintf(stderr, "\r[%s%s] %3.0f%%  t = %.1f / %.1f s", std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), 100.0 * fraction, fraction * duration_s, duration_s);
    if (fraction >= 1.0) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  };
}

std::function<void(int, int)> CountProgress(const char* what) {
  const bool tty = ::isatty(STDERR_FILENO);
  return [tty, what](int done, int total) {
    if (!tty) return;
    std::fprintf(stderr, "\r%s %d / %d", what, done, total);
    if (done == total) std::fprintf(stderr, "\n");
  };
}

std::function<void(int, int)> EtaProgress(const char* what) {
  const bool tty = ::isatty(STDERR_FILENO);
  const Stopwatch clock;
  return [tty, what, clock](int done, int total) {
    if (!tty) return;
    const double elapsed = clock.seconds();
    const double eta = done > 0 ? elapsed * (total - done) / done : 0.0;
    std::fprintf(stderr, "\r%s %d / %d, %.0f s elapsed, ETA %.0f s   ", what, done, total, elapsed, eta);
    if (done == total) std::fprintf(stderr, "\n");
  };
}

}  // namespace rotorguard::cli
