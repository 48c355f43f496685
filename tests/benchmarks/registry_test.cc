// The benchmarks on the campaign engine (campaign_kinds/registry.h): a benchmark run whole, in
// shards merged by `MergeCampaign`, or from its spec file gives one result; the results are built
// from the records as hand-made records say they must be; bad specs name the key.

#include "rotorguard/campaign_kinds/registry.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "rotorguard/campaign_kinds/flatness_bench.h"
#include "rotorguard/campaign_kinds/ftc_bench.h"
#include "rotorguard/campaign_kinds/nav_bench.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/merge.h"
#include "rotorguard/campaign/registry.h"
#include "rotorguard/campaign/slurm.h"
#include "rotorguard/campaign/statistics.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/json_archive.h"
#include "test_util.h"

namespace rotorguard::benchmarks {
namespace {

namespace fs = std::filesystem;

const std::string kConfigs = testing::SourcePath("configs");

/// The FTC benchmark at its smallest: one trial per cell, the project's method and the nominal
/// controller (18 flights of a few seconds each).
FtcBenchOptions SmallFtc() {
  FtcBenchOptions o;
  o.trials = 1;
  o.seed = 5;
  o.methods = {"rotorguard", "none"};
  o.vehicle = harness::LoadVehicle(kConfigs + "/vehicles/zhou2025_quad.yaml");
  o.fdd = harness::LoadVehicleFdd(kConfigs + "/vehicles/zhou2025_quad.yaml")->first;  // as `bench ftc` does
  o.truth = sim::TruthPreset::kIdeal;  // the figures below are the exact model's
  return o;
}

/// A record as RunCampaign writes it.
nlohmann::json Record(int trial, std::map<std::string, std::string> params, nlohmann::json metrics,
                      const std::string& status = "ok", const std::string& message = "") {
  return {{"trial", trial}, {"id", campaign::TrialId(params)}, {"params", params}, {"status", status}, {"message", message},
          {"metrics", metrics}};
}

class BenchCampaigns : public testing::TempFolderTest {};

TEST_F(BenchCampaigns, FtcInShardsMergesToTheResultOfOneRunAndItsSpecFileIsTheSameCampaign) {
  const campaign::Campaign c = FtcCampaign(SmallFtc());
  ASSERT_EQ(c.trials, 26 * 2);  // 26 cells (ftc_bench.cc, kCells), two methods
  // The adjacent double failure with a parachute flies the trials of the one without (a paired
  // comparison); every other cell its own.
  std::map<std::string, std::set<std::string>> seeds;
  for (int i = 0; i < c.trials; ++i) {
    const std::map<std::string, std::string> p = c.parameters(i);
    seeds[p.at("phase") + "/" + p.at("fault")].insert(p.at("seed"));
  }
  EXPECT_EQ(seeds.at("hover/motor_stop_then_adjacent_parachute"), seeds.at("hover/motor_stop_then_adjacent"));
  EXPECT_NE(seeds.at("hover/motor_stop_then_twin"), seeds.at("hover/motor_stop_then_adjacent"));
  // The propeller losses on a battery fly the trials of those without one.
  for (const std::string phase : {"hover", "tracking"}) {
    for (const std::string battery : {"_battery_full", "_battery_30"}) {
      EXPECT_EQ(seeds.at(phase + "/propeller_loss" + battery), seeds.at(phase + "/propeller_loss")) << phase << battery;
    }
  }
  // The take-off failures with the ground effect fly those without; only the ground effect differs.
  FtcBenchOptions small = SmallFtc();
  for (const std::string fault : {"propeller_loss", "motor_stop"}) {
    EXPECT_EQ(seeds.at("takeoff/" + fault + "_ground_effect"), seeds.at("takeoff/" + fault)) << fault;
    const harness::Scenario with = MakeFtcTrial("takeoff/" + fault + "_ground_effect", "rotorguard", small, 7);
    const harness::Scenario without = MakeFtcTrial("takeoff/" + fault, "rotorguard", small, 7);
    EXPECT_EQ(with.sim.ground_effect.strength, 1.0);
    EXPECT_EQ(without.sim.ground_effect.strength, 0.0);
    ASSERT_EQ(with.faults.size(), 1u);
    EXPECT_EQ(with.faults[0].rotor, without.faults[0].rotor);
    EXPECT_EQ(with.faults[0].onset.value, without.faults[0].onset.value);
  }
  // Whole, on two threads, in a temporary folder.
  campaign::CampaignRunOptions whole;
  whole.jobs = 2;
  const nlohmann::json direct = FtcResult(c.bench["options"], *campaign::RunCampaignRecords(c, whole));
  // In three shards in two folders, then merged: the merge writes the same benchmark result.
  for (int i = 0; i < 3; ++i) {
    campaign::CampaignRunOptions o;
    o.out_dir = (dir_ / (i < 2 ? "a" : "b")).string();
    o.shard = campaign::Shard{i, 3};
    o.version = "test";
    EXPECT_FALSE(campaign::RunCampaignRecords(c, o).has_value());  // one shard of several: nothing to report yet
  }
  const nlohmann::json merged = campaign::MergeCampaign({(dir_ / "a").string(), (dir_ / "b").string()}, (dir_ / "m").string(), CampaignKinds());
  ASSERT_TRUE(merged.contains("bench"));
  // The generic summary counts only the trials that record a metric: `none` runs no FDD.
  for (const auto& g : merged["by_grid_point"]) {
    EXPECT_EQ(g["metrics"]["correct"]["n"], g["grid"]["method"] == "none" ? 0 : 1) << g.dump();
  }
  EXPECT_EQ(merged["bench"]["cells"], direct["cells"]);
  EXPECT_EQ(io::ReadFile((dir_ / "m" / "bench.md").string()), FtcMarkdown(direct));
  // The benchmark's own figures: the project's method isolates every fault and flies every cell
  // but the one with two adjacent rotors lost, where it isolates both and stops the motors.
  for (const auto& cell : direct["cells"]) {
    if (cell["method"] != "rotorguard") continue;
    const bool adjacent = cell["fault"].get<std::string>().starts_with("motor_stop_then_adjacent");  // with a parachute too
    EXPECT_EQ(cell["sucr"], adjacent ? 0.0 : 1.0) << cell.dump();
    if (cell["fault"] != "none") {
      EXPECT_EQ(cell["mdr"], 0.0) << cell.dump();
    }
    if (adjacent) {
      EXPECT_EQ(cell["second_isolated"], 1.0) << cell.dump();
      EXPECT_EQ(cell["crashes"], 1) << cell.dump();
    }
  }
  // The same options written as a spec are the same campaign: the same trials and hash, so shards
  // run from the spec and from `bench ftc` merge together.
  const std::string spec = Write("ftc.yaml",
                                 "name: small_ftc\nbench: ftc\ntrials: 1\nseed: 5\n"
                                 "methods: [rotorguard, none]\nvehicle: " +
                                     kConfigs + "/vehicles/zhou2025_quad.yaml\ntruth: ideal\n");
  const campaign::Campaign from_file = campaign::LoadCampaign(spec, CampaignKinds());
  EXPECT_EQ(from_file.hash, c.hash);
  EXPECT_EQ(from_file.trials, c.trials);
  EXPECT_EQ(from_file.name, "small_ftc");
  for (int i = 0; i < c.trials; ++i) EXPECT_EQ(from_file.parameters(i), c.parameters(i));
  // Any change of what the trials depend on is another campaign.
  FtcBenchOptions heavier = SmallFtc();
  heavier.vehicle.mass_kg *= 1.01;
  EXPECT_NE(FtcCampaign(heavier).hash, c.hash);
}

TEST_F(BenchCampaigns, FtcFliesTheVehiclesOwnFddThresholds) {
  // Thresholds nothing can reach: with them, no isolation.
  Write("disarmed.yaml",
        "motor_index_threshold: 0.01\nmotor_index_samples: 1000\npropeller_index_threshold: 1.0\n"
        "propeller_persistence_s: 10\ntakeoff_index_threshold: 1000\n");
  Write("quad.yaml", rotorguard::testing::ReferenceVehicleWithoutFdd() + "fdd: disarmed.yaml\n");
  const auto spec = [&](const std::string& vehicle) {
    return Write(
        "ftc_" + std::to_string(vehicle.size()) + ".yaml",
        "name: f\nbench: ftc\ntrials: 1\nseed: 5\nmethods: [rotorguard]\nvehicle: " + vehicle + "\ntruth: ideal\n");
  };
  const campaign::Campaign own = campaign::LoadCampaign(spec("quad.yaml"), CampaignKinds());
  const campaign::Campaign shipped =
      campaign::LoadCampaign(spec(kConfigs + "/vehicles/zhou2025_quad.yaml"), CampaignKinds());
  EXPECT_NE(own.hash, shipped.hash);
  EXPECT_EQ(own.bench["options"]["fdd"]["propeller_index_threshold"], 1.0);
  EXPECT_EQ(shipped.bench["options"]["fdd"],
            io::ToJson(harness::LoadVehicleFdd(kConfigs + "/vehicles/zhou2025_quad.yaml")->first));
  // Trial 0 is a propeller lost in hover: the shipped thresholds isolate it, the disarmed ones do not.
  EXPECT_EQ(shipped.run(0, shipped.parameters(0)).metrics["correct"], true);
  EXPECT_EQ(own.run(0, own.parameters(0)).metrics["correct"], false);
}

TEST_F(BenchCampaigns, FtcResultCountsAnErroredTrialAsAFailure) {
  FtcBenchOptions o = SmallFtc();
  o.methods = {"none"};
  const campaign::Campaign c = FtcCampaign(o);
  std::vector<nlohmann::json> records;
  for (int i = 0; i < c.trials; ++i) {
    records.push_back(Record(i, c.parameters(i), {{"success", true}, {"altitude_change_m", -0.01}}));
  }
  records[0] = Record(0, c.parameters(0), nullptr, "error", "boom");
  const nlohmann::json r = FtcResult(c.bench["options"], records);
  EXPECT_EQ(r["errors"], 1);
  EXPECT_EQ(r["cells"][0]["sucr"], 0.0);  // cell 0 is its one trial, the errored one
  EXPECT_EQ(r["cells"][0]["failures"][0]["reason"], "error: boom");
  EXPECT_EQ(r["cells"][1]["sucr"], 1.0);
  records.pop_back();
  RG_EXPECT_THROW_WITH(FtcResult(c.bench["options"], records), std::invalid_argument, "25 trial records");
}

/// The nav benchmark's campaign of `trials` rooms, each flown by both variants.
campaign::Campaign RoomNavCampaign(int trials) {
  NavBenchOptions o;
  o.trials = trials;
  o.kinds = {"room"};
  o.base = harness::LoadScenario(kConfigs + "/scenarios/forest.yaml");
  return NavCampaign(o);
}

TEST_F(BenchCampaigns, NavResultAggregatesHandMadeRecords) {
  const campaign::Campaign c = RoomNavCampaign(2);
  ASSERT_EQ(c.trials, 4);  // (trial, variant): rotorguard, failure_unaware, rotorguard, failure_unaware
  EXPECT_EQ(c.parameters(0).at("seed"), c.parameters(1).at("seed"));  // both variants fly one world
  EXPECT_NE(c.parameters(0).at("seed"), c.parameters(2).at("seed"));
  const auto metrics = [](bool success, bool collision, double rmse, nlohmann::json time) {
    nlohmann::json m{{"success", success},      {"crashed", collision},
                     {"collision", collision},  {"tracking_rmse_m", rmse},
                     {"max_spin_rad_s", 11.0},  {"mission_time_s", time},
                     {"planner_ms_mean", 2.0},  {"stack_ms_per_cycle_mean", 0.5},
                     {"realtime_factor", 10.0}, {"trial_realtime_factor", rmse * 100.0}};
    // The wall-clock parts of a run (ms per simulated second), the simulator's differing by trial.
    for (const char* part : {"odometry", "mapper", "planner", "controller", "stack_other", "runner"}) {
      m[fmt::format("cost_{}_ms_per_sim_s", part)] = 10.0;
    }
    m["cost_simulator_ms_per_sim_s"] = rmse * 1000.0;
    return m;
  };
  const std::vector<nlohmann::json> records = {
      Record(0, c.parameters(0), metrics(true, false, 0.05, 30.0)),
      Record(1, c.parameters(1), metrics(false, true, 0.20, nullptr), "ok", "crash: collision with a box"),
      Record(2, c.parameters(2), metrics(true, false, 0.07, 34.0)),
      Record(3, c.parameters(3), nullptr, "diverged", "a metric is not finite")};
  const nlohmann::json r = NavResult(c.bench["options"], records);
  EXPECT_EQ(r["rotorguard"]["success_rate"], 1.0);
  EXPECT_NEAR(r["rotorguard"]["tracking_rmse_m"].get<double>(), 0.06, 1e-12);
  EXPECT_NEAR(r["rotorguard"]["mission_time_s"].get<double>(), 32.0, 1e-12);
  EXPECT_NEAR(r["rotorguard"]["cost_ms_per_sim_s"]["simulator"].get<double>(), 60.0, 1e-9);  // (50 + 70) / 2
  EXPECT_NEAR(r["rotorguard"]["cost_ms_per_sim_s"]["runner"].get<double>(), 10.0, 1e-12);
  EXPECT_NEAR(r["rotorguard"]["realtime_factor"].get<double>(), 10.0, 1e-12);       // the stack's
  EXPECT_NEAR(r["rotorguard"]["trial_realtime_factor"].get<double>(), 6.0, 1e-12);  // (5 + 7) / 2
  EXPECT_EQ(r["failure_unaware"]["success_rate"], 0.0);
  EXPECT_EQ(r["failure_unaware"]["collision_rate"], 0.5);   // the diverged trial did not report one
  EXPECT_TRUE(r["failure_unaware"]["mission_time_s"].is_null());  // neither completed
  ASSERT_EQ(r["failure_unaware"]["failures"].size(), 2u);
  EXPECT_EQ(r["failure_unaware"]["failures"][1]["reason"], "diverged: a metric is not finite");
  EXPECT_EQ(r["groups"]["room"]["rotorguard"], r["rotorguard"]);
  // Paired on the two worlds: rotorguard alone succeeded in both; p = 2 C(2, 0) / 2^2 = 0.5.
  EXPECT_EQ(r["paired"]["only_rotorguard"], 2);
  EXPECT_EQ(r["paired"]["only_failure_unaware"], 0);
  EXPECT_EQ(r["paired"]["success_difference"], 1.0);
  EXPECT_EQ(r["paired"]["mcnemar_exact_p"], 0.5);
  EXPECT_EQ(r["groups"]["room"]["paired"], r["paired"]);
  EXPECT_NEAR(r["rotorguard"]["success_wilson95"][0].get<double>(), campaign::WilsonInterval(2, 2).first, 1e-15);
}

// A record edited by hand so that an "ok" trial lacks a metric (or its params their seed) is an
// error that names the key, not a read past the record.
TEST_F(BenchCampaigns, NavResultRefusesARecordWithoutItsMetricsNamingTheKey) {
  const campaign::Campaign c = RoomNavCampaign(1);
  ASSERT_EQ(c.trials, 2);
  std::vector<nlohmann::json> records = {Record(0, c.parameters(0), {{"crashed", false}}),
                                         Record(1, c.parameters(1), nullptr, "error", "boom")};
  try {
    NavResult(c.bench["options"], records);
    ADD_FAILURE() << "a record without its success read";
  } catch (const nlohmann::json::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("'success'"), std::string::npos) << e.what();
  }
  records[0] = Record(0, c.parameters(0), nullptr, "error", "boom");
  records[0]["params"].erase("seed");
  EXPECT_THROW(NavResult(c.bench["options"], records), nlohmann::json::out_of_range);
}

// Thirteen failed flights of one variant: ten are listed with their seeds, the other three are
// counted, in the JSON and in the Markdown, rather than dropped.
TEST_F(BenchCampaigns, NavResultCountsTheFailuresItDoesNotList) {
  const campaign::Campaign c = RoomNavCampaign(13);
  ASSERT_EQ(c.trials, 26);
  std::vector<nlohmann::json> records;
  for (int i = 0; i < c.trials; ++i) records.push_back(Record(i, c.parameters(i), nullptr, "error", "boom"));
  const nlohmann::json r = NavResult(c.bench["options"], records);
  EXPECT_EQ(r["rotorguard"]["failures"].size(), 10u);
  EXPECT_EQ(r["rotorguard"]["failures_not_listed"], 3);
  EXPECT_EQ(r["failure_unaware"]["failures_not_listed"], 3);
  const std::string md = NavMarkdown(r);
  EXPECT_NE(md.find("rotorguard failed: 3 more, not listed"), std::string::npos) << md;
  EXPECT_NE(md.find("failure_unaware failed: 3 more, not listed"), std::string::npos) << md;
}

TEST_F(BenchCampaigns, FlatnessInShardsMergesToTheResultOfOneRunAndItsSpecFileIsTheSameCampaign) {
  FlatnessBenchOptions o;
  o.trials = 2;
  o.seed = 3;
  o.fig2 = harness::LoadScenario(kConfigs + "/scenarios/flatness_fig2.yaml");
  o.truth = sim::TruthPreset::kIdeal;
  o.jobs = 2;
  const campaign::Campaign c = FlatnessCampaign(o);
  ASSERT_EQ(c.trials, 3);  // Fig. 1's closed forms, then one trial per flight
  const nlohmann::json direct = RunFlatnessBenchmark(o);  // whole, on two threads, in a temporary folder
  // Paper 004's figures (docs/flatness.md): Fig. 1's 5.46 s, and in the exact world the UKF
  // identifies the 40 % loss and every flight arrives.
  EXPECT_NEAR(direct["ts_envelope_s"].get<double>(), 5.46, 0.005);
  EXPECT_EQ(direct["success_rate"], 1.0) << direct["failures"].dump();
  EXPECT_EQ(direct["ukf_identified_rate"], 1.0) << direct["ukf_w_estimate_range"].dump();
  EXPECT_EQ(direct["replanned_rate"], 1.0);
  for (int i = 0; i < 2; ++i) {
    campaign::CampaignRunOptions shard;
    shard.out_dir = (dir_ / "s").string();
    shard.shard = campaign::Shard{i, 2};
    shard.version = "test";
    EXPECT_FALSE(campaign::RunCampaignRecords(c, shard).has_value());
  }
  const nlohmann::json merged =
      campaign::MergeCampaign({(dir_ / "s").string()}, (dir_ / "m").string(), CampaignKinds());
  nlohmann::json a = merged["bench"], b = direct;
  a.erase("host");
  b.erase("host");
  EXPECT_EQ(a, b);
  EXPECT_EQ(io::ReadFile((dir_ / "m" / "bench.md").string()), FlatnessMarkdown(direct));
  const campaign::Campaign from_file = campaign::LoadCampaign(
      Write("f.yaml", "name: f\nbench: flatness\ntrials: 2\nseed: 3\ntruth: ideal\nfig2: " + kConfigs +
                          "/scenarios/flatness_fig2.yaml\n"),
      CampaignKinds());
  EXPECT_EQ(from_file.hash, c.hash);
  for (int i = 0; i < c.trials; ++i) EXPECT_EQ(from_file.parameters(i), c.parameters(i));
}

TEST_F(BenchCampaigns, AFlatnessFlightPastItsBudgetIsAFailureNamingTheCommandThatFliesIt) {
  FlatnessBenchOptions o;
  o.trials = 1;
  o.fig2 = harness::LoadScenario(kConfigs + "/scenarios/flatness_fig2.yaml");
  const campaign::Campaign c = FlatnessCampaign(o);
  campaign::CampaignRunOptions run;
  run.trial_timeout_factor = 1e-6;  // 0.12 ms for the two 60-s flights: none can finish
  const std::vector<nlohmann::json> records = *campaign::RunCampaignRecords(c, run);
  EXPECT_EQ(records[0]["status"], "ok");  // the closed forms run without a budget
  EXPECT_EQ(records[1]["status"], "timeout");
  const nlohmann::json r = FlatnessResult(c.bench["options"], records);
  EXPECT_EQ(r["success_rate"], 0.0);
  ASSERT_EQ(r["failures"].size(), 1u);
  const std::string seed = std::to_string(TrialSeed(o.seed, "bench flatness", 0));
  EXPECT_NE(r["failures"][0]["reason"].get<std::string>().find("rotorguard run " + o.fig2.file + " --seed " + seed +
                                                               " --set truth=realistic"),
            std::string::npos)
      << r["failures"][0].dump();
  EXPECT_TRUE(r["ukf_w_estimate"].is_null());  // no flight, no median
}

TEST_F(BenchCampaigns, ASpecsTruthIsTheSameCampaignAsTheFlag) {
  // `truth: realistic` in a spec is `bench ftc --truth realistic`: the same options, the same hash.
  const std::string spec = "name: t\nbench: ftc\ntrials: 1\nseed: 5\nmethods: [rotorguard, none]\nvehicle: " + kConfigs +
                           "/vehicles/zhou2025_quad.yaml\n";
  FtcBenchOptions o = SmallFtc();
  o.truth = sim::TruthPreset::kRealistic;
  const campaign::Campaign from_spec = campaign::LoadCampaign(Write("t.yaml", spec + "truth: realistic\n"), CampaignKinds());
  EXPECT_EQ(from_spec.hash, FtcCampaign(o).hash);
  EXPECT_EQ(from_spec.bench["options"]["truth"], "realistic");
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("u.yaml", spec + "truth: perfect\n"), CampaignKinds()),
                       io::ConfigError, "truth: 'perfect' is not allowed; expected one of: ideal, realistic");
}

