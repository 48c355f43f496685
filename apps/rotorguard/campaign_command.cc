// rotorguard campaign run|slurm|merge: Monte Carlo campaigns in crash-safe, resumable shards.
#include <fmt/format.h>

#include <filesystem>

#include "cli.h"
#include "rotorguard/campaign_kinds/registry.h"
#include "rotorguard/campaign/merge.h"
#include "rotorguard/campaign/registry.h"
#include "rotorguard/campaign/slurm.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/report_html.h"
#include "rotorguard/record/report.h"

namespace rotorguard::cli {

namespace fs = std::filesystem;

namespace {

class CampaignCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* campaign = app->add_subcommand("campaign",
                                             "Monte Carlo campaigns: sweeps over a scenario's keys, run in\n"
                                             "crash-safe, resumable shards and merged (docs/campaigns.md).");
    campaign->require_subcommand(1);
    run_ = campaign->add_subcommand(
        "run",
        "Run a campaign spec's trials (or one shard of them): each finished trial appends a line to\n"
        "DIR/results.jsonl (results.shard-i.jsonl), synced; DIR/manifest.json records the run.\n"
        "Exit 0 when every trial ran (a trial's crash or error is recorded, not fatal).");
    run_->add_option("spec", spec_, "Campaign spec (YAML), e.g. configs/campaigns/ftc_demo.yaml")->required();
    run_->add_option("--out", out_, "Results folder")->required();
    run_->add_option("--jobs", jobs_text_, "Worker threads (default: the number of cores)");
    run_->add_option("--shard", shard_, "Run shard i of N (i/N, 0 <= i < N; default 0/1: all)");
    run_->add_flag("--resume", resume_, "Continue the results in --out: skip finished trials");
    run_->add_option("--trial-timeout", trial_timeout_, kTrialTimeoutHelp);
    run_->add_flag("--quiet,-q", quiet_, "No progress line");
    slurm_ = campaign->add_subcommand(
        "slurm",
        "Write DIR/campaign.sbatch: a Slurm job array whose task i runs shard i/N of the spec into DIR\n"
        "(with --resume, so resubmitting it or its failed tasks is safe). Submit it with sbatch;\n"
        "merge DIR when every task is done.");
    slurm_->add_option("spec", spec_, "Campaign spec (YAML)")->required();
    slurm_->add_option("--shards", shards_text_, "Array tasks, one shard each")->required();
    slurm_->add_option("--out", out_, "Results folder (on a file system every node sees)")->required();
    slurm_->add_option("--cpus-per-task", cpus_text_, "CPUs per task, and its --jobs (default 1)");
    slurm_->add_option("--partition", partition_, "Slurm partition (default: the cluster's)");
    slurm_->add_option("--time", time_, "Slurm time limit per task, e.g. 02:00:00");
    merge_ = campaign->add_subcommand(
        "merge",
        "Join the shards in the given folders (every trial exactly once, one spec, one program) and\n"
        "write summary.json, summary.md and (with the report viewer) summary.html.");
    merge_->add_option("dirs", merge_dirs_, "Results folders")->required();
    merge_->add_option("--out", merge_out_, "Where to write the summary (default: the first folder)");
    return campaign;
  }

  int Execute() override {
    if (*run_) return Run();
    if (*slurm_) return Slurm();
    return Merge();
  }

 private:
  int Run() {
    const campaign::Campaign spec = campaign::LoadCampaign(spec_, benchmarks::CampaignKinds());
    campaign::CampaignRunOptions o = CampaignRunOptionsOf(out_, jobs_text_, shard_, resume_, trial_timeout_);
    if (!quiet_) o.progress = EtaProgress("trials");
    const campaign::CampaignRunSummary r = campaign::RunCampaign(spec, o);
    fmt::print("campaign          {} (spec {})\n", spec.name, spec.hash);
    fmt::print("shard             {}/{}: {} trials, {} already done, {} run, {} error or diverged, {} timed out\n",
               o.shard.index, o.shard.count, r.trials, r.skipped, r.ran, r.errors, r.timeouts);
    fmt::print("results           {}\n", r.results_file);
    return kOk;
  }

  int Slurm() {
    const campaign::Campaign spec = campaign::LoadCampaign(spec_, benchmarks::CampaignKinds());
    campaign::SlurmScriptOptions o;
    o.shards = static_cast<int>(ParseUnsigned("--shards", shards_text_, 1, 1'000'000));
    o.cpus_per_task = static_cast<int>(ParseUnsigned("--cpus-per-task", cpus_text_, 1, 256));
    o.out_dir = out_;
    o.rotorguard = fs::read_symlink("/proc/self/exe").string();
    o.partition = partition_;
    o.time_limit = time_;
    const std::string script = campaign::SlurmArrayScript(spec, o);
    fs::create_directories(out_);
    const std::string path = (fs::path(out_) / "campaign.sbatch").string();
    io::WriteFileAtomically(path, script);
    fmt::print("campaign          {} (spec {}): {} trials in {} array tasks\n", spec.name, spec.hash, spec.trials,
               o.shards);
    fmt::print("script            {}\n", path);
    fmt::print("submit            sbatch {}\n", path);
    return kOk;
  }

  int Merge() {
    const std::string out = merge_out_.empty() ? merge_dirs_.front() : merge_out_;
    const nlohmann::json s = campaign::MergeCampaign(merge_dirs_, out, benchmarks::CampaignKinds());
    fmt::print("campaign          {}: {} trials merged\n", s["campaign"].get<std::string>(), s["trials"].get<int>());
    fmt::print("summary           {}\n", (fs::path(out) / "summary.json").string());
    fmt::print("                  {}\n", (fs::path(out) / "summary.md").string());
    if (s.contains("bench")) {  // a benchmark's campaign: its own result and tables too
      fmt::print("                  {}\n", (fs::path(out) / "bench.json").string());
      fmt::print("                  {}\n", (fs::path(out) / "bench.md").string());
    }
    if (io::HasViewer()) {  // the report viewer's page of any benchmark result
      const std::string html = (fs::path(out) / "summary.html").string();
      if (s.contains("bench")) {
        record::WriteBenchReport(s["bench"]["benchmark"].get<std::string>(), s["bench"], html);
      } else {
        record::WriteBenchReport("campaign " + s["campaign"].get<std::string>(), s, html);
      }
      fmt::print("                  {}\n", html);
    }
    return kOk;
  }

  CLI::App *run_ = nullptr, *slurm_ = nullptr, *merge_ = nullptr;
  std::string spec_, out_, jobs_text_, shard_ = "0/1", merge_out_;
  std::string shards_text_, cpus_text_ = "1", partition_, time_;
  bool resume_ = false, quiet_ = false;
  std::string trial_timeout_;
  std::vector<std::string> merge_dirs_;
};

}  // namespace

std::unique_ptr<Command> MakeCampaignCommand() { return std::make_unique<CampaignCommand>(); }

}  // namespace rotorguard::cli
