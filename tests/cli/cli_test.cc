// End-to-end tests of the rotorguard command line: exit codes, error messages that name file,
// line and key path, and outputs that are never half-written.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_util.h"

namespace {

namespace fs = std::filesystem;

struct Result {
  int exit_code = -1;
  std::string out;  ///< stdout and stderr together
};

/// Runs the CLI with `args` (already shell-quoted where needed).
Result Cli(const std::string& args) {
  const std::string cmd = std::string(ROTORGUARD_CLI) + " " + args + " 2>&1";
  Result r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), pipe)) r.out += buf.data();
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string ReadText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const std::string kVehicle = rotorguard::testing::SourcePath("configs/vehicles/zhou2025_quad.yaml");

/// A short valid hover scenario; `extra` is appended (YAML) to it.
std::string Scenario(const std::string& vehicle, const std::string& extra = "") {
  return "vehicle: " + vehicle +
         "\n"
         "duration_s: 1.0\n"
         "seed: 3\n"
         "initial:\n"
         "  position_m: [0.0, 0.0, 1.0]\n"
         "mission:\n"
         "  type: hover\n" +
         extra;
}

class CliTest : public rotorguard::testing::TempFolderTest {
 protected:
  /// A copy of the reference vehicle file with `from` replaced by `to` in its text.
  std::string VehicleWith(const std::string& from, const std::string& to) {
    std::string text = ReadText(kVehicle);
    const auto pos = text.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    if (pos != std::string::npos) text.replace(pos, from.size(), to);
    return Write("vehicle.yaml", text);
  }
  /// Expects exit 2 and a message holding "<file>:<line>" and every needle.
  void ExpectConfigError(const std::string& args, const std::string& file, int line,
                         const std::vector<std::string>& needles) {
    const Result r = Cli(args);
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_NE(r.out.find(file + ":" + std::to_string(line)), std::string::npos)
        << "expected " << file << ":" << line << " in: " << r.out;
    for (const std::string& n : needles) EXPECT_NE(r.out.find(n), std::string::npos) << "'" << n << "' not in: " << r.out;
  }
  std::string Out() const { return (dir_ / "out").string(); }
};

/// --version names the release and the source revision, as every result's manifest does, so that a
/// figure made with a copied binary can be traced to its build.
TEST_F(CliTest, TheVersionNamesTheReleaseAndTheRevision) {
  const Result r = Cli("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(std::regex_match(r.out, std::regex(R"([0-9]+\.[0-9]+\.[0-9]+ \((unknown|[0-9a-f]{7,}(-dirty)?)\)\n)")))
      << r.out;
}

/// Software in the loop through two processes (docs/runtime.md): `sitl` starts `rotorguard node`
/// and flies a propeller loss in real time against it; the stack's process isolates the rotor and
/// both processes' figures reach the summary and runtime.json.
TEST_F(CliTest, SitlFliesAPropellerLossInRealTimeWithTheStackInItsOwnProcess) {
  const std::string scenario = rotorguard::testing::SourcePath("configs/scenarios/fdd_hover_propeller_loss.yaml");
  const Result r = Cli("sitl " + scenario + " --set duration_s=6 --seed 2 -q --out " + (dir_ / "sitl").string());
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json s = nlohmann::json::parse(ReadText(dir_ / "sitl" / "summary.json"));
  EXPECT_TRUE(s["success"].get<bool>()) << s["failure_reason"];
  EXPECT_TRUE(s["fdd"]["correct"].get<bool>());
  EXPECT_EQ(s["fdd"]["rotor"], 0);
  EXPECT_EQ(s["supervisor"]["transitions"][0]["to"], "failure_recovery");
  const nlohmann::json rt = nlohmann::json::parse(ReadText(dir_ / "sitl" / "runtime.json"));
  EXPECT_EQ(rt["link"]["processes"], 2);
  // The two processes' clocks agree: no command is stamped before the sample it was computed from.
  EXPECT_EQ(rt["link"]["commands_before_their_sample"], 0);
  const auto runs = rt["control"]["runs"].get<std::uint64_t>();
  // 6 s at 200 Hz: a cycle per control instant, unless the control thread was late (skipped).
  EXPECT_EQ(runs + rt["control"]["skipped"].get<std::uint64_t>(), 1200u);
  // Every cycle's command arrives, and every command the deadline guard held in a late cycle's place.
  EXPECT_EQ(rt["link"]["commands"].get<std::uint64_t>() + rt["link"]["commands_after_end"].get<std::uint64_t>(),
            runs + rt["deadline_policy"]["holds"].get<std::uint64_t>());
  EXPECT_EQ(s["control_cycles"].get<std::uint64_t>(), runs);
  for (const char* file : {"log.csv", "scene.json", "sensors.csv", "vehicle.yaml", "truth_vehicle.yaml"}) {
    EXPECT_TRUE(fs::exists(dir_ / "sitl" / file)) << file;
  }
}

/// On the simulator's clock (the simulator waits for each command), the stack in its own process
/// flies `run`'s flight to the bit: the transport loses, reorders and alters nothing, the LiDAR
/// frames through their shared-memory slots to the LiDAR-inertial odometry included (the forest,
/// its failure brought forward).
TEST_F(CliTest, SitlOnTheSimulatorsClockInTwoProcessesFliesRunsFlightToTheBit) {
  const std::string scenario = rotorguard::testing::SourcePath("configs/scenarios/forest.yaml");
  const std::string args = scenario + " --set duration_s=5 --set faults.0.onset.at_time_s=3.5 --seed 4 -q --out ";
  // Five seconds of a 120-s mission do not reach its goal: both exit 1 (the mission failed).
  const Result run = Cli("run " + args + (dir_ / "run").string() + " --no-report");
  ASSERT_TRUE(fs::exists(dir_ / "run" / "summary.json")) << run.out;
  const Result r = Cli("sitl " + args + (dir_ / "sitl").string() + " --lockstep-clock");
  EXPECT_EQ(r.exit_code, run.exit_code) << r.out;
  const nlohmann::json a = nlohmann::json::parse(ReadText(dir_ / "run" / "summary.json"));
  const nlohmann::json b = nlohmann::json::parse(ReadText(dir_ / "sitl" / "summary.json"));
  for (const char* key : {"control_cycles", "physics_steps", "min_altitude_m", "max_spin_rad_s", "max_tilt_rad",
                          "estimate_position_rmse_m", "estimate_attitude_max_rad", "success"}) {
    EXPECT_EQ(a[key], b[key]) << key;
  }
  EXPECT_EQ(a["fdd"]["detection_s"], b["fdd"]["detection_s"]);
  EXPECT_EQ(nlohmann::json::parse(ReadText(dir_ / "sitl" / "runtime.json"))["link"]["processes"], 2);
  // log.csv: `run`'s columns but the stack's internals (FDD indices, NMPC time, odometry health,
  // which stay in the node), row for row the same text.
  const auto table = [](const std::string& text) {
    std::vector<std::vector<std::string>> rows;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
      std::vector<std::string> fields;
      std::istringstream cells(line);
      for (std::string f; std::getline(cells, f, ',');) fields.push_back(f);
      rows.push_back(fields);
    }
    return rows;
  };
  const auto ra = table(ReadText(dir_ / "run" / "log.csv")), rb = table(ReadText(dir_ / "sitl" / "log.csv"));
  ASSERT_EQ(ra.size(), rb.size());
  ASSERT_GT(rb.size(), 10u);
  std::size_t compared = 0;
  for (std::size_t j = 0; j < rb[0].size(); ++j) {
    const auto col = std::find(ra[0].begin(), ra[0].end(), rb[0][j]);
    ASSERT_NE(col, ra[0].end()) << rb[0][j];
    const auto i = static_cast<std::size_t>(col - ra[0].begin());
    for (std::size_t k = 1; k < rb.size(); ++k) ASSERT_EQ(ra[k][i], rb[k][j]) << rb[0][j] << ", row " << k;
    ++compared;
  }
  EXPECT_GE(compared, 50u) << "truth, reference, estimate, mode, rotors";
  EXPECT_LT(rb[0].size(), ra[0].size()) << "the stack's internal columns are the node's";
}