TEST_F(BenchCampaigns, ANavSpecsEstimatorIsTheSameCampaignAsTheFlagAndOverridesTheBase) {
  // The benchmark flies the stack's LiDAR-inertial odometry unless told otherwise, whatever the
  // base says, and `estimator: odometry` is `bench nav --estimator odometry`.
  const std::string spec =
      "name: n\nbench: nav\ntrials: 1\nkinds: [room]\nbase: " + kConfigs + "/scenarios/forest.yaml\n";
  NavBenchOptions o;
  o.trials = 1;
  o.kinds = {"room"};
  o.base = harness::LoadScenario(kConfigs + "/scenarios/forest.yaml");
  ASSERT_EQ(o.estimator, stack::EstimatorKind::kLio);
  const campaign::Campaign lio = campaign::LoadCampaign(Write("n.yaml", spec), CampaignKinds());
  EXPECT_EQ(lio.bench["options"]["estimator"], "lio");
  EXPECT_EQ(lio.hash, NavCampaign(o).hash);
  o.estimator = stack::EstimatorKind::kOdometry;
  o.base.stack.estimator.kind = stack::EstimatorKind::kLio;  // overridden by the benchmark's
  const campaign::Campaign odometry =
      campaign::LoadCampaign(Write("l.yaml", spec + "estimator: odometry\n"), CampaignKinds());
  EXPECT_EQ(odometry.bench["options"]["estimator"], "odometry");
  EXPECT_EQ(odometry.hash, NavCampaign(o).hash);
  EXPECT_NE(lio.hash, odometry.hash);
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("m.yaml", spec + "estimator: gps\n"), CampaignKinds()),
                       io::ConfigError, "expected one of: odometry, lio");
}

