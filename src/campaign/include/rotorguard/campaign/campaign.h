#pragma once
/// The campaign engine (docs/campaigns.md): `trials` numbered trials, each a pure function of its
/// index, run on worker threads in shards; it knows no benchmark. What the trials are comes from
/// whoever builds the Campaign (a scenario sweep, a benchmark: registry.h), as Drake's
/// MonteCarloSimulation takes a factory. Every trial's seed is derived counter-style from the
/// campaign's seed and the trial's index, so that results depend on neither the number of worker
/// threads nor the sharding.
///
/// Each finished trial appends one whole JSON line to DIR/results.jsonl (or results.shard-i.jsonl),
/// flushed and synced before the next: a kill loses at most the trials in flight, and a resume
/// discards a partial last line and skips what is done. merge.h joins the shards.
#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace rotorguard::campaign {

/// Whether `name` may name a campaign (its files and Slurm jobs): letters, digits, '_', '.', '-'.
bool IsValidCampaignName(const std::string& name);

/// The trial's id: a 64-bit FNV-1a hash of its resolved parameters, in hex.
std::string TrialId(const std::map<std::string, std::string>& parameters);
/// 64-bit FNV-1a of `text`, in hex: campaign and trial fingerprints.
std::string Fingerprint(const std::string& text);

/// Why a recorded trial failed, as the benchmarks report it: its message when it ran (why the flight
/// failed, "" for none), "error: ..." or "diverged: ..." when it did not.
std::string TrialFailure(const nlohmann::json& record);

/// What one trial recorded besides its parameters: its metrics (numbers, booleans or null, keyed by
/// name; or a word, such as the decision a flight took, which summaries give no statistics for) and
/// a message (why a flight failed; "" for none).
struct TrialOutcome {
  nlohmann::json metrics = nlohmann::json::object();
  std::string message;
};

/// What the engine runs: `trials` numbered trials, each a pure function of its index. A scenario
/// sweep is one kind; the benchmarks' trial sets (`bench ftc|nav|mars`) are others, and all of them
/// shard, resume, merge and run on Slurm alike (registry.h).
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
  /// Runs trial `index`; thread-safe. An exception is recorded as the trial's error. Under the
  /// watchdog (CampaignRunOptions::trial_timeout_factor) it runs in a child process: what it
  /// changes besides its result is lost.
  std::function<TrialOutcome(int index, const std::map<std::string, std::string>& parameters)> run;
  /// Trial `index`'s simulated time [s], from which the watchdog sets its wall-clock budget; none
  /// (or one that throws): the trial runs without a budget.
  std::function<double(int index, const std::map<std::string, std::string>& parameters)> simulated_s;
  /// The command that flies trial `index` alone, named when it times out; none: its index and seed.
  std::function<std::string(int index, const std::map<std::string, std::string>& parameters)> reproduce;
  /// A benchmark's campaign: {"name": KIND, "options": {...}}, recorded in the manifests so that a
  /// merge also writes the kind's own result and tables (registry.h). Null for a scenario sweep.
  nlohmann::json bench;
};

/// Which trials a shard runs: shard `index` of `count` takes a contiguous range.
struct Shard {
  int index = 0;
  int count = 1;
  std::pair<int, int> Range(int trials) const;  ///< [first, last)
  /// The shard's files in its folder: results.jsonl and manifest.json for the whole campaign,
  /// results.shard-i.jsonl and manifest.shard-i.json for one of several.
  std::string ResultsFileName() const;
  std::string ManifestFileName() const;
};

struct CampaignRunOptions {
  std::string out_dir;  ///< the shard's folder, created when missing
  int jobs = 1;         ///< worker threads, in [1, 256]
  Shard shard;          ///< 0 <= index < count <= the campaign's trials
  bool resume = false;  ///< continue the results already in out_dir (else they are an error)
  /// The per-trial watchdog, in [0, 1e6]: each trial runs in a child process and is stopped once
  /// it has taken this many wall-clock seconds per simulated second (Campaign::simulated_s),
  /// recorded with status `timeout`; a trial whose process crashes is recorded as an `error`, and
  /// the shard goes on either way. 0: the trials run in the worker threads, unwatched.
  double trial_timeout_factor = 100.0;
  std::string version;  ///< the program's version and revision, recorded and checked
  std::function<void(int done, int total)> progress;
};

struct CampaignRunSummary {
  int trials = 0;   ///< in the shard
  int skipped = 0;  ///< already done (resume)
  int ran = 0;
  int errors = 0;    ///< status error or diverged
  int timeouts = 0;  ///< status timeout: stopped by the watchdog
  std::string results_file, manifest_file;
};

/// Runs the shard's trials not yet recorded. Throws ValidationError naming the option (a bad count
/// or shard, an existing results file without `resume`, a resume against another spec or
/// version), std::invalid_argument when the shard is already running in another process, io::InputFileError or
/// io::CorruptFileError for unreadable or damaged results, and leaves every existing file as it was; an I/O failure
/// while appending is rethrown once the trials in flight are done (the manifest stays unfinished: resume later).
CampaignRunSummary RunCampaign(const Campaign& campaign, const CampaignRunOptions& options);

/// Runs `options.shard` of `campaign` (RunCampaign) and, when that is the whole campaign, returns
/// every trial's record in trial order; nullopt for one shard of several (merge the folders when all
/// are done). An empty `options.out_dir` runs in a temporary folder, removed afterwards.
std::optional<std::vector<nlohmann::json>> RunCampaignRecords(const Campaign& campaign, CampaignRunOptions options);
/// The whole campaign on `jobs` threads in a temporary folder: every trial's record, in trial order.
std::vector<nlohmann::json> RunWholeCampaign(const Campaign& campaign, int jobs,
                                             const std::function<void(int, int)>& progress = {});

}  // namespace rotorguard::campaign
