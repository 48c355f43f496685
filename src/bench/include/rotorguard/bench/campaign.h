#pragma once
/// Monte Carlo campaigns (docs/campaigns.md): a spec names a base scenario and sweeps over its keys
/// (a grid, and random draws per trial); every trial is one run of the scenario with the sweep's
/// values set (as `--set` would) and its own seed, derived counter-style from the campaign's seed
/// and the trial's index, so that results depend on neither the number of worker threads nor the
/// sharding.
///
/// Each finished trial appends one whole JSON line to DIR/results.jsonl (or results.shard-i.jsonl),
/// flushed and synced before the next: a kill loses at most the trials in flight, and a resume
/// discards a partial last line and skips what is done. `MergeCampaign` joins the shards, refusing
/// gaps, duplicates and mismatched specs or versions, and writes summary.json and summary.md.
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rotorguard::bench {

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

/// Whether `name` may name a campaign (its files and Slurm jobs): letters, digits, '_', '.', '-'.
bool IsValidCampaignName(const std::string& name);

/// Loads and validates a spec. Throws io::ConfigError naming file, line and key (an unknown key,
/// an empty sweep, a sweep over a key the scenario does not have, an unknown metric) or
/// io::InputFileError.
CampaignSpec LoadCampaignSpec(const std::string& path);

/// Trial `index`'s resolved parameters: every swept key's value (YAML text) and "seed".
std::map<std::string, std::string> TrialParameters(const CampaignSpec& spec, int index);
/// The trial's id: a 64-bit FNV-1a hash of its resolved parameters, in hex.
std::string TrialId(const std::map<std::string, std::string>& parameters);
/// 64-bit FNV-1a of `text`, in hex: campaign and trial fingerprints.
std::string Fingerprint(const std::string& text);

/// Why a recorded trial failed, as the benchmarks report it: its message when it ran (why the flight
/// failed, "" for none), "error: ..." or "diverged: ..." when it did not.
std::string TrialFailure(const nlohmann::json& record);

/// What one trial recorded besides its parameters: its metrics (numbers, booleans or null, keyed by
/// name) and a message (why a flight failed; "" for none).
struct TrialOutcome {
  nlohmann::json metrics = nlohmann::json::object();
  std::string message;
};

/// What the engine runs: `trials` numbered trials, each a pure function of its index. A scenario
/// sweep (ScenarioCampaign) is one kind; the benchmarks' trial sets (`bench ftc|nav|mars`,
/// bench_campaigns.h) are others, and all of them shard, resume, merge and run on Slurm alike.
struct Campaign {
  std::string name;  ///< letters, digits, '_', '.', '-': it names files and Slurm jobs
  std::string file;  ///< the spec file that defines it ("" when built in code: no Slurm script)
  std::string hash;  ///< the fingerprint of everything the trials depend on: what shards must share
  std::uint64_t seed = 1;
  int trials = 0;
  /// Parameters whose values group the summary's rows (a grid's keys), in order.
  std::vector<std::string> group_keys;
  /// The metrics the summary reports, in order (a trial may record more).
  std::vector<std::string> metrics;
  /// Trial `index`'s resolved parameters (with "seed"): its identity, recorded with its results.
  std::function<std::map<std::string, std::string>(int index)> parameters;
  /// Runs trial `index`; thread-safe. An exception is recorded as the trial's error.
  std::function<TrialOutcome(int index, const std::map<std::string, std::string>& parameters)> run;
  /// A benchmark's campaign: {"name": "ftc"|"nav"|"mars", "options": {...}}, recorded in the
  /// manifests so that a merge also writes the benchmark's own tables. Null for a scenario sweep.
  nlohmann::json bench;
};

/// The spec's trials: each one run of the scenario with its parameters set (as `--set` would),
/// recording the spec's metrics from RunSummary::ToJson.
Campaign ScenarioCampaign(const CampaignSpec& spec);

/// Which trials a shard runs: shard `index` of `count` takes a contiguous range.
struct Shard {
  int index = 0;
  int count = 1;
  /// "i/N" with 0 <= i < N. Throws std::invalid_argument naming the text.
  static Shard Parse(const std::string& text);
  std::pair<int, int> Range(int trials) const;  ///< [first, last)
};

struct CampaignRunOptions {
  std::string out_dir;
  int jobs = 1;
  Shard shard;
  bool resume = false;
  std::string version;  ///< the program's version and revision, recorded and checked
  std::function<void(int done, int total)> progress;
};

struct CampaignRunSummary {
  int trials = 0;    ///< in the shard
  int skipped = 0;   ///< already done (resume)
  int ran = 0;
  int errors = 0;    ///< status error or diverged
  std::string results_file, manifest_file;
};

/// Runs the shard's trials not yet recorded. Throws std::invalid_argument for a bad request (an
/// existing results file without `resume`, a resume against another spec or version, the shard
/// already running in another process), io::InputFileError or io::CorruptFileError for unreadable
/// or damaged results, and leaves every existing file as it was; an I/O failure while appending
/// is rethrown once the trials in flight are done (the manifest stays unfinished: resume later).
CampaignRunSummary RunCampaign(const Campaign& campaign, const CampaignRunOptions& options);

struct SlurmScriptOptions {
  int shards = 1;              ///< array tasks, one shard each, in [1, trials]
  int cpus_per_task = 1;       ///< --cpus-per-task, and each task's --jobs, in [1, 256]
  std::string out_dir;         ///< the results folder (made absolute in the script)
  std::string rotorguard;      ///< the program each task runs (absolute path)
  std::string partition;       ///< "" for the cluster's default
  std::string time_limit;      ///< Slurm's --time ("" for the partition's default)
};

/// An `sbatch --array` script: task i runs `campaign run SPEC --shard i/N --resume` into the
/// results folder, so resubmitting the script, or only its failed tasks, is safe. Throws
/// std::invalid_argument naming a bad option.
std::string SlurmArrayScript(const Campaign& campaign, const SlurmScriptOptions& options);

/// Every trial record of a whole campaign, in trial order, read from `dirs` (every shard's manifest
/// and results) once checked to form the campaign exactly once, with one spec and one version;
/// `manifest` receives the first shard's manifest. Throws io::CorruptFileError, io::InputFileError
/// or std::invalid_argument naming the file.
std::vector<nlohmann::json> ReadCampaignRecords(const std::vector<std::string>& dirs, nlohmann::json* manifest);

/// Joins the results of `dirs` (ReadCampaignRecords) and writes summary.json and summary.md into
/// `out_dir`; for a benchmark's campaign also the benchmark's result, bench.json and bench.md
/// (bench_campaigns.h). Returns the summary, with the benchmark's result under "bench" when there
/// is one.
nlohmann::json MergeCampaign(const std::vector<std::string>& dirs, const std::string& out_dir);

/// Runs `options.shard` of `campaign` (RunCampaign) and, when that is the whole campaign, returns
/// every trial's record in trial order; nullopt for one shard of several (merge the folders when all
/// are done). An empty `options.out_dir` runs in a temporary folder, removed afterwards.
std::optional<std::vector<nlohmann::json>> RunCampaignRecords(const Campaign& campaign, CampaignRunOptions options);
/// The whole campaign on `jobs` threads in a temporary folder: every trial's record, in trial order.
std::vector<nlohmann::json> RunWholeCampaign(const Campaign& campaign, int jobs,
                                             const std::function<void(int, int)>& progress = {});

/// `rotorguard bench campaign`: runs `spec` in `work_dir` (which it fills) with one worker and
/// with two, then a kill-and-resume (a run cut after a third of its trials, mid-line, unfinished,
/// then resumed) and 4 shards, and compares their merged summaries with the uninterrupted one's:
/// {trials, trials_per_s_1worker, trials_per_s_2workers, scaling_efficiency (the 2-worker rate over
/// twice the 1-worker rate), resume_identical, shards_identical, jobs_identical}.
nlohmann::json RunCampaignBenchmark(const Campaign& campaign, const std::string& work_dir, const std::string& version);

/// The source revision this program was built from (git's short hash; "unknown" outside a clone).
std::string GitRevision();

/// Wilson score interval of `successes` in `n` at 95 %: [lo, hi] ([0, 1] for n = 0).
std::pair<double, double> WilsonInterval(int successes, int n);

}  // namespace rotorguard::bench