// bench ftc flies the external odometry in open space unless told otherwise (its hash then is
// the one it had before the key existed); `estimator: lio` flies each trial in the hall with the
// LiDAR on and the stack on its own odometry, the trial's draws unchanged.
TEST_F(BenchCampaigns, AnFtcSpecsEstimatorFliesTheSameDrawsInTheHallOnTheLio) {
  const std::string vehicle = kConfigs + "/vehicles/zhou2025_quad.yaml";
  const std::string spec = "name: f\nbench: ftc\ntrials: 1\nmethods: [rotorguard]\nvehicle: " + vehicle + "\n";
  FtcBenchOptions o;
  o.trials = 1;
  o.methods = {"rotorguard"};
  o.vehicle = harness::LoadVehicle(vehicle);
  const campaign::Campaign odometry = campaign::LoadCampaign(Write("f.yaml", spec), CampaignKinds());
  EXPECT_FALSE(odometry.bench["options"].contains("estimator"));
  const campaign::Campaign lio = campaign::LoadCampaign(Write("g.yaml", spec + "estimator: lio\n"), CampaignKinds());
  EXPECT_EQ(lio.bench["options"]["estimator"], "lio");
  EXPECT_NE(lio.hash, odometry.hash);
  o.estimator = stack::EstimatorKind::kLio;
  const harness::Scenario on_lio = MakeFtcTrial("hover/propeller_loss", "rotorguard", o, 7);
  o.estimator = stack::EstimatorKind::kOdometry;
  const harness::Scenario on_odometry = MakeFtcTrial("hover/propeller_loss", "rotorguard", o, 7);
  EXPECT_EQ(on_lio.stack.estimator.kind, stack::EstimatorKind::kLio);
  EXPECT_TRUE(on_lio.sim.lidar.enabled);
  EXPECT_FALSE(on_lio.world.boxes.empty());
  EXPECT_FALSE(on_odometry.sim.lidar.enabled);
  EXPECT_TRUE(on_odometry.world.boxes.empty());
  ASSERT_EQ(on_lio.faults.size(), 1u);
  EXPECT_EQ(on_lio.faults[0].rotor, on_odometry.faults[0].rotor);
  EXPECT_EQ(on_lio.faults[0].onset.value, on_odometry.faults[0].onset.value);
  // The LIO's mounts are the vehicle's sensors' (the stack fitted to the hardware).
  EXPECT_EQ(on_lio.stack.estimator.lio.lidar_position_m, on_lio.sim.lidar.position_m);
  // The hall holds every phase's flight: the start and the lemniscate's extent stay inside it.
  for (const sim::Box& b : FtcHall().boxes) {
    const Vector3 half = 0.5 * b.size_m;
    for (const Vector3& p : {Vector3(0, 0, 2), Vector3(3, 1.5, 1.5), Vector3(-3, -1.5, 1.5), Vector3(0, 0, 0.1)}) {
      EXPECT_FALSE(((p - b.center_m).cwiseAbs() - half).maxCoeff() < 1.0) << "a box within 1 m of " << p.transpose();
    }
  }
}

