// The FTC benchmark's cell metrics (docs/metrics.md) on hand-made trials.
#include "rotorguard/campaign_kinds/ftc_bench.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "rotorguard/harness/scenario.h"
#include "test_util.h"
#include "vehicle_fixture.h"

namespace rotorguard::benchmarks {
namespace {

TEST(FtcCell, MetricArithmeticOnHandMadeTrials) {
  // Four faulty trials: two correct isolations (0.02 s, 0.04 s), one detected 1.5 s late (counts as
  // missed), one false alarm before the onset; three successes; altitude changes 1.9, 1.8, 1.5 and
  // -0.2 m, whose least is MiniA.
  std::vector<FtcTrial> t(4);
  for (auto& x : t) x.has_fdd = true;
  t[0] = {true, true, true, false, 0.02, 1.9, "", 11};
  t[1] = {true, true, true, false, 0.04, 1.8, "", 12};
  t[2] = {true, true, true, false, 1.5, 1.5, "", 13};
  t[3] = {false, true, false, true, -1.0, -0.2, "crash: ground impact at 3.00 m/s", 14};
  const nlohmann::json c = AggregateFtcCell(t, /*faulty=*/true);
  EXPECT_EQ(c["trials"], 4);
  EXPECT_NEAR(c["fdd_latency_s_mean"].get<double>(), (0.02 + 0.04 + 1.5) / 3.0, 1e-12);
  EXPECT_NEAR(c["fdd_latency_s_max"].get<double>(), 1.5, 1e-12);
  EXPECT_NEAR(c["sucr"].get<double>(), 0.75, 1e-12);
  EXPECT_NEAR(c["mdr"].get<double>(), 0.5, 1e-12);  // the late one and the false alarm
  EXPECT_NEAR(c["far"].get<double>(), 0.25, 1e-12);
  EXPECT_NEAR(c["mini_alt_m"].get<double>(), -0.2, 1e-12);
  ASSERT_EQ(c["failures"].size(), 1u);
  EXPECT_EQ(c["failures"][0]["seed"], 14);
}

TEST(FtcCell, SettledErrorIsTheMedianAndEtaErrorsCountOnlyWhereThereAreAny) {
  // Three trials settled at 0.1, 0.3 and 0.2 m; two partial losses estimated 0.02 and 0.06 off.
  std::vector<FtcTrial> t(3);
  t[0].final_rmse_m = 0.1;
  t[1].final_rmse_m = 0.3;
  t[2].final_rmse_m = 0.2;
  t[0].eta_error = 0.02;
  t[2].eta_error = 0.06;
  const nlohmann::json c = AggregateFtcCell(t, /*faulty=*/true);
  EXPECT_NEAR(c["final_rmse_m_median"].get<double>(), 0.2, 1e-12);
  EXPECT_NEAR(c["eta_error_mean"].get<double>(), 0.04, 1e-12);
  EXPECT_NEAR(c["eta_error_max"].get<double>(), 0.06, 1e-12);
  EXPECT_TRUE(AggregateFtcCell({FtcTrial{}}, true)["eta_error_mean"].is_null());
}

TEST(FtcCell, AnErroredTrialIsAFailureAndAMissedDetection) {
  // Two faulty trials of a method with FDD: one correct isolation, one that errored (it reported no
  // metrics). MDR counts the errored one; MiniA comes from the finished one alone.
  std::vector<FtcTrial> t(2);
  t[0] = {true, true, true, false, 0.02, 1.9, "", 11};
  t[1].has_fdd = true;
  t[1].errored = true;
  t[1].failure = "error: diverged";
  const nlohmann::json c = AggregateFtcCell(t, /*faulty=*/true);
  EXPECT_NEAR(c["mdr"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(c["sucr"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(c["mini_alt_m"].get<double>(), 1.9, 1e-12);
  EXPECT_NEAR(c["far"].get<double>(), 0.0, 1e-12);
}

TEST(FtcResult, TrialsThatErroredAreMissedDetectionsOfAMethodWithFdd) {
  // Every trial of rotorguard (composite FDD) errored: every faulty cell misses all its faults,
  // and the fault-free cell has no MDR to report. Without FDD (none) MDR stays null.
  for (const char* method : {"rotorguard", "none"}) {
    const nlohmann::json options = {{"trials", 1}, {"seed", 1}, {"methods", {method}}, {"vehicle", "v"}};
    std::vector<nlohmann::json> records;
    const int cells = static_cast<int>(FtcCampaign([&] {
                                         FtcBenchOptions o;
                                         o.trials = 1;
                                         o.methods = {method};
                                         o.vehicle = testing::ReferenceQuad();
                                         return o;
                                       }())
                                           .trials);
    for (int i = 0; i < cells; ++i) {
      records.push_back({{"status", "error"}, {"message", "diverged"}, {"params", {{"seed", "7"}}}});
    }
    const nlohmann::json r = FtcResult(options, records);
    EXPECT_EQ(r["errors"], cells);
    for (const nlohmann::json& c : r["cells"]) {
      EXPECT_EQ(c["sucr"], 0.0);
      const bool faulty = c["fault"] != "none";
      if (faulty && std::string(method) == "rotorguard") {
        EXPECT_EQ(c["mdr"], 1.0) << c["phase"] << " " << c["fault"];
      } else {
        EXPECT_TRUE(c["mdr"].is_null()) << method << " " << c["phase"] << " " << c["fault"];
      }
    }
  }
}

TEST(FtcCell, MetricsWithoutFaultDetectionAreNull) {
  std::vector<FtcTrial> t(2);
  t[0].success = true;
  const nlohmann::json c = AggregateFtcCell(t, /*faulty=*/true);
  EXPECT_TRUE(c["mdr"].is_null());
  EXPECT_TRUE(c["far"].is_null());
  EXPECT_TRUE(c["fdd_latency_s_mean"].is_null());
  EXPECT_NEAR(c["sucr"].get<double>(), 0.5, 1e-12);
  EXPECT_TRUE(AggregateFtcCell({FtcTrial{true, true, false, false, -1.0, 1.0, "", 1}}, false)["mdr"].is_null());
}

TEST(FtcCell, FaultFreeTrialsHaveNoAltitudeChange) {
  const double none = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(AggregateFtcCell({FtcTrial{true, true, false, false, -1.0, none, "", 1}}, false)["mini_alt_m"].is_null());
}

TEST(FtcBenchmark, TheRealisticWorldFliesOtherVehiclesUnderItsOwnHash) {
  // One trial of one method in each world: the same index, the same seed and fault, another
  // vehicle. A campaign of one world cannot resume or merge into the other's (hash).
  FtcBenchOptions o;
  o.trials = 1;
  o.methods = {"rotorguard"};
  o.vehicle = harness::LoadVehicle(testing::SourcePath("configs/vehicles/zhou2025_quad.yaml"));
  o.truth = sim::TruthPreset::kIdeal;
  const campaign::Campaign ideal = FtcCampaign(o);
  o.truth = sim::TruthPreset::kRealistic;
  const campaign::Campaign realistic = FtcCampaign(o);
  EXPECT_EQ(ideal.bench["options"]["truth"], "ideal");
  EXPECT_EQ(realistic.bench["options"]["truth"], "realistic");
  EXPECT_NE(ideal.hash, realistic.hash);
  EXPECT_EQ(ideal.parameters(0), realistic.parameters(0));
  const campaign::TrialOutcome a = ideal.run(0, ideal.parameters(0));
  const campaign::TrialOutcome b = realistic.run(0, realistic.parameters(0));
  EXPECT_NE(a.metrics["altitude_change_m"], b.metrics["altitude_change_m"]);
}

TEST(FtcBenchmark, ACellFlownAloneFliesTheTrialsItFliesAmongTheOthers) {
  // The same (cell, trial) has the same parameters, seed included, whichever cells are flown; the
  // result aggregates exactly the cells flown, in the tables' order.
  FtcBenchOptions o;
  o.trials = 3;
  o.methods = {"rotorguard", "none"};
  o.vehicle = testing::ReferenceQuad();
  const campaign::Campaign all = FtcCampaign(o);
  o.cells = {"takeoff/propeller_loss", "hover/motor_stop"};
  const campaign::Campaign two = FtcCampaign(o);
  EXPECT_EQ(two.trials, 2 * 2 * 3);
  EXPECT_NE(all.hash, two.hash);
  const std::vector<std::string> names = FtcCells();
  const auto index_of = [&](const std::string& cell) {
    return static_cast<int>(std::find(names.begin(), names.end(), cell) - names.begin());
  };
  // Trial index = (cell, method, trial), the trial fastest; hover/motor_stop comes first.
  for (int m = 0; m < 2; ++m) {
    for (int t = 0; t < 3; ++t) {
      EXPECT_EQ(two.parameters(m * 3 + t), all.parameters((index_of("hover/motor_stop") * 2 + m) * 3 + t));
      EXPECT_EQ(two.parameters(6 + m * 3 + t), all.parameters((index_of("takeoff/propeller_loss") * 2 + m) * 3 + t));
    }
  }
  std::vector<nlohmann::json> records(static_cast<std::size_t>(two.trials),
                                      {{"status", "error"}, {"message", "diverged"}, {"params", {{"seed", "7"}}}});
  const nlohmann::json r = FtcResult(two.bench["options"], records);
  ASSERT_EQ(r["cells"].size(), 4u);
  EXPECT_EQ(r["cells"][0]["phase"], "hover");
  EXPECT_EQ(r["cells"][0]["fault"], "motor_stop");
  EXPECT_EQ(r["cells"][3]["phase"], "takeoff");
  EXPECT_EQ(r["cells"][3]["method"], "none");
  o.cells = {"hover/nothing"};
  RG_EXPECT_THROW_WITH(FtcCampaign(o), std::invalid_argument, "cells = hover/nothing");
}

}  // namespace
}  // namespace rotorguard::benchmarks