/// A node given a channel no simulator made says which, and fails.
TEST_F(CliTest, ANodeWithoutItsChannelNamesIt) {
  const std::string scenario = rotorguard::testing::SourcePath("configs/scenarios/hover.yaml");
  const Result r = Cli("node " + scenario + " --channel /rotorguard-sitl-none");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("/rotorguard-sitl-none"), std::string::npos) << r.out;
}

TEST_F(CliTest, AStallWithoutItsDurationIsAUsageErrorShowingTheForm) {
  const std::string scenario = rotorguard::testing::SourcePath("configs/scenarios/hover.yaml");
  Result r = Cli("sitl " + scenario + " --stall 3.0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--stall '3.0' is invalid; expected AT:DURATION"), std::string::npos) << r.out;
  r = Cli("sitl " + scenario + " --stall 3.0:0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--stall DURATION '0' is invalid"), std::string::npos) << r.out;
}

/// Bad list and word options of the benchmarks are usage errors that name the option and the field.
TEST_F(CliTest, ABenchmarksListOptionsNameTheFieldThatIsWrong) {
  Result r = Cli("bench lio --spins 11,,20");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--spins: '' is invalid; expected a finite number in [0, 30]"), std::string::npos) << r.out;
  r = Cli("bench lio --spins 11,45");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--spins: '45' is invalid"), std::string::npos) << r.out;
  r = Cli("bench nav --estimator gps");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--estimator 'gps' is invalid; expected one of: odometry, lio"), std::string::npos) << r.out;
}

/// The campaign benchmarks fly the world --truth names and say which in their JSON.
TEST_F(CliTest, ABenchmarksWorldIsNamedByTruthAndRecordedInItsJson) {
  const Result r = Cli("bench ftc --trials 1 --methods none --seed 3 --jobs 1 --truth realistic --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(r.out.substr(r.out.find('{')))["truth"], "realistic");
  const Result bad = Cli("bench nav --truth perfect");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.out.find("--truth 'perfect' is invalid; expected one of: ideal, realistic"), std::string::npos)
      << bad.out;
}