TEST_F(BenchCampaigns, BadBenchmarkSpecsNameTheKey) {
  const std::string vehicle = "vehicle: " + kConfigs + "/vehicles/zhou2025_quad.yaml\n";
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("a.yaml", "name: a\nbench: hover\ntrials: 1\n"), CampaignKinds()), io::ConfigError, "bench");
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("b.yaml", "name: b\nbench: ftc\ntrials: 0\n" + vehicle), CampaignKinds()), io::ConfigError,
                       "trials");
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("c.yaml", "name: c\nbench: ftc\ntrials: 1\nmethods: [rotorguard, magic]\n" +
                                                        vehicle), CampaignKinds()),
                       io::ConfigError, "magic");
  // A key of another benchmark is unknown here.
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("d.yaml", "name: d\nbench: ftc\ntrials: 1\nkinds: [room]\n" + vehicle), CampaignKinds()),
                       io::ConfigError, "kinds");
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("e.yaml", "name: e\nbench: ftc\ntrials: 1\n"), CampaignKinds()), io::ConfigError, "vehicle");
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("f.yaml", "name: a b\nbench: ftc\ntrials: 1\n" + vehicle), CampaignKinds()), io::ConfigError,
                       "name");
  // A file that cannot be read is reported at the key that names it.
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("g.yaml", "name: g\nbench: nav\ntrials: 1\nbase: no_such.yaml\n"), CampaignKinds()),
                       io::ConfigError, "base");
  // Table II needs both of its scenes.
  RG_EXPECT_THROW_WITH(campaign::LoadCampaign(Write("h.yaml", "name: h\nbench: mars\ntrials: 1\nspiral: " + kConfigs +
                                                        "/scenarios/mars_spiral_3x2.yaml\nnine_units: " + kConfigs +
                                                        "/assemblies/3x3.yaml\nplan_4x1: " + kConfigs +
                                                        "/scenarios/mars_plan_4x1.yaml\n"), CampaignKinds()),
                       io::ConfigError, "plan_3x2");
  // A spec without a file cannot make a Slurm script.
  campaign::SlurmScriptOptions s;
  s.out_dir = dir_.string();
  s.rotorguard = "/bin/true";
  RG_EXPECT_THROW_WITH(campaign::SlurmArrayScript(FtcCampaign(SmallFtc()), s), std::invalid_argument, "no spec file");
}

}  // namespace
}  // namespace rotorguard::benchmarks
