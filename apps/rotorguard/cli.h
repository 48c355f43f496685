#pragma once
// The command line's shared parts: exit codes, strict argument parsing, progress lines, and the
// Command interface each subcommand file implements (run, report, validate, fdd-calibrate, bench,
// campaign). Commands parse, call the libraries and print; no algorithm lives here.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "rotorguard/campaign/campaign.h"
#include "rotorguard/core/config_schema.h"
#include "rotorguard/harness/flight_recorder.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/harness/sitl.h"
#include "rotorguard/harness/stack_observer.h"
#include "rotorguard/runtime/realtime.h"

namespace rotorguard::cli {

/// The documented exit codes (docs/cli.md).
enum ExitCode : int { kOk = 0, kRunFailed = 1, kUsage = 2, kUnreadable = 3, kInfeasible = 4 };

/// A command-line value that is not acceptable: exit 2 with this message.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A subcommand: it adds itself and its options to the parser, and runs once the parser chose it.
class Command {
 public:
  virtual ~Command() = default;
  /// Adds the command to `app`; returns its subcommand, which the parser marks as chosen.
  virtual CLI::App* Register(CLI::App* app) = 0;
  /// Runs the parsed command; returns its exit code. Throws for errors (ExitCodeOf maps them).
  virtual int Execute() = 0;
};

std::unique_ptr<Command> MakeRunCommand();
std::unique_ptr<Command> MakeReportCommand();
std::unique_ptr<Command> MakeValidateCommand();
std::unique_ptr<Command> MakeFddCalibrateCommand();
std::unique_ptr<Command> MakeBenchCommand();
std::unique_ptr<Command> MakeCampaignCommand();
std::unique_ptr<Command> MakeKeysCommand();
std::unique_ptr<Command> MakeSitlCommand();
std::unique_ptr<Command> MakeNodeCommand();
std::unique_ptr<Command> MakeReplayCommand();

// ---- ROS (ros_support.cc; each throws UsageError naming the option in a build without ROS).
/// Whether this rotorguard was built with ROS 1 (ROTORGUARD_ROS).
bool BuiltWithRos();
/// --bag PATH: UsageError when it cannot be written (its folder does not exist).
void CheckBagPath(const std::string& path);
/// --bag PATH: a recorder of the flight's sensor messages and cycles.
std::unique_ptr<harness::StackObserver> MakeBagRecorder(const std::string& path);
/// sitl --ros: the stack's link over ROS through the master `master_uri` ("" : ROS_MASTER_URI),
/// the node started from sitl->node_command (with --ros added) unless `external_node`.
void UseRosLink(harness::SitlOptions* sitl, const std::string& master_uri, bool external_node = false);
/// node --ros: flies the node over ROS until told to stop; `args` are the ROS remappings
/// (from:=to) given after the options; `bag` ("": none) records its intake and cycles.
void RunNodeOverRos(const harness::Scenario& scenario, const std::string& master_uri, const std::vector<std::string>& args,
                    bool start_now, const std::string& bag, const runtime::RealtimeOptions& realtime);

/// The exit code of an error, by its type (UsageError, io::ConfigError: 2; io::InputFileError,
/// io::CorruptFileError: 3; std::invalid_argument: 2; anything else: 1), and its message with the
/// option fields library errors name turned into the flags that set them.
int ExitCodeOf(const std::exception& error);
std::string MessageOf(const std::exception& error);

// ---- Strict argument parsing: each throws UsageError naming the option, the text and what was expected.
/// An unsigned integer in [lo, hi]: digits only, no sign, no exponent.
std::uint64_t ParseUnsigned(const std::string& option, const std::string& text, std::uint64_t lo, std::uint64_t hi);
/// A finite number in [lo, hi]; rejects nan, inf, 1e999 (overflow) and trailing text.
double ParseFinite(const std::string& option, const std::string& text, double lo, double hi);
/// --jobs: worker threads, the number of cores when `text` is empty.
int ParseJobs(const std::string& text);
/// --shard "i/N" with 0 <= i < N.
campaign::Shard ParseShard(const std::string& text);
/// The fields of `text` between `separator`s, empty ones included ("a,,b" has three).
std::vector<std::string> SplitFields(const std::string& text, char separator);
/// A comma-separated list of finite numbers, each in [lo, hi] (ParseFinite's rules).
std::vector<double> ParseFiniteList(const std::string& option, const std::string& text, double lo, double hi);
/// A comma-separated list of words, each one of `allowed`.
std::vector<std::string> ParseWordList(const std::string& option, const std::string& text,
                                       const std::vector<std::string>& allowed);
/// The value of a named enum (core/config_schema.h's NamesOf) that `text` names.
template <NamedEnum E>
E ParseName(const std::string& option, const std::string& text) {
  if (const std::optional<E> value = FromName<E>(text)) return *value;
  throw UsageError(
      fmt::format("{} '{}' is invalid; expected one of: {}", option, text, fmt::join(NameList<E>(), ", ")));
}
/// --set key.path=value, repeatable.
std::vector<harness::Override> ParseOverrides(const std::vector<std::string>& sets);

/// The scenario a flying command takes (run, sitl, node): the file, --set overrides and --seed.
struct ScenarioArguments {
  std::string path, seed_text;
  std::vector<std::string> sets;
  CLI::App* app = nullptr;
  /// Adds the positional scenario and --set and --seed to `command`.
  void Register(CLI::App* command);
  /// The scenario as given (LoadScenario's errors, UsageError for a bad --set or --seed).
  harness::Scenario Load() const;
};

/// Creates the folder `dir` (and its parents); UsageError naming --out when it cannot.
void CreateOutputFolder(const std::string& dir);
/// This program's own path (software in the loop starts its node as this program with another
/// command). Throws std::runtime_error when /proc/self/exe cannot be read.
std::string SelfPath();

/// The campaign options a command line gives (campaign run and the benchmarks that run as campaigns).
campaign::CampaignRunOptions CampaignRunOptionsOf(const std::string& out, const std::string& jobs_text,
                                                  const std::string& shard, bool resume,
                                                  const std::string& trial_timeout_text);
/// --trial-timeout's help, shared by campaign run and the benchmarks that run as campaigns.
extern const char* const kTrialTimeoutHelp;

/// A configs/ file: relative to the working directory when it has one, else the source tree's.
std::string ConfigPath(const std::string& relative);

// ---- Progress on a terminal's stderr (nothing when stderr is not a terminal).
/// "\r[####    ]  42%  t = 4.2 / 10.0 s" for a flight of `duration_s`.
std::function<void(double)> FlightProgress(bool enabled, double duration_s);
/// "\r<what> done / total", for benchmarks that report whole units of work.
std::function<void(int, int)> CountProgress(const char* what);
/// "\r<what> done / total, elapsed, ETA", for long runs of equal units of work.
std::function<void(int, int)> EtaProgress(const char* what);

/// The run's table: outcome, metrics, faults, detection, re-planning, flight modes and the files.
void PrintRunSummary(const harness::RunSummary& summary, const std::string& out_dir,
                     const harness::FlightRecorderOptions& files);

}  // namespace rotorguard::cli