/// A failure listed by bench ftc, replayed alone into a run folder, fails for the same reason.
TEST_F(CliTest, AnFtcTrialReplaysIntoARunFolderAsItFlewInTheBenchmark) {
  const Result r = Cli("bench ftc --trials 1 --methods none --cells hover/motor_stop --seed 3 --jobs 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json cell = nlohmann::json::parse(r.out.substr(r.out.find('{')))["cells"].at(0);
  ASSERT_EQ(cell["failures"].size(), 1u) << cell.dump();  // the nominal controller loses a motor
  const nlohmann::json failure = cell["failures"][0];
  const std::string seed = std::to_string(failure["seed"].get<std::uint64_t>());
  const Result replay = Cli("bench ftc --replay hover/motor_stop:none:" + seed + " --out " + Out());
  EXPECT_EQ(replay.exit_code, 1) << replay.out;
  const nlohmann::json summary = nlohmann::json::parse(ReadText(fs::path(Out()) / "summary.json"));
  EXPECT_EQ(summary["failure_reason"], failure["reason"]);
  EXPECT_EQ(Cli("bench ftc --replay hover/motor_stop:nobody:" + seed).exit_code, 2);
  EXPECT_EQ(Cli("bench ftc --replay hover/motor_stop").exit_code, 2);
}

/// A benchmark run in two shards and merged prints the same tables as one run of it, and its
/// campaign flags are checked (docs/campaigns.md, "Benchmarks as campaigns").
TEST_F(CliTest, ABenchmarkInShardsMergesToTheTablesOfOneRun) {
  const std::string args = "bench ftc --trials 1 --methods none --seed 3 --jobs 1";
  const Result whole = Cli(args);
  ASSERT_EQ(whole.exit_code, 0) << whole.out;
  const std::string out = (dir_ / "shards").string();
  for (const char* shard : {"0/2", "1/2"}) {
    const Result r = Cli(args + " --out " + out + " --shard " + shard);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_NE(r.out.find("campaign merge"), std::string::npos) << r.out;  // what to do next
  }
  const Result merged = Cli("campaign merge " + out);
  ASSERT_EQ(merged.exit_code, 0) << merged.out;
  EXPECT_EQ(ReadText(fs::path(out) / "bench.md"), whole.out);
  EXPECT_TRUE(fs::exists(fs::path(out) / "bench.json"));
  // A whole run into the same folder keeps its own files and reads only them.
  const Result again = Cli(args + " --out " + out);
  EXPECT_EQ(again.exit_code, 0) << again.out;
  EXPECT_EQ(again.out, whole.out);
  // The same trials again into the folder: refused without --resume, nothing to do with it.
  const std::string before = ReadText(fs::path(out) / "results.shard-0.jsonl");
  EXPECT_EQ(Cli(args + " --out " + out + " --shard 0/2").exit_code, 2);
  const Result resumed = Cli(args + " --out " + out + " --shard 0/2 --resume");
  EXPECT_EQ(resumed.exit_code, 0) << resumed.out;
  EXPECT_EQ(ReadText(fs::path(out) / "results.shard-0.jsonl"), before);
  // Shards and resumes need a folder to keep the trials in.
  const Result no_out = Cli(args + " --shard 0/2");
  EXPECT_EQ(no_out.exit_code, 2);
  EXPECT_NE(no_out.out.find("--shard needs --out"), std::string::npos) << no_out.out;
  EXPECT_EQ(Cli(args + " --resume").exit_code, 2);
  EXPECT_EQ(Cli(args + " --out " + out + " --shard 2/2").exit_code, 2);
}

/// A campaign killed without warning mid-run and resumed merges to the same bytes as one that ran
/// through (docs/campaigns.md).
TEST_F(CliTest, AKilledCampaignResumesToAByteIdenticalSummary) {
  const std::string spec = Write("c.yaml", "name: kill_test\n"
                                           "scenario: " +
                                               rotorguard::testing::SourcePath("configs/scenarios/fdd_hover_motor_stop.yaml") +
                                               "\n"
                                           "repeats: 4\n"
                                           "grid:\n"
                                           "  duration_s: [3.0]\n"
                                           "  faults.0.rotor: [0, 2]\n"
                                           "metrics: [success, tracking_rmse_m, fdd.latency_s]\n");
  const std::string whole = (dir_ / "whole").string(), killed = (dir_ / "killed").string();
  ASSERT_EQ(Cli("campaign run " + spec + " --out " + whole + " --jobs 1 --quiet").exit_code, 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl(ROTORGUARD_CLI, ROTORGUARD_CLI, "campaign", "run", spec.c_str(), "--out", killed.c_str(), "--jobs", "1",
            "--quiet", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Kill it once two trials are recorded and before the last one is.
  const fs::path results = fs::path(killed) / "results.jsonl";
  const auto lines = [&] {
    const std::string text = ReadText(results);
    return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  };
  for (int i = 0; i < 6000 && lines() < 2; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the campaign finished before it could be killed";
  // The trials' processes (the watchdog's children, forked without exec: the same command line)
  // die with the run at once (within 0.2 s; the trial in flight would go on for about a second):
  // none is left flying unwatched.
  const auto running = [&] {
    int n = 0;
    for (const auto& entry : fs::directory_iterator("/proc")) {
      std::string cmdline = ReadText(entry.path() / "cmdline");
      std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
      if (cmdline.find(killed) != std::string::npos && cmdline.find("campaign run") != std::string::npos) ++n;
    }
    return n;
  };
  for (int i = 0; i < 20 && running() > 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(running(), 0);
  const int recorded = lines();
  EXPECT_GE(recorded, 2);
  EXPECT_LT(recorded, 8);
  const Result early = Cli("campaign merge " + killed);
  EXPECT_EQ(early.exit_code, 2) << early.out;  // unfinished: refused
  const Result resumed = Cli("campaign run " + spec + " --out " + killed + " --jobs 2 --resume --quiet");
  EXPECT_EQ(resumed.exit_code, 0) << resumed.out;
  EXPECT_NE(resumed.out.find(std::to_string(recorded) + " already done"), std::string::npos) << resumed.out;
  ASSERT_EQ(Cli("campaign merge " + whole).exit_code, 0);
  ASSERT_EQ(Cli("campaign merge " + killed).exit_code, 0);
  EXPECT_EQ(ReadText(fs::path(killed) / "summary.json"), ReadText(fs::path(whole) / "summary.json"));
  EXPECT_EQ(ReadText(fs::path(killed) / "summary.md"), ReadText(fs::path(whole) / "summary.md"));
  // The viewer's page of the summary (the CI build always has the viewer) names the campaign.
  const std::string page = ReadText(fs::path(whole) / "summary.html");
  EXPECT_NE(page.find("kill_test"), std::string::npos);
  // The watchdog: a budget of 0.01 s per simulated second (0.03 s for these 3 s flights) stops
  // every trial; each is recorded as a timeout with the command that flies it, and the run exits 0.
  const std::string watched = (dir_ / "watched").string();
  const Result timed_out = Cli("campaign run " + spec + " --out " + watched + " --trial-timeout 0.01 --quiet");
  EXPECT_EQ(timed_out.exit_code, 0) << timed_out.out;
  EXPECT_NE(timed_out.out.find("0 error or diverged, 8 timed out"), std::string::npos) << timed_out.out;
  const std::string watched_lines = ReadText(fs::path(watched) / "results.jsonl");
  EXPECT_EQ(std::count(watched_lines.begin(), watched_lines.end(), '\n'), 8);
  EXPECT_NE(watched_lines.find("\"status\":\"timeout\""), std::string::npos) << watched_lines;
  EXPECT_NE(watched_lines.find("reproduce: rotorguard run "), std::string::npos) << watched_lines;
  // The budget is of the trial's own duration, which the sweep sets (3 s; the scenario's is 10 s).
  EXPECT_NE(watched_lines.find("(0.01 x its 3 s simulated)"), std::string::npos) << watched_lines;
  const Result negative = Cli("campaign run " + spec + " --out " + (dir_ / "n").string() + " --trial-timeout -1");
  EXPECT_EQ(negative.exit_code, 2);
  EXPECT_NE(negative.out.find("--trial-timeout"), std::string::npos) << negative.out;
  // Without --resume the results are not touched; shard and spec errors exit 2.
  const std::string before = ReadText(results);
  EXPECT_EQ(Cli("campaign run " + spec + " --out " + killed).exit_code, 2);
  EXPECT_EQ(ReadText(results), before);
  for (const char* shard : {"4/4", "0/0", "-1/2", "a/2", "1/2x", "3"}) {
    const Result r = Cli("campaign run " + spec + " --out " + (dir_ / "s").string() + " --shard=" + shard);
    EXPECT_EQ(r.exit_code, 2) << shard << ": " << r.out;
    EXPECT_NE(r.out.find("--shard"), std::string::npos) << r.out;
  }
  const Result unknown = Cli("campaign run " + Write("u.yaml", "name: u\nscenario: " + spec + "\n") + " --out " +
                             (dir_ / "u").string());
  EXPECT_EQ(unknown.exit_code, 2) << unknown.out;
  const Result typo = Cli("campaign run " + Write("t.yaml", ReadText(spec) + "repeat: 3\n") + " --out " +
                          (dir_ / "t").string());
  EXPECT_EQ(typo.exit_code, 2) << typo.out;
  EXPECT_NE(typo.out.find("repeat"), std::string::npos) << typo.out;
  // Results that cannot be read exit 3.
  const std::string damaged = (dir_ / "damaged").string();
  fs::create_directories(damaged);
  std::ofstream(fs::path(damaged) / "manifest.json") << "not json";
  const Result corrupt = Cli("campaign merge " + damaged);
  EXPECT_EQ(corrupt.exit_code, 3) << corrupt.out;
}

TEST_F(CliTest, HelpListsEveryCommandAndExitCodes) {
  const Result r = Cli("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* s : {"run", "validate", "keys", "bench", "campaign", "fdd-calibrate", "report", "Exit codes"}) {
    EXPECT_NE(r.out.find(s), std::string::npos) << s;
  }
  const Result run = Cli("run --help");
  EXPECT_EQ(run.exit_code, 0);
  for (const char* s : {"--out", "--set", "--seed", "--quiet", "--log-format", "--no-report"}) EXPECT_NE(run.out.find(s), std::string::npos) << s;
  EXPECT_EQ(Cli("report --help").exit_code, 0);
  EXPECT_NE(Cli("bench planner --help").out.find("--html"), std::string::npos);
  EXPECT_EQ(Cli("bench sim --help").exit_code, 0);
  const Result perception = Cli("bench perception --help");
  EXPECT_EQ(perception.exit_code, 0);
  for (const char* s : {"--duration", "--seed", "--json"}) EXPECT_NE(perception.out.find(s), std::string::npos) << s;
  const Result planner = Cli("bench planner --help");
  EXPECT_EQ(planner.exit_code, 0);
  for (const char* s : {"--pairs", "--worlds", "--seed", "--json"}) EXPECT_NE(planner.out.find(s), std::string::npos) << s;
  EXPECT_EQ(Cli("validate --help").exit_code, 0);
}

// `keys` prints every scenario key with its default: the stack's NMPC horizon (20, paper 000) among them.
TEST_F(CliTest, KeysPrintsEveryScenarioKeyWithItsDefault) {
  const Result r = Cli("keys");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("| `stack.nmpc.horizon_steps` | `20` | an integer in [1, 200] |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("`mission` with `type: lemniscate`"), std::string::npos);
}

// docs/benchmarks.md's table is the registry's (`bench --list`), unedited; every benchmark it
// lists takes --html, --json and --help.
TEST_F(CliTest, TheBenchmarksPageListsTheRegistry) {
  const Result list = Cli("bench --list");
  ASSERT_EQ(list.exit_code, 0) << list.out;
  const std::string page = ReadText(rotorguard::testing::SourcePath("docs/benchmarks.md"));
  const std::string begin = "<!-- BEGIN rotorguard bench --list: generated, do not edit by hand -->\n";
  const std::size_t a = page.find(begin), b = page.find("<!-- END rotorguard bench --list -->");
  ASSERT_TRUE(a != std::string::npos && b != std::string::npos) << "docs/benchmarks.md lacks the markers";
  EXPECT_EQ(page.substr(a + begin.size(), b - a - begin.size()), list.out)
      << "docs/benchmarks.md's table is out of date: replace the lines between the markers with the output of "
         "`rotorguard bench --list`";
  int rows = 0;
  for (std::size_t at = list.out.find("\n| `"); at != std::string::npos; at = list.out.find("\n| `", at + 1)) {
    const std::size_t name_end = list.out.find('`', at + 4);
    const std::string name = list.out.substr(at + 4, name_end - at - 4);
    const Result help = Cli("bench " + name + " --help");
    EXPECT_EQ(help.exit_code, 0) << name;
    for (const char* flag : {"--html", "--json"}) EXPECT_NE(help.out.find(flag), std::string::npos) << name << " " << flag;
    ++rows;
  }
  EXPECT_EQ(rows, 12);  // sim, qp, nmpc, sitl, ftc, perception, lio, planner, nav, flatness, mars, campaign
  EXPECT_EQ(Cli("bench").exit_code, 2);  // a benchmark or --list
}

TEST_F(CliTest, UsageErrorsExitTwo) {
  EXPECT_EQ(Cli("").exit_code, 2);
  EXPECT_EQ(Cli("fly").exit_code, 2);
  EXPECT_EQ(Cli("run").exit_code, 2);
  EXPECT_EQ(Cli("run a.yaml --no-such-flag").exit_code, 2);
}

TEST_F(CliTest, HoverRunSucceedsAndWritesLogAndSummary) {
  const std::string s = Write("hover.yaml", Scenario(kVehicle));
  const Result r = Cli("run " + s + " --out " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("success"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(ReadText(fs::path(Out()) / "summary.json"));
  for (const char* key :
       {"scenario", "seed", "success", "crashed", "crash_reason", "sim_time_s", "wall_time_s", "realtime_factor",
        "stack_realtime_factor", "tracking_rmse_m", "tracking_rmse_window_m", "tracking_window_s",
        "max_position_error_m", "min_altitude_m", "max_spin_rad_s", "faults", "fdd"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["seed"], 3);
  EXPECT_EQ(j["success"], true);
  EXPECT_TRUE(j["fdd"].is_null());
  EXPECT_NEAR(j["sim_time_s"].get<double>(), 1.0, 1e-9);
  // Where the wall-clock time went: every part present (each is a duration, or clamped at zero),
  // and no LiDAR hence no mapping (runner_test checks the mapper and planner are timed when they
  // run).
  for (const char* part : {"simulator", "odometry", "mapper", "planner", "controller", "stack_other", "runner"}) {
    ASSERT_TRUE(j["cost_ms_per_sim_s"][part].is_number()) << part;
  }
  EXPECT_EQ(j["cost_ms_per_sim_s"]["mapper"].get<double>(), 0.0);
  EXPECT_GT(j["cost_ms_per_sim_s"]["controller"].get<double>(), 0.0);
  const std::string log = ReadText(fs::path(Out()) / "log.csv");
  EXPECT_EQ(log.rfind("t,p_x,p_y,p_z", 0), 0u);
  // 100 Hz over 1 s plus the header and the final row.
  EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 102);
}

TEST_F(CliTest, FddCalibrateReplaysRunFoldersAndRejectsBadOnes) {
  const std::string fault_free = Write("free.yaml", Scenario(kVehicle, "stack: {controller: nmpc, fdd: composite}\n"));
  const std::string faulty = Write("faulty.yaml", Scenario(kVehicle,
                                                           "faults:\n"
                                                           "  - {rotor: 1, kind: motor_stop, onset: {at_time_s: 0.5}}\n"
                                                           "stack: {controller: nmpc, fdd: composite}\n"));
  ASSERT_EQ(Cli("run " + fault_free + " --quiet --out " + Out() + "/free").exit_code, 0);
  Cli("run " + faulty + " --quiet --out " + Out() + "/faulty");  // a 1 s flight: the outcome does not matter
  const Result r = Cli("fdd-calibrate " + Out() + "/free " + Out() + "/faulty --out " + Out() + "/cal");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("2 logs (1 faulty, 1 fault-free)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("### motor_index_threshold"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(ReadText(fs::path(Out()) / "cal" / "calibration.json"));
  EXPECT_EQ(j["sweeps"].size(), 4u);
  EXPECT_EQ(j["logs"][1]["with_configured_thresholds"]["correct"], true);
  // --write: the thresholds with the suggestions applied, a file a vehicle file names with `fdd:`.
  const Result w = Cli("fdd-calibrate " + Out() + "/free " + Out() + "/faulty --write " + Out() + "/thresholds.yaml");
  ASSERT_EQ(w.exit_code, 0) << w.out;
  const std::string vehicle = Write(
      "calibrated.yaml", rotorguard::testing::ReferenceVehicleWithoutFdd() + "fdd: " + Out() + "/thresholds.yaml\n");
  const std::string flown =
      Write("calibrated_run.yaml", Scenario(vehicle, "stack: {controller: nmpc, fdd: composite}\n"));
  ASSERT_EQ(Cli("run " + flown + " --quiet --no-report --out " + Out() + "/calibrated").exit_code, 0);
  const nlohmann::json used = nlohmann::json::parse(ReadText(fs::path(Out()) / "calibrated" / "summary.json"));
  int applied = 0;
  for (const auto& sw : j["sweeps"]) {
    if (sw["suggested"].is_null()) continue;
    EXPECT_EQ(used["composite_fdd"][sw["threshold"].get<std::string>()], sw["suggested"]["value"]) << sw.dump();
    ++applied;
  }
  EXPECT_GT(applied, 0);

  EXPECT_EQ(Cli("fdd-calibrate " + Out() + "/free --margin 1").exit_code, 2);
  EXPECT_EQ(Cli("fdd-calibrate").exit_code, 2);
  const Result missing = Cli("fdd-calibrate " + Out() + "/no_such_run");
  EXPECT_EQ(missing.exit_code, 3);
  EXPECT_NE(missing.out.find("no such folder"), std::string::npos) << missing.out;
  // --healthy takes campaign folders: a run folder has no campaign manifest.
  const Result not_campaign = Cli("fdd-calibrate --healthy " + Out() + "/free");
  EXPECT_EQ(not_campaign.exit_code, 3) << not_campaign.out;
  EXPECT_NE(not_campaign.out.find("manifest"), std::string::npos) << not_campaign.out;
  // A sensor log cut in the middle of a line: exit 3, naming the file, line and byte.
  const fs::path sensors = fs::path(Out()) / "free" / "sensors.csv";
  const std::string text = ReadText(sensors);
  const std::size_t line_start = text.find('\n', text.size() / 2) + 1;
  std::ofstream(sensors, std::ios::binary | std::ios::trunc) << text.substr(0, line_start + 5);  // mid-line
  const Result cut = Cli("fdd-calibrate " + Out() + "/free");
  EXPECT_EQ(cut.exit_code, 3);
  EXPECT_TRUE(std::regex_search(cut.out, std::regex("sensors.csv: cannot read input file: line [0-9]+ \\(byte [0-9]+\\)")))
      << cut.out;
}

// A navigate mission whose waypoint lies just behind a box's face (mapped by the LiDAR, never told
// to the stack, so the goal falls in the face's inflation) or above the planner's altitude band (a
// goal merely beyond the map's window is flown towards through local goals): the run ends in its
// scenario time with exit 4 (an infeasible request) and names the waypoint and the planner's status.
TEST_F(CliTest, UnreachableWaypointExitsFourNamingIt) {
  for (const auto& [waypoint, status] : {std::pair{"[1.6, 0.0, 1.0]", "goal_blocked"},
                                         std::pair{"[1.0, 0.0, 10.0]", "goal_out_of_bounds"}}) {
    std::string text = Scenario(kVehicle, std::string("world:\n  boxes:\n    - {center_m: [2, 0, 1.5], size_m: [1, 1, 3]}\n") +
                                              "sensors:\n  lidar: {}\n");
    text.replace(text.find("duration_s: 1.0"), 15, "duration_s: 1.5");
    const std::string hover = "mission:\n  type: hover";
    text.replace(text.find(hover), hover.size(), std::string("mission: {type: navigate, waypoints_m: [") + waypoint + "]}");
    const std::string f = Write("unreachable.yaml", text);
    const Result r = Cli("run " + f + " --out " + Out());
    EXPECT_EQ(r.exit_code, 4) << r.out;
    EXPECT_NE(r.out.find("waypoint 1"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("unreachable"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(status), std::string::npos) << r.out;
    const nlohmann::json j = nlohmann::json::parse(ReadText(fs::path(Out()) / "summary.json"));
    EXPECT_EQ(j["navigation"]["infeasible_request"], true);
    EXPECT_EQ(j["crashed"], false);
  }
}

TEST_F(CliTest, NominalControllerLosingAMotorCrashesAndExitsOne) {
  const std::string s = rotorguard::testing::SourcePath("configs/scenarios/hover_motor_stop_nominal.yaml");
  const Result r = Cli("run " + s + " --quiet --out " + Out());
  EXPECT_EQ(r.exit_code, 1) << r.out;
  const nlohmann::json j = nlohmann::json::parse(ReadText(fs::path(Out()) / "summary.json"));
  EXPECT_EQ(j["crashed"], true);
  EXPECT_EQ(j["success"], false);
  EXPECT_NE(j["crash_reason"].get<std::string>().find("ground impact"), std::string::npos);
  ASSERT_EQ(j["faults"].size(), 1u);
  EXPECT_EQ(j["faults"][0]["rotor"], 0);
  EXPECT_EQ(j["faults"][0]["kind"], "motor_stop");
  EXPECT_NEAR(j["faults"][0]["onset_s"].get<double>(), 2.0, 1e-9);
}

TEST_F(CliTest, AFlightThatEndsFarFromItsReferenceFailsWithExitOne) {
  // A 30 m/s wind blows the vehicle away without a crash: the mission failed all the same.
  const std::string s = Write("windy.yaml", Scenario(kVehicle, "wind: {mean_m_s: [30.0, 0.0, 0.0]}\n"));
  const Result r = Cli("run " + s + " --out " + Out());
  EXPECT_EQ(r.exit_code, 1) << r.out;
  const nlohmann::json j = nlohmann::json::parse(ReadText(fs::path(Out()) / "summary.json"));
  EXPECT_EQ(j["success"], false);
  EXPECT_EQ(j["crashed"], false);
  EXPECT_NE(j["failure_reason"].get<std::string>().find("position error"), std::string::npos) << j.dump();
}

TEST_F(CliTest, SameSeedGivesAnIdenticalLogDifferentSeedsDiffer) {
  const std::string s = Write("s.yaml", Scenario(kVehicle, "wind: {gust_std_m_s: 0.5}\n"));
  ASSERT_EQ(Cli("run " + s + " --quiet --out " + Out() + "/a").exit_code, 0);
  ASSERT_EQ(Cli("run " + s + " --quiet --out " + Out() + "/b").exit_code, 0);
  ASSERT_EQ(Cli("run " + s + " --quiet --seed 4 --out " + Out() + "/c").exit_code, 0);
  const std::string a = ReadText(fs::path(Out()) / "a/log.csv");
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, ReadText(fs::path(Out()) / "b/log.csv"));
  EXPECT_NE(a, ReadText(fs::path(Out()) / "c/log.csv"));
}

TEST_F(CliTest, SetOverridesScenarioAndVehicleValues) {
  const std::string s = Write("s.yaml", Scenario(kVehicle));
  const Result r = Cli("run " + s + " --quiet --set duration_s=0.5 --set vehicle.mass_kg=1.3 --out " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json j = nlohmann::json::parse(ReadText(fs::path(Out()) / "summary.json"));
  EXPECT_NEAR(j["sim_time_s"].get<double>(), 0.5, 1e-9);
}

TEST_F(CliTest, BadScenarioContentExitsTwoNamingFileLineAndKey) {
  const std::string v = kVehicle;
  // Line numbers: 1 vehicle, 2 duration_s, 3 seed, 4 initial, 5 position_m, 6 mission, 7 type, 8+ extra.
  std::string f = Write("unknown.yaml", Scenario(v, "durations_s: 3\n"));
  ExpectConfigError("run " + f, f, 8, {"durations_s", "unknown key"});
  f = Write("dup.yaml", Scenario(v, "duration_s: 2.0\n"));
  ExpectConfigError("run " + f, f, 8, {"duplicate key", "duration_s"});
  f = Write("missing.yaml", "vehicle: " + v + "\nmission:\n  type: hover\n");
  ExpectConfigError("run " + f, f, 1, {"duration_s", "missing"});
  f = Write("nan.yaml", Scenario(v, "wind: {gust_std_m_s: .nan}\n"));
  ExpectConfigError("run " + f, f, 8, {"wind.gust_std_m_s", "finite"});
  f = Write("inf.yaml", Scenario(v, "wind: {gust_std_m_s: .inf}\n"));
  ExpectConfigError("run " + f, f, 8, {"wind.gust_std_m_s", "finite"});
  f = Write("unit.yaml", Scenario(v, "sim: {physics_rate_hz: 1kHz}\n"));
  ExpectConfigError("run " + f, f, 8, {"sim.physics_rate_hz", "1kHz"});
  f = Write("rotor.yaml", Scenario(v, "faults:\n  - {rotor: 7, kind: motor_stop, onset: {at_time_s: 0.5}}\n"));
  ExpectConfigError("run " + f, f, 9, {"faults.0.rotor", "[0, 3]"});
  f = Write("onset.yaml", Scenario(v, "faults:\n  - rotor: 1\n    kind: propeller_loss\n    onset: {at_time_s: 5.0}\n"));
  ExpectConfigError("run " + f, f, 11, {"faults.0.onset.at_time_s", "duration_s"});
  f = Write("kind.yaml", Scenario(v, "faults:\n  - {rotor: 1, kind: melted, onset: {at_time_s: 0.5}}\n"));
  ExpectConfigError("run " + f, f, 9, {"faults.0.kind", "motor_stop"});
  f = Write("below.yaml", Scenario(v, "  position_m: [0, 0, -1]\n"));  // extends the mission map
  ExpectConfigError("run " + f, f, 7, {"below the ground"});
  f = Write("takeoff.yaml", Scenario(v, "faults:\n  - {rotor: 1, kind: motor_stop, onset: {during_takeoff_s: 0.1}}\n"));
  ExpectConfigError("run " + f, f, 9, {"faults.0.onset.during_takeoff_s", "on the ground"});
  f = Write("rate.yaml", Scenario(v, "stack: {control_rate_hz: 5000}\n"));
  ExpectConfigError("run " + f, f, 8, {"stack.control_rate_hz", "physics rate"});
  f = Write("map.yaml", Scenario(v, "stack:\n  map: {resolution_m: 0.1, log_odds_max: 40}\n"));
  ExpectConfigError("run " + f, f, 9, {"stack.map.log_odds_max", "40", "(0, 30]"});
  f = Write("hysteresis.yaml", Scenario(v, "stack:\n  map: {window_size_m: [8, 8, 1.6], recenter_hysteresis_m: 0.5}\n"));
  ExpectConfigError("run " + f, f, 9, {"stack.map.recenter_hysteresis_m", "0.5", "a quarter of the smallest window extent"});
  f = Write("margin.yaml", Scenario(v, "stack:\n  map: {inflation_margin_m: -0.1}\n"));
  ExpectConfigError("run " + f, f, 9, {"stack.map.inflation_margin_m", "-0.1", "in [0, 10]"});
  f = Write("planner.yaml", Scenario(v, "stack:\n  planner: {v_max: -1}\n"));
  ExpectConfigError("run " + f, f, 9, {"stack.planner", "v_max", "in [0.001, 50]"});
  std::string navigate = Scenario(v);
  const std::string hover = "mission:\n  type: hover";
  navigate.replace(navigate.find(hover), hover.size(), "mission: {type: navigate, waypoints_m: [[1, 0, 1]]}");
  f = Write("navigate.yaml", navigate);
  ExpectConfigError("run " + f, f, 6, {"mission", "sensors.lidar"});
  f = Write("mapkey.yaml", Scenario(v, "stack:\n  map: {inflation_radius_m: 0.3}\n"));
  ExpectConfigError("run " + f, f, 9, {"stack.map.inflation_radius_m", "unknown key"});
  f = Write("malformed.yaml", "vehicle: " + v + "\nduration_s: [1, 2\nmission: {type: hover}\n");
  {
    const Result r = Cli("run " + f);
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_NE(r.out.find(f + ":"), std::string::npos) << r.out;
  }
  f = Write("empty.yaml", "");
  ExpectConfigError("run " + f, f, 1, {"empty"});
  f = Write("comments.yaml", "# nothing here\n");
  ExpectConfigError("run " + f, f, 1, {"empty"});
}

TEST_F(CliTest, BadVehicleContentExitsTwoNamingTheVehicleFile) {
  std::string v = VehicleWith("mass_kg: 1.15", "mass_kg: -1.15");
  std::string s = Write("s.yaml", Scenario(v));
  ExpectConfigError("run " + s, v, 5, {"mass_kg", "-1.15"});
  v = VehicleWith("mass_kg: 1.15", "mass_kg: 1.5kg");
  s = Write("s.yaml", Scenario(v));
  ExpectConfigError("run " + s, v, 5, {"mass_kg", "1.5kg"});
  v = VehicleWith("[0.0, 0.0, 8.650e-3]", "[0.0, 0.0, -8.650e-3]");
  s = Write("s.yaml", Scenario(v));
  ExpectConfigError("run " + s, v, 7, {"inertia_kg_m2", "positive definite"});
  v = VehicleWith("[0.0, 0.0, 8.650e-3]", "[0.0, 0.0, 14.0e-3]");  // above I_xx + I_yy: no body has it
  s = Write("s.yaml", Scenario(v));
  ExpectConfigError("run " + s, v, 7, {"inertia_kg_m2", "each principal moment at most the sum of the other two"});
  v = Write("v.yaml", std::regex_replace(ReadText(kVehicle), std::regex("max_thrust_n: 11.5"), "max_thrust_n: 2.5"));
  s = Write("s.yaml", Scenario(v));
  const Result r = Cli("run " + s);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("thrust-to-weight"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(v + ":"), std::string::npos) << r.out;
  v = Write("v.yaml", std::regex_replace(ReadText(kVehicle), std::regex("yaw_coefficient_m: 0.0107"), "yaw_coefficient_m: 0.0"));
  s = Write("s.yaml", Scenario(v));
  const Result rank = Cli("run " + s);
  EXPECT_EQ(rank.exit_code, 2) << rank.out;
  EXPECT_NE(rank.out.find("independent thrust"), std::string::npos) << rank.out;
  // The sensor default clashes with a slow physics rate: reported at the sensors key path.
  const std::string slow = Write("slow.yaml", Scenario(kVehicle, "sim: {physics_rate_hz: 500}\n"));
  ExpectConfigError("run " + slow, slow, 1, {"sensors.esc.rate_hz", "[0.01, 500]"});
}

TEST_F(CliTest, SetOnAPathThatDoesNotExistExitsTwo) {
  const std::string s = Write("s.yaml", Scenario(kVehicle));
  for (const char* set : {"durationn_s=3", "mission.speed=2", "vehicle.masss_kg=1", "faults.0.rotor=1", "novalue"}) {
    const Result r = Cli("run " + s + " --set " + set);
    EXPECT_EQ(r.exit_code, 2) << set << ": " << r.out;
    EXPECT_NE(r.out.find("--set"), std::string::npos) << set << ": " << r.out;
  }
  // An existing path given a bad value is reported against --set.
  const Result r = Cli("run " + s + " --set duration_s=abc");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("duration_s"), std::string::npos) << r.out;
}

TEST_F(CliTest, NumericOptionsRejectNonFiniteNegativeAndGarbage) {
  const std::string s = Write("s.yaml", Scenario(kVehicle));
  const auto expect_usage_error = [&](const std::string& args) {
    const Result r = Cli(args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.out;
    EXPECT_NE(r.out.find("invalid"), std::string::npos) << args << ": " << r.out;
  };
  for (const std::string bad : {"nan", "inf", "1e999", "-1", "abc", ""}) {
    expect_usage_error("run " + s + " --quiet --seed '" + bad + "' --out " + Out());
    expect_usage_error("bench sim --scenario " + s + " --duration '" + bad + "'");
    expect_usage_error("bench sim --scenario " + s + " --repetitions '" + bad + "'");
    expect_usage_error("bench perception --duration '" + bad + "'");
    expect_usage_error("bench perception --seed '" + bad + "'");
    expect_usage_error("bench planner --pairs '" + bad + "'");
    expect_usage_error("bench planner --seed '" + bad + "'");
  }
  expect_usage_error("bench planner --pairs 0");
  expect_usage_error("bench planner --pairs 4 --worlds 5");
  // Integers only where a count is expected.
  expect_usage_error("run " + s + " --quiet --seed 1.5 --out " + Out());
  expect_usage_error("bench sim --scenario " + s + " --repetitions 1.5");
}

TEST_F(CliTest, UnreadableInputExitsThree) {
  const Result r = Cli("run " + (dir_ / "no_such_file.yaml").string());
  EXPECT_EQ(r.exit_code, 3) << r.out;
  EXPECT_NE(r.out.find("no_such_file.yaml"), std::string::npos);
  EXPECT_EQ(Cli("validate " + dir_.string()).exit_code, 3);  // a folder is not a file
  // The scenario's vehicle file is missing: still an unreadable input, and the message says which
  // scenario line names it.
  const std::string s = Write("s.yaml", Scenario((dir_ / "missing_vehicle.yaml").string()));
  const Result v = Cli("run " + s);
  EXPECT_EQ(v.exit_code, 3) << v.out;
  EXPECT_NE(v.out.find("missing_vehicle.yaml"), std::string::npos) << v.out;
  EXPECT_NE(v.out.find(s + ":1"), std::string::npos) << v.out;
}

TEST_F(CliTest, ValidateChecksScenariosAndVehiclesWithoutFlying) {
  const Result ok = Cli("validate " + rotorguard::testing::SourcePath("configs/scenarios/lemniscate_2ms.yaml"));
  EXPECT_EQ(ok.exit_code, 0) << ok.out;
  EXPECT_NE(ok.out.find("valid scenario"), std::string::npos) << ok.out;
  const Result veh = Cli("validate " + kVehicle);
  EXPECT_EQ(veh.exit_code, 0) << veh.out;
  EXPECT_NE(veh.out.find("valid vehicle"), std::string::npos) << veh.out;
  const std::string bad = VehicleWith("collision_radius_m: 0.2", "collision_radius_m: 0.2\ncolision_radius_m: 0.3");
  EXPECT_EQ(Cli("validate " + bad).exit_code, 2);
}

TEST_F(CliTest, EveryShippedConfigValidates) {
  for (const auto& e : fs::recursive_directory_iterator(rotorguard::testing::SourcePath("configs"))) {
    if (e.path().extension() != ".yaml") continue;
    const Result r = Cli("validate " + e.path().string());
    EXPECT_EQ(r.exit_code, 0) << e.path() << ": " << r.out;
  }
}

TEST_F(CliTest, KilledRunLeavesNoSummaryThatLooksComplete) {
  const std::string s = Write("s.yaml", Scenario(kVehicle));
  fs::create_directories(Out());
  std::ofstream(fs::path(Out()) / "summary.json") << "{\"stale\": true}";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // A day, the longest flight a scenario takes: the run is killed long before its end.
    ::execl(ROTORGUARD_CLI, ROTORGUARD_CLI, "run", s.c_str(), "--quiet", "--set", "duration_s=86400", "--out",
            Out().c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Wait until the run has started writing, then kill it without warning.
  for (int i = 0; i < 200; ++i) {
    bool started = false;
    for (const auto& e : fs::directory_iterator(Out())) started |= e.path().filename().string().rfind("sensors.csv.tmp", 0) == 0;
    if (started) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_FALSE(fs::exists(fs::path(Out()) / "summary.json")) << "a stale or partial summary survived";
  EXPECT_FALSE(fs::exists(fs::path(Out()) / "log.csv")) << "a partial log carries the final name";
}

TEST_F(CliTest, RunWritesAReportAndReportRebuildsItFromCsvOrMcap) {
  const std::string s = Write("hover.yaml", Scenario(kVehicle));
  const Result r = Cli("run " + s + " --out " + Out() + " --log-format both");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (const char* f : {"log.csv", "scene.json", "sensors.csv", "flight.mcap", "summary.json", "report.html"}) {
    EXPECT_TRUE(fs::exists(fs::path(Out()) / f)) << f;
  }
  EXPECT_NE(r.out.find("report.html"), std::string::npos) << "the run prints the report's path";
  const std::string page = ReadText(fs::path(Out()) / "report.html");
  EXPECT_NE(page.find("rotorguard-data"), std::string::npos);
  // Rebuilt from the CSV log: the same page.
  fs::remove(fs::path(Out()) / "report.html");
  const Result rebuilt = Cli("report " + Out());
  ASSERT_EQ(rebuilt.exit_code, 0) << rebuilt.out;
  // The run's report came from the flight in memory, the rebuilt one from log.csv's 9 digits: the
  // same page but for a last-decimal rounding here and there.
  const auto data = [](const std::string& html) {
    const std::string tag = "type=\"application/json\">";
    const std::size_t a = html.find(tag) + tag.size();
    return nlohmann::json::parse(html.substr(a, html.find("</script>", a) - a));
  };
  nlohmann::json a = data(page), b = data(ReadText(fs::path(Out()) / "report.html"));
  for (const auto& [name, column] : a["series"].items()) {
    ASSERT_EQ(column.size(), b["series"][name].size()) << name;
    for (std::size_t i = 0; i < column.size(); ++i) {
      EXPECT_NEAR(column[i].get<double>(), b["series"][name][i].get<double>(), 1.01) << name;
      if (name.rfind("rpm_", 0) != 0) {
        EXPECT_NEAR(column[i].get<double>(), b["series"][name][i].get<double>(), 1.01e-4) << name;
      }
    }
  }
  a.erase("series");
  b.erase("series");
  EXPECT_EQ(a, b);
  // Rebuilt from the MCAP file alone (with the MCAP's exact numbers rather than the CSV's 9 digits).
  fs::remove(fs::path(Out()) / "log.csv");
  fs::remove(fs::path(Out()) / "scene.json");
  const std::string other = (fs::path(Out()) / "from_mcap.html").string();
  ASSERT_EQ(Cli("report " + Out() + " --out " + other).exit_code, 0);
  EXPECT_GT(ReadText(other).size(), 10000u);
}

TEST_F(CliTest, McapOnlyRunWritesNoCsv) {
  const std::string s = Write("hover.yaml", Scenario(kVehicle));
  const Result r = Cli("run " + s + " --out " + Out() + " --log-format mcap --no-report");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_TRUE(fs::exists(fs::path(Out()) / "flight.mcap"));
  for (const char* f : {"log.csv", "scene.json", "sensors.csv", "report.html"}) EXPECT_FALSE(fs::exists(fs::path(Out()) / f)) << f;
  const Result bad = Cli("run " + s + " --out " + Out() + " --log-format parquet");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.out.find("--log-format: 'parquet' is invalid; expected csv, mcap or both"), std::string::npos) << bad.out;
}

TEST_F(CliTest, ReportOfADamagedRunExitsThreeWithTheByteOffset) {
  const std::string s = Write("hover.yaml", Scenario(kVehicle));
  ASSERT_EQ(Cli("run " + s + " --out " + Out() + " --log-format both --quiet").exit_code, 0);
  const std::string log = ReadText(fs::path(Out()) / "log.csv");
  Write("out/log.csv", log.substr(0, log.size() - 5));
  const Result truncated = Cli("report " + Out());
  EXPECT_EQ(truncated.exit_code, 3) << truncated.out;
  EXPECT_NE(truncated.out.find("log.csv: corrupt at byte " + std::to_string(log.size() - 5)), std::string::npos)
      << truncated.out;
  // The MCAP file with one byte of a chunk changed: its CRC names the damage.
  fs::remove(fs::path(Out()) / "log.csv");
  std::string mcap = ReadText(fs::path(Out()) / "flight.mcap");
  mcap[mcap.size() / 3] ^= 0x20;
  Write("out/flight.mcap", mcap);
  const Result corrupt = Cli("report " + Out());
  EXPECT_EQ(corrupt.exit_code, 3) << corrupt.out;
  EXPECT_NE(corrupt.out.find("flight.mcap: corrupt at byte "), std::string::npos) << corrupt.out;
  EXPECT_EQ(Cli("report " + Out() + "/missing").exit_code, 3);
}

}  // namespace
