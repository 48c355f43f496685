// The campaign engine on made-up trials, each a pure function of its index (no flight): the same
// summary however the trials are run (one worker or two, shards, a kill and a resume), errors and
// non-finite results recorded, merges that refuse gaps, duplicates and mixed specs, and the
// registry that dispatches specs to their kinds. The oracle for "results do not depend on how they
// were run" is a byte comparison of merged summaries.

#include "rotorguard/campaign/campaign.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "rotorguard/campaign/merge.h"
#include "rotorguard/campaign/registry.h"
#include "rotorguard/campaign/statistics.h"
#include "rotorguard/core/error.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "test_util.h"

namespace rotorguard::campaign {
namespace {

namespace fs = std::filesystem;

/// 12 trials over a grid of 3 values of `a`; trial i records x = i^2 and flag = (i odd). Trial 7
/// throws when `failing` is set, and trial 5 records a NaN when `diverging` is.
Campaign MadeUp(std::atomic<int>* runs, bool failing = false, bool diverging = false) {
  Campaign c;
  c.name = "made_up";
  c.hash = "hash-1";
  c.trials = 12;
  c.group_keys = {"a"};
  c.metrics = {"x", "flag"};
  c.parameters = [](int i) {
    return std::map<std::string, std::string>{{"a", std::to_string(i % 3)}, {"seed", std::to_string(1000 + i)}};
  };
  c.run = [runs, failing, diverging](int i, const std::map<std::string, std::string>&) {
    ++*runs;
    if (failing && i == 7) throw std::runtime_error("trial 7 fails");
    TrialOutcome out;
    out.metrics = {{"x", diverging && i == 5 ? std::numeric_limits<double>::quiet_NaN() : double(i * i)},
                   {"flag", i % 2 == 1}};
    return out;
  };
  return c;
}

class CampaignEngine : public testing::TempFolderTest {
 protected:
  /// In-process trials by default (trial_timeout_factor 0): the made-up trials count their runs,
  /// which a child process would not report.
  CampaignRunSummary Run(const Campaign& c, const std::string& out, int jobs = 1, Shard shard = {}, bool resume = false,
                         double trial_timeout_factor = 0.0) {
    CampaignRunOptions o;
    o.trial_timeout_factor = trial_timeout_factor;
    o.out_dir = (dir_ / out).string();
    o.jobs = jobs;
    o.shard = shard;
    o.resume = resume;
    o.version = "test";
    return RunCampaign(c, o);
  }
  /// The merged summary of the folders, as text (summary.json and summary.md).
  std::string Merge(const std::vector<std::string>& outs, const std::string& into) {
    std::vector<std::string> dirs;
    for (const std::string& o : outs) dirs.push_back((dir_ / o).string());
    MergeCampaign(dirs, (dir_ / into).string(), CampaignRegistry{});
    return io::ReadFile((dir_ / into / "summary.json").string()) + io::ReadFile((dir_ / into / "summary.md").string());
  }
  std::atomic<int> runs_{0};
};

TEST_F(CampaignEngine, WorkersAndShardsGiveByteIdenticalSummaries) {
  const Campaign c = MadeUp(&runs_);
  Run(c, "one", 1);
  Run(c, "two", 2);
  for (int i = 0; i < 3; ++i) Run(c, i < 2 ? "shards_a" : "shards_b", 1, Shard{i, 3});
  const std::string reference = Merge({"one"}, "one");
  EXPECT_EQ(Merge({"two"}, "two"), reference);
  EXPECT_EQ(Merge({"shards_a", "shards_b"}, "shards_merged"), reference);
  EXPECT_EQ(runs_.load(), 36);
  // The statistics by hand: x over a = 0 is {0, 9, 36, 81}, mean 31.5; flag true in half of all.
  const nlohmann::json s = nlohmann::json::parse(io::ReadFile((dir_ / "one" / "summary.json").string()));
  EXPECT_DOUBLE_EQ(s["by_grid_point"][0]["metrics"]["x"]["mean"].get<double>(), 31.5);
  EXPECT_DOUBLE_EQ(s["overall"]["metrics"]["flag"]["rate"].get<double>(), 0.5);
}

TEST_F(CampaignEngine, AKilledRunResumesRunningOnlyWhatItHadNotRecorded) {
  const Campaign c = MadeUp(&runs_);
  Run(c, "whole");
  const std::string reference = Merge({"whole"}, "whole");
  Run(c, "killed");
  // What a kill leaves: five whole lines, the sixth cut short, the manifest unfinished.
  const std::string results = (dir_ / "killed" / "results.jsonl").string();
  std::string text = io::ReadFile(results);
  std::size_t cut = 0;
  for (int k = 0; k < 5; ++k) cut = text.find('\n', cut) + 1;
  io::WriteFileAtomically(results, text.substr(0, cut + 10));
  const std::string manifest = (dir_ / "killed" / "manifest.json").string();
  nlohmann::json m = nlohmann::json::parse(io::ReadFile(manifest));
  m["finished"] = nullptr;
  io::WriteFileAtomically(manifest, m.dump(2));
  RG_EXPECT_THROW_WITH(Merge({"killed"}, "killed"), std::invalid_argument, "unfinished");
  // Without --resume the folder's results are not overwritten.
  RG_EXPECT_THROW_WITH(Run(c, "killed"), ValidationError, "CampaignRunOptions::resume");
  runs_ = 0;
  const CampaignRunSummary r = Run(c, "killed", 2, {}, /*resume=*/true);
  EXPECT_EQ(r.skipped, 5);
  EXPECT_EQ(r.ran, 7);
  EXPECT_EQ(runs_.load(), 7);
  EXPECT_EQ(Merge({"killed"}, "killed"), reference);
}

TEST_F(CampaignEngine, ErrorsAndNonFiniteResultsAreRecordedAndTheRestRuns) {
  const Campaign c = MadeUp(&runs_, /*failing=*/true, /*diverging=*/true);
  CampaignRunOptions o;
  o.jobs = 2;
  const std::vector<nlohmann::json> records = *RunCampaignRecords(c, o);
  ASSERT_EQ(records.size(), 12u);
  EXPECT_EQ(records[7]["status"], "error");
  EXPECT_EQ(TrialFailure(records[7]), "error: trial 7 fails");
  EXPECT_EQ(records[5]["status"], "diverged");
  EXPECT_TRUE(records[5]["metrics"]["x"].is_null()) << "JSON has no NaN";
  EXPECT_EQ(records[6]["status"], "ok");
  EXPECT_EQ(records[6]["metrics"]["x"], 36.0);
}

TEST_F(CampaignEngine, WatchedTrialsInChildProcessesRecordWhatInProcessTrialsRecord) {
  const Campaign c = MadeUp(&runs_, /*failing=*/true, /*diverging=*/true);
  Run(c, "in_process", 2);
  const CampaignRunSummary watched = Run(c, "watched", 2, {}, false, /*trial_timeout_factor=*/100.0);
  EXPECT_EQ(watched.errors, 2);  // trial 7's exception and trial 5's NaN, as in process
  EXPECT_EQ(watched.timeouts, 0);
  EXPECT_EQ(io::ReadFile((dir_ / "watched" / "results.jsonl").string()).size(),
            io::ReadFile((dir_ / "in_process" / "results.jsonl").string()).size());
  EXPECT_EQ(Merge({"watched"}, "watched"), Merge({"in_process"}, "in_process"));
}

// The watchdog's reason to be: a trial that never ends and one whose process dies are recorded,
// and the shard's other trials run and are recorded as usual.
TEST_F(CampaignEngine, AHungTrialTimesOutAndACrashedOneIsAnErrorWhileTheShardGoesOn) {
  Campaign c = MadeUp(&runs_);
  const auto made_up = c.run;
  c.run = [made_up](int i, const std::map<std::string, std::string>& p) {
    if (i == 3) {
      for (;;) std::this_thread::sleep_for(std::chrono::milliseconds(10));  // hangs
    }
    if (i == 4) std::abort();
    return made_up(i, p);
  };
  // The hung trial gets 50 x 0.005 s = 0.25 s; the others 50 s, so that a loaded machine's slow fork
  // never turns a trial that ends into a timeout.
  c.simulated_s = [](int i, const std::map<std::string, std::string>&) { return i == 3 ? 0.005 : 1.0; };
  c.reproduce = [](int i, const std::map<std::string, std::string>&) { return fmt::format("replay {}", i); };
  const CampaignRunSummary r = Run(c, "watched", 2, {}, false, /*trial_timeout_factor=*/50.0);
  EXPECT_EQ(r.ran, 12);
  EXPECT_EQ(r.timeouts, 1);
  EXPECT_EQ(r.errors, 1);
  std::map<int, nlohmann::json> lines;
  std::istringstream text(io::ReadFile((dir_ / "watched" / "results.jsonl").string()));
  for (std::string line; std::getline(text, line);) {
    const nlohmann::json j = nlohmann::json::parse(line);
    lines[j["trial"].get<int>()] = j;
  }
  ASSERT_EQ(lines.size(), 12u);
  EXPECT_EQ(lines[3]["status"], "timeout");
  const std::string why = lines[3]["message"];
  EXPECT_NE(why.find("50 x its 0.005 s simulated"), std::string::npos) << why;
  EXPECT_NE(why.find("seed 1003"), std::string::npos) << why;
  EXPECT_NE(why.find("reproduce: replay 3"), std::string::npos) << why;
  EXPECT_EQ(lines[4]["status"], "error");
  EXPECT_NE(lines[4]["message"].get<std::string>().find("SIGABRT"), std::string::npos) << lines[4]["message"];
  EXPECT_EQ(lines[5]["status"], "ok");
  EXPECT_EQ(lines[5]["metrics"]["x"], 25.0);
  // The merge counts the timeout apart from the error.
  Merge({"watched"}, "merged");
  const nlohmann::json s = nlohmann::json::parse(io::ReadFile((dir_ / "merged" / "summary.json").string()));
  EXPECT_EQ(s["overall"]["status"]["timeout"], 1);
  EXPECT_EQ(s["overall"]["status"]["error"], 1);
  EXPECT_EQ(s["overall"]["status"]["ok"], 10);
}

TEST_F(CampaignEngine, AMergeRefusesGapsDuplicatesAndMixedSpecs) {
  const Campaign c = MadeUp(&runs_);
  Run(c, "s0", 1, Shard{0, 2});
  RG_EXPECT_THROW_WITH(Merge({"s0"}, "gap"), std::invalid_argument, "missing");
  Run(c, "s0_again", 1, Shard{0, 2});
  Run(c, "s1", 1, Shard{1, 2});
  RG_EXPECT_THROW_WITH(Merge({"s0", "s0_again", "s1"}, "dup"), std::invalid_argument, "in both");
  Campaign other = c;
  other.hash = "hash-2";
  Run(other, "s1_other", 1, Shard{1, 2});
  RG_EXPECT_THROW_WITH(Merge({"s0", "s1_other"}, "mixed"), std::invalid_argument, "spec_hash");
  // Found by fuzzing (tests/fuzz, manifest_json): a manifest whose keys hold the wrong types escaped
  // as the JSON library's type_error; it is a damaged file, named with the key.
  const fs::path m = dir_ / "s1" / "manifest.shard-1.json";
  const std::string manifest = io::ReadFile(m.string());
  nlohmann::json damaged = nlohmann::json::parse(manifest);
  damaged["trials_total"] = nullptr;
  io::WriteFileAtomically(m.string(), damaged.dump());
  RG_EXPECT_THROW_WITH(Merge({"s0", "s1"}, "damaged"), io::CorruptFileError,
                       "'trials_total' is missing or not a count");
  damaged = nlohmann::json::parse(manifest);
  damaged["metrics"] = {"x", 3};
  io::WriteFileAtomically(m.string(), damaged.dump());
  RG_EXPECT_THROW_WITH(Merge({"s0", "s1"}, "damaged"), io::CorruptFileError, "'metrics' is missing or not a list");
  io::WriteFileAtomically(m.string(), manifest);
  // A resume against another spec is refused, the folder untouched.
  const std::string before = io::ReadFile((dir_ / "s0" / "results.shard-0.jsonl").string());
  RG_EXPECT_THROW_WITH(Run(other, "s0", 1, Shard{0, 2}, true), ValidationError, "spec_hash");
  EXPECT_EQ(io::ReadFile((dir_ / "s0" / "results.shard-0.jsonl").string()), before);
  // Options the engine cannot run name their field.
  RG_EXPECT_THROW_WITH(Run(c, "bad", 0), ValidationError, "CampaignRunOptions::jobs = 0");
  RG_EXPECT_THROW_WITH(Run(c, "bad", 1, Shard{0, 13}), ValidationError, "CampaignRunOptions::shard = 0/13");
}

TEST_F(CampaignEngine, TheRegistryHandsEachSpecToItsKind) {
  CampaignRegistry kinds;
  std::vector<std::string> loaded;
  const auto kind = [&loaded](const std::string& name) {
    return CampaignKind{name,
                        [&loaded, name](const io::ConfigNode& root, const std::string&) {
                          loaded.push_back(name);
                          Campaign c;
                          c.trials = static_cast<int>(root.Required("trials").AsIntIn(1, 100));
                          return c;
                        },
                        {}};
  };
  kinds.Add(kind(""));
  kinds.Add(kind("alpha"));
  kinds.Add(kind("beta"));
  EXPECT_THROW(kinds.Add(kind("beta")), std::logic_error);
  EXPECT_EQ(kinds.names(), (std::vector<std::string>{"alpha", "beta"}));
  EXPECT_EQ(LoadCampaign(Write("plain.yaml", "name: p\ntrials: 3\n"), kinds).trials, 3);
  const Campaign b = LoadCampaign(Write("b.yaml", "name: b_1\nbench: beta\ntrials: 4\n"), kinds);
  EXPECT_EQ(b.trials, 4);
  EXPECT_EQ(b.name, "b_1");
  EXPECT_EQ(loaded, (std::vector<std::string>{"", "beta"}));
  RG_EXPECT_THROW_WITH(LoadCampaign(Write("g.yaml", "name: g\nbench: gamma\ntrials: 1\n"), kinds), io::ConfigError,
                       "expected one of: alpha, beta");
  RG_EXPECT_THROW_WITH(LoadCampaign(Write("u.yaml", "name: u\nbench: beta\ntrials: 1\nextra: 1\n"), kinds),
                       io::ConfigError, "unknown key 'extra'");
  RG_EXPECT_THROW_WITH(CampaignResult({{"name", "alpha"}, {"options", {}}}, {}, kinds), std::invalid_argument,
                       "benchmark 'alpha' is unknown");
}

TEST_F(CampaignEngine, TheSummaryStatisticsMatchTheClosedFormsOnHandMadeResults) {
  // A campaign of three trials written by hand: x = 1, 2, 3 (mean 2, std 1), flag true twice.
  fs::create_directories(dir_ / "hand");
  Write("hand/manifest.json", R"({"campaign": "hand", "spec_hash": "h", "version": "v", "trials_total": 3,
      "shard": "0/1", "metrics": ["x", "flag", "big"], "grid_keys": [], "finished": "t"})");
  std::string lines;
  const double xs[3] = {1.0, 2.0, 3.0};
  for (int i = 0; i < 3; ++i) {
    lines += nlohmann::json({{"trial", i}, {"id", "i"}, {"params", nlohmann::json::object()}, {"status", "ok"},
                             {"message", ""},
                             {"metrics", {{"x", xs[i]}, {"flag", i < 2}, {"big", 1.5e308}}}})
                 .dump() +
             "\n";
  }
  Write("hand/results.jsonl", lines);
  const nlohmann::json s = MergeCampaign({(dir_ / "hand").string()}, (dir_ / "hand").string(), CampaignRegistry{});
  const nlohmann::json& x = s["overall"]["metrics"]["x"];
  EXPECT_DOUBLE_EQ(x["mean"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(x["std"].get<double>(), 1.0);
  EXPECT_NEAR(x["ci95"][0].get<double>(), 2.0 - 1.959963984540054 / std::sqrt(3.0), 1e-12);
  EXPECT_DOUBLE_EQ(x["min"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(x["max"].get<double>(), 3.0);
  const nlohmann::json& flag = s["overall"]["metrics"]["flag"];
  EXPECT_NEAR(flag["rate"].get<double>(), 2.0 / 3.0, 1e-15);
  EXPECT_EQ(flag["wilson95"][0].get<double>(), WilsonInterval(2, 3).first);
  // Three values of 1.5e308 sum past the largest double; the running mean stays exact.
  EXPECT_DOUBLE_EQ(s["overall"]["metrics"]["big"]["mean"].get<double>(), 1.5e308);
  EXPECT_EQ(io::ReadFile((dir_ / "hand" / "summary.md").string()).find("nan"), std::string::npos);
}

}  // namespace
}  // namespace rotorguard::campaign
