// Scenario sweeps run by the campaign engine (campaign_kinds/scenario_sweep.h, campaign/campaign.h):
// trial parameters and seeds, crash-safe results, resume, shards and the merge's checks, on real
// flights. The oracle for "results do not depend on how they were run" is a byte
// comparison of merged summaries.

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "rotorguard/benchmarks/campaign_bench.h"
#include "rotorguard/campaign_kinds/registry.h"
#include "rotorguard/campaign_kinds/scenario_sweep.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/merge.h"
#include "rotorguard/campaign/slurm.h"
#include "rotorguard/campaign/statistics.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "test_util.h"

namespace rotorguard::benchmarks {
namespace {

namespace fs = std::filesystem;

std::string ScenarioPath(const std::string& name) {
  return testing::SourcePath("configs/scenarios/" + name);
}

class Campaigns : public testing::TempFolderTest {
 protected:
  /// A spec of 6 short trials: the nominal controller losing a motor or a propeller in hover, over
  /// the rotor, with random onsets, 1.5 s each.
  std::string Spec(const std::string& extra = "", const std::string& name = "spec.yaml") {
    return Write(name, "name: test_campaign\n"
                       "scenario: " + ScenarioPath("hover_motor_stop_nominal.yaml") + "\n"
                       "seed: 7\n"
                       "repeats: 2\n"
                       "grid:\n"
                       "  duration_s: [1.5]\n"
                       "  faults.0.rotor: [0, 1, 2]\n"
                       "random:\n"
                       "  faults.0.onset.at_time_s: {uniform: [0.5, 1.0]}\n"
                       "  faults.0.kind: {choice: [motor_stop, propeller_loss]}\n"
                       "metrics: [success, crashed, tracking_rmse_m, max_tilt_rad]\n" + extra);
  }
  campaign::CampaignRunSummary Run(const CampaignSpec& spec, const std::string& out, int jobs = 1, campaign::Shard shard = {},
                         bool resume = false) {
    campaign::CampaignRunOptions o;
    o.out_dir = (dir_ / out).string();
    o.jobs = jobs;
    o.shard = shard;
    o.resume = resume;
    o.version = "test";
    return campaign::RunCampaign(ScenarioCampaign(spec), o);
  }
  std::string Merge(const std::vector<std::string>& outs, const std::string& into) {
    std::vector<std::string> dirs;
    for (const std::string& o : outs) dirs.push_back((dir_ / o).string());
    campaign::MergeCampaign(dirs, (dir_ / into).string(), CampaignKinds());
    return io::ReadFile((dir_ / into / "summary.json").string()) + io::ReadFile((dir_ / into / "summary.md").string());
  }
};

TEST_F(Campaigns, TrialsCoverTheGridWithCounterStyleSeedsAndDraws) {
  const CampaignSpec spec = LoadCampaignSpec(Spec());
  ASSERT_EQ(spec.trials(), 6);  // 1 x 3 grid points, 2 repeats each
  std::set<std::string> rotors, ids;
  for (int i = 0; i < spec.trials(); ++i) {
    const auto p = TrialParameters(spec, i);
    EXPECT_EQ(p.at("faults.0.rotor"), std::to_string(i / 2));  // the last key varies fastest, repeats inner
    // The campaign's own stream: no other campaign or benchmark flies these seeds.
    EXPECT_EQ(p.at("seed"), std::to_string(TrialSeed(7, "campaign " + spec.name, static_cast<std::uint64_t>(i))));
    const double onset = std::stod(p.at("faults.0.onset.at_time_s"));
    EXPECT_GE(onset, 0.5);
    EXPECT_LT(onset, 1.0);
    EXPECT_TRUE(p.at("faults.0.kind") == "motor_stop" || p.at("faults.0.kind") == "propeller_loss");
    EXPECT_EQ(TrialParameters(spec, i), p);  // a pure function of the spec and the index
    ids.insert(campaign::TrialId(p));
    rotors.insert(p.at("faults.0.rotor"));
  }
  EXPECT_EQ(ids.size(), 6u);
  EXPECT_EQ(rotors.size(), 3u);
}

TEST(ShippedCampaigns, NoEvaluationSetFliesAVehicleOfTheCalibrationSets) {
  // The shipped thresholds are calibrated on fdd_calibration_* and judged on fdd_far_* (docs/fdd.md,
  // "Calibration and evaluation"): a judged flight must be a vehicle the calibration never saw. A
  // spec copied under the name of another, or a stream shared again, fails here.
  std::set<std::string> calibration;
  std::map<std::string, std::set<std::string>> evaluation;
  for (const auto& e : fs::directory_iterator(testing::SourcePath("configs/campaigns"))) {
    const std::string stem = e.path().stem().string();
    const bool cal = stem.rfind("fdd_calibration_", 0) == 0, far = stem.rfind("fdd_far_", 0) == 0;
    if (!cal && !far) continue;
    const CampaignSpec spec = LoadCampaignSpec(e.path().string());
    std::set<std::string> seeds;
    for (int i = 0; i < spec.trials(); ++i) seeds.insert(TrialParameters(spec, i).at("seed"));
    EXPECT_EQ(seeds.size(), static_cast<std::size_t>(spec.trials())) << stem << ": every trial its own vehicle";
    if (cal) {
      calibration.insert(seeds.begin(), seeds.end());
    } else {
      EXPECT_GE(spec.trials(), 1000) << stem;
      evaluation[stem] = std::move(seeds);
    }
  }
  EXPECT_GE(calibration.size(), 1000u);
  EXPECT_GE(evaluation.size(), 6u);
  for (const auto& [name, seeds] : evaluation) {
    for (const std::string& s : seeds) EXPECT_EQ(calibration.count(s), 0u) << name << " flies seed " << s;
  }
}

TEST_F(Campaigns, JobsAndShardsGiveByteIdenticalSummaries) {
  const CampaignSpec spec = LoadCampaignSpec(Spec());
  const campaign::CampaignRunSummary one = Run(spec, "one", 1);
  EXPECT_EQ(one.ran, 6);
  EXPECT_EQ(one.errors, 0);
  Run(spec, "two", 2);
  for (int i = 0; i < 4; ++i) Run(spec, "shards", 1, campaign::Shard{i, 4});
  const std::string reference = Merge({"one"}, "m1");
  EXPECT_EQ(Merge({"two"}, "m2"), reference);
  EXPECT_EQ(Merge({"shards"}, "m4"), reference);
  // The summary holds what the trials measured: the nominal controller crashes after a motor stop.
  const nlohmann::json s = nlohmann::json::parse(io::ReadFile((dir_ / "m1" / "summary.json").string()));
  EXPECT_EQ(s["trials"].get<int>(), 6);
  EXPECT_EQ(s["overall"]["metrics"]["success"]["n"].get<int>(), 6);
  const auto wilson = s["overall"]["metrics"]["success"]["wilson95"];
  EXPECT_LE(wilson[0].get<double>(), s["overall"]["metrics"]["success"]["rate"].get<double>());
  EXPECT_GE(wilson[1].get<double>(), s["overall"]["metrics"]["success"]["rate"].get<double>());
  EXPECT_EQ(s["by_grid_point"].size(), 3u);
}

TEST_F(Campaigns, AKilledShardResumesToTheSameSummaryAndLosesOnlyTheTrialInFlight) {
  const CampaignSpec spec = LoadCampaignSpec(Spec());
  Run(spec, "whole");
  const std::string reference = Merge({"whole"}, "m_whole");
  // A kill after three trials, in the middle of writing the fourth: three whole lines and a cut one,
  // and a manifest that never finished.
  Run(spec, "killed");
  const std::string results = (dir_ / "killed" / "results.jsonl").string();
  std::string text = io::ReadFile(results);
  std::size_t cut = 0;
  for (int k = 0; k < 3; ++k) cut = text.find('\n', cut) + 1;
  text = text.substr(0, cut) + text.substr(cut, 25);
  { std::ofstream(results, std::ios::binary | std::ios::trunc) << text; }
  const std::string manifest = (dir_ / "killed" / "manifest.json").string();
  nlohmann::json m = nlohmann::json::parse(io::ReadFile(manifest));
  m["finished"] = nullptr;
  { std::ofstream(manifest, std::ios::trunc) << m.dump(2); }
  RG_EXPECT_THROW_WITH(Merge({"killed"}, "m_early"), std::invalid_argument, "unfinished");
  const campaign::CampaignRunSummary resumed = Run(spec, "killed", 2, {}, /*resume=*/true);
  EXPECT_EQ(resumed.skipped, 3);
  EXPECT_EQ(resumed.ran, 3);
  EXPECT_EQ(Merge({"killed"}, "m_killed"), reference);
}

TEST_F(Campaigns, AnErroringTrialIsRecordedAndTheCampaignGoesOn) {
  // Rotor 9 of a quadrotor: trials 0-1 load, trials 2-3 fail at load time and are recorded.
  const CampaignSpec spec = LoadCampaignSpec(Write("err.yaml", "name: err\n"
                                                               "scenario: " + ScenarioPath("hover_motor_stop_nominal.yaml") + "\n"
                                                               "repeats: 2\n"
                                                               "grid:\n"
                                                               "  duration_s: [2.5]\n"
                                                               "  faults.0.rotor: [0, 9]\n"));
  const campaign::CampaignRunSummary r = Run(spec, "err", 2);
  EXPECT_EQ(r.ran, 4);
  EXPECT_EQ(r.errors, 2);
  Merge({"err"}, "m");
  const nlohmann::json s = nlohmann::json::parse(io::ReadFile((dir_ / "m" / "summary.json").string()));
  EXPECT_EQ(s["overall"]["status"]["error"].get<int>(), 2);
  EXPECT_EQ(s["overall"]["status"]["ok"].get<int>(), 2);
  ASSERT_EQ(s["errors"].size(), 2u);
  EXPECT_NE(s["errors"][0]["message"].get<std::string>().find("rotor"), std::string::npos);
}

TEST_F(Campaigns, BadInputIsRejectedNamingTheKeyAndNothingIsOverwritten) {
  RG_EXPECT_THROW_WITH(LoadCampaignSpec(Write("u.yaml", "name: u\nscenario: " + ScenarioPath("hover.yaml") +
                                                             "\ngrid:\n  wind.gusty: [0.1]\n")),
                       io::ConfigError, "grid.wind.gusty");
  RG_EXPECT_THROW_WITH(LoadCampaignSpec(Write("e.yaml", "name: e\nscenario: " + ScenarioPath("hover.yaml") +
                                                             "\ngrid:\n  duration_s: []\n")),
                       io::ConfigError, "an empty sweep");
  RG_EXPECT_THROW_WITH(LoadCampaignSpec(Write("m.yaml", "name: m\nscenario: " + ScenarioPath("hover.yaml") +
                                                             "\nmetrics: [wall_time_s]\n")),
                       io::ConfigError, "not a recorded metric");
  for (const campaign::Shard bad : {campaign::Shard{4, 4}, campaign::Shard{0, 0}, campaign::Shard{-1, 2}}) {
    campaign::CampaignRunOptions o;
    o.out_dir = (dir_ / "bad_shard").string();
    o.shard = bad;
    RG_EXPECT_THROW_WITH(campaign::RunCampaign(ScenarioCampaign(LoadCampaignSpec(Spec())), o), ValidationError,
                         "CampaignRunOptions::shard");
  }

  const CampaignSpec spec = LoadCampaignSpec(Spec());
  Run(spec, "out");
  const std::string results = (dir_ / "out" / "results.jsonl").string();
  const std::string before = io::ReadFile(results);
  RG_EXPECT_THROW_WITH(Run(spec, "out"), ValidationError, "set CampaignRunOptions::resume");
  // Another spec (another seed) cannot resume these results, nor merge with them.
  std::string text = io::ReadFile((dir_ / "spec.yaml").string());
  text.replace(text.find("seed: 7"), 7, "seed: 8");
  const CampaignSpec other = LoadCampaignSpec(Write("other.yaml", text));
  EXPECT_NE(other.hash, spec.hash);
  RG_EXPECT_THROW_WITH(Run(other, "out", 1, {}, true), std::invalid_argument, "spec_hash");
  EXPECT_EQ(io::ReadFile(results), before);
  Run(other, "other_out");
  RG_EXPECT_THROW_WITH(Merge({"out", "other_out"}, "m"), std::invalid_argument, "spec_hash");
  // Half the shards: a gap.
  Run(spec, "half", 1, campaign::Shard{0, 2});
  RG_EXPECT_THROW_WITH(Merge({"half"}, "mh"), std::invalid_argument, "missing");
  // The same shard twice: duplicates.
  Run(spec, "dup_a", 1, campaign::Shard{1, 2});
  Run(spec, "dup_b", 1, campaign::Shard{1, 2});
  RG_EXPECT_THROW_WITH(Merge({"half", "dup_a", "dup_b"}, "md"), std::invalid_argument, "is in both");
  // A refused merge leaves an earlier summary as it was.
  fs::create_directories(dir_ / "md");
  Write("md/summary.json", "{\"earlier\": true}");
  RG_EXPECT_THROW_WITH(Merge({"half", "dup_a", "dup_b"}, "md"), std::invalid_argument, "is in both");
  EXPECT_EQ(io::ReadFile((dir_ / "md" / "summary.json").string()), "{\"earlier\": true}");
}

TEST_F(Campaigns, SpecRulesNameTheKey) {
  const std::string base = "name: s\nscenario: " + ScenarioPath("hover.yaml") + "\n";
  RG_EXPECT_THROW_WITH(LoadCampaignSpec(Write("k.yaml", base + "trials: 5\n")), io::ConfigError, "trials");
  RG_EXPECT_THROW_WITH(LoadCampaignSpec(Write("o.yaml", base + "grid:\n  duration_s: [1.0]\nrandom:\n  duration_s: "
                                                               "{uniform: [1.0, 2.0]}\n")),
                       io::ConfigError, "in one sweep only");
  RG_EXPECT_THROW_WITH(LoadCampaignSpec(Write("n.yaml", "name: a b\nscenario: " + ScenarioPath("hover.yaml") + "\n")),
                       io::ConfigError, "'a b' is invalid");
  RG_EXPECT_THROW_WITH(LoadCampaignSpec(Write("r.yaml", base + "random:\n  duration_s: {uniform: [2.0, 1.0]}\n")),
                       io::ConfigError, "lo < hi");
}

TEST_F(Campaigns, ARunningShardIsNotRunTwiceAndDamagedResultsAreRefusedUntouched) {
  const CampaignSpec spec = LoadCampaignSpec(Spec());
  // Another process holds the shard.
  fs::create_directories(dir_ / "busy");
  const int fd = ::open((dir_ / "busy" / "manifest.json.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  RG_EXPECT_THROW_WITH(Run(spec, "busy"), std::invalid_argument, "already running");
  ::close(fd);
  EXPECT_EQ(Run(spec, "busy").ran, 6);  // released: it runs

  // A cut last line and another spec's resume: refused, and the file keeps its cut line.
  const std::string results = (dir_ / "busy" / "results.jsonl").string();
  { std::ofstream(results, std::ios::app | std::ios::binary) << "{\"trial\": 3, \"id\""; }
  const std::string cut = io::ReadFile(results);
  std::string text = io::ReadFile((dir_ / "spec.yaml").string());
  text.replace(text.find("seed: 7"), 7, "seed: 9");
  RG_EXPECT_THROW_WITH(Run(LoadCampaignSpec(Write("other.yaml", text)), "busy", 1, {}, true), std::invalid_argument,
                       "spec_hash");
  EXPECT_EQ(io::ReadFile(results), cut);
  // Merge refuses the cut line (resume first), and a damaged line in the middle.
  RG_EXPECT_THROW_WITH(Merge({"busy"}, "m1"), io::CorruptFileError, "cut short");
  std::string lines = cut.substr(0, cut.rfind('\n') + 1);
  lines.replace(lines.find("\"status\""), 8, "\"statuz\"");
  { std::ofstream(results, std::ios::trunc | std::ios::binary) << lines; }
  RG_EXPECT_THROW_WITH(Merge({"busy"}, "m2"), io::CorruptFileError, "one trial record per line");
  // Shards of two builds of the program do not merge.
  campaign::CampaignRunOptions o;
  o.out_dir = (dir_ / "versions").string();
  o.shard = {0, 2};
  o.version = "build A";
  campaign::RunCampaign(ScenarioCampaign(spec), o);
  o.shard = {1, 2};
  o.version = "build B";
  campaign::RunCampaign(ScenarioCampaign(spec), o);
  RG_EXPECT_THROW_WITH(Merge({"versions"}, "m3"), std::invalid_argument, "version");
}

TEST_F(Campaigns, TheSlurmScriptRunsOneResumableShardPerArrayTask) {
  const CampaignSpec spec = LoadCampaignSpec(Spec());
  campaign::SlurmScriptOptions o;
  o.shards = 3;
  o.cpus_per_task = 2;
  o.out_dir = (dir_ / "results").string();
  o.rotorguard = "/opt/rg/bin/rotorguard";
  o.partition = "short";
  const std::string script = campaign::SlurmArrayScript(ScenarioCampaign(spec), o);
  for (const std::string& needle :
       {std::string("#SBATCH --array=0-2\n"), std::string("#SBATCH --cpus-per-task=2\n"),
        std::string("#SBATCH --partition=short\n"), std::string("--shard \"${SLURM_ARRAY_TASK_ID}/3\""),
        std::string("--resume"), std::string("'/opt/rg/bin/rotorguard' campaign run"),
        "--out '" + (dir_ / "results").string() + "'"}) {
    EXPECT_NE(script.find(needle), std::string::npos) << needle << " not in\n" << script;
  }
  o.shards = 7;  // more than the 6 trials
  RG_EXPECT_THROW_WITH(campaign::SlurmArrayScript(ScenarioCampaign(spec), o), ValidationError, "SlurmScriptOptions::shards = 7");
  o.shards = 3;
  o.partition = "a b";
  RG_EXPECT_THROW_WITH(campaign::SlurmArrayScript(ScenarioCampaign(spec), o), std::invalid_argument, "'a b'");
  o.partition = "";
  o.out_dir = (dir_ / "with space").string();
  RG_EXPECT_THROW_WITH(campaign::SlurmArrayScript(ScenarioCampaign(spec), o), std::invalid_argument, "without spaces");
}

TEST_F(Campaigns, TheBenchmarkFindsJobsResumeAndShardsIdenticalAndRefusesAFullFolder) {
  const CampaignSpec spec = LoadCampaignSpec(Spec());
  const nlohmann::json r = RunCampaignBenchmark(ScenarioCampaign(spec), (dir_ / "bench").string(), "test", CampaignKinds());
  EXPECT_EQ(r["trials"].get<int>(), 6);
  EXPECT_TRUE(r["jobs_identical"].get<bool>());
  EXPECT_TRUE(r["resume_identical"].get<bool>());
  EXPECT_TRUE(r["shards_identical"].get<bool>());
  EXPECT_GT(r["trials_per_s_1worker"].get<double>(), 0.0);
  RG_EXPECT_THROW_WITH(RunCampaignBenchmark(ScenarioCampaign(spec), (dir_ / "bench").string(), "test", CampaignKinds()), std::invalid_argument,
                       "not empty");
}

}  // namespace
}  // namespace rotorguard::benchmarks
