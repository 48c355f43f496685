// Paper 002's benchmark (Tables I and II, the reallocation's time, the self-reconfiguration) on
// short runs: the cases that can hover are held near the fault-free error, the planner's rows fly
// as the paper's do.

#include <cmath>
#include <cstdint>
#include <string>

#include <gtest/gtest.h>

#include "rotorguard/campaign_kinds/mars_bench.h"
#include "rotorguard/campaign_kinds/reconfiguration.h"
#include "rotorguard/core/types.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/modular/assembly_trajectory.h"
#include "rotorguard/sim/truth.h"
#include "test_util.h"

namespace rotorguard::benchmarks {
namespace {

std::string Config(const std::string& path) { return testing::SourcePath("configs/" + path); }

TEST(MarsBenchmark, FullReallocationHoldsEveryHoverableCaseNearTheFaultFreeError) {
  MarsBenchOptions o;
  o.trials = 1;
  o.jobs = 2;
  o.alloc_samples = 1000;
  o.spiral = harness::LoadScenario(Config("scenarios/mars_spiral_3x2.yaml"), {{"duration_s", "15"}});
  o.nine_units = harness::LoadAssembly(Config("assemblies/3x3.yaml"));
  o.reconfigure = harness::LoadScenario(Config("scenarios/mars_reconfigure_3x1.yaml"));
  o.plan_4x1 = harness::LoadScenario(Config("scenarios/mars_plan_4x1.yaml"));
  o.plan_3x2 = harness::LoadScenario(Config("scenarios/mars_plan_3x2.yaml"));
  o.truth = sim::TruthPreset::kIdeal;  // the figures below are the exact model's
  const nlohmann::json r = RunMarsBenchmark(o);
  // Table II: ours plans every row and flies it, each plan within what the known rotors can give.
  ASSERT_EQ(r["table2"].size(), 5u);
  for (const auto& row : r["table2"]) {
    SCOPED_TRACE(row["shape"].get<std::string>() + " " + row["fault"].get<std::string>());
    ASSERT_TRUE(row["ours_planned"].get<bool>());
    EXPECT_EQ(row["ours_success_rate"].get<double>(), 1.0) << row["ours_first_failure"];
    // Ours asks no more of the assembly than its rotors can give (sampled every millisecond against
    // the allocator's capacity, not the planner's own limits).
    EXPECT_LT(row["ours_max_thrust_accel_m_s2"].get<double>(), row["capacity_thrust_accel_m_s2"].get<double>());
    EXPECT_LT(row["ours_max_yaw_accel_rad_s2"].get<double>(), row["capacity_yaw_accel_rad_s2"].get<double>());
    EXPECT_LT(row["ours_max_roll_accel_rad_s2"].get<double>(), row["capacity_roll_accel_rad_s2"].get<double>());
    EXPECT_LT(row["ours_max_pitch_accel_rad_s2"].get<double>(), row["capacity_pitch_accel_rad_s2"].get<double>());
  }
  // The baseline plans the same trajectory whatever the fault: with the end unit No. 4 dead it asks
  // for more yaw acceleration than the row can give (ours, above, does not). Whether the row then
  // falls is a draw this one flight cannot settle: rounding at the 1e-16 level (most likely where
  // a vector's data starts, which decides how Eigen's reductions peel) moves the baseline's plan for seed 1 between
  // asking 0.88 and 0.71 rad/s² of yaw where 0.42 can be given, and it falls with the first and survives the second; of
  // its planned flights over seeds 1-5, two or three of three fall. The error over a crashed flight's plan window is
  // tested on hand-made records below (MarsTableTwo).
  const nlohmann::json& dead_end = r["table2"][2];
  ASSERT_EQ(dead_end["fault"].get<std::string>(), "No. 4");
  ASSERT_TRUE(dead_end["baseline_planned"].get<bool>());
  EXPECT_GT(dead_end["baseline_max_yaw_accel_rad_s2"].get<double>(),
            1.5 * dead_end["capacity_yaw_accel_rad_s2"].get<double>());
  EXPECT_EQ(dead_end["ours_error_m"].get<double>(), dead_end["ours_error_to_crash_m"].get<double>());
  ASSERT_EQ(r["table1"].size(), 6u);
  for (const auto& row : r["table1"]) {
    SCOPED_TRACE(row["case"].get<std::string>());
    // Units No. 1 and 3 dead leave unit No. 2 alone on its side of the roll axis: it would have to
    // carry half the weight (14.7 N), four rotors of 2.6 N give 10.4 N. Every other case can hover.
    const bool one_row = row["case"].get<std::string>().find("No. 1 and 3") != std::string::npos;
    EXPECT_EQ(row["hover_attainable"].get<bool>(), !one_row);
    if (one_row) continue;
    EXPECT_EQ(row["full_success_rate"].get<double>(), 1.0);
    EXPECT_LE(row["full_over_fault_free"].get<double>(), 1.5);
  }
  // A dead unit: the fault-blind allocation errs far more than the reallocation.
  EXPECT_GT(r["table1"][3]["none_error_m"].get<double>(), 4.0 * r["table1"][3]["full_error_m"].get<double>());
  EXPECT_TRUE(r["table1_full_within_1_5x_fault_free"].get<bool>());
  EXPECT_GT(r["alloc_us_mean"].get<double>(), 0.0);
  EXPECT_EQ(r["alloc_units"].get<int>(), 9);
  EXPECT_LT(r["reconfig_max_attitude_deg"].get<double>(), 1.0);
  EXPECT_EQ(r["reconfig"]["prepared"]["success_rate"].get<double>(), 1.0);
  o.trials = 0;
  RG_EXPECT_THROW_WITH(RunMarsBenchmark(o), std::invalid_argument, "trials = 0");
}

TEST(MarsTableTwo, TheTruthsThrustPerKilogramIsTheFilesOverTheDrawnMass) {
  // Only the mass drawn (up to 7 %): the rotors and the centre of gravity are the file's, so the
  // drawn vehicle's thrust with zero torque is the planner's (CapacityOf on the file), per drawn
  // kilogram; with the end unit dead (6 % above hover on the file) a heavier draw cannot hover: 0.
  harness::Scenario scene = harness::LoadScenario(Config("scenarios/mars_plan_4x1.yaml"));
  scene.truth = sim::TruthOptions{};
  scene.truth.preset = sim::TruthPreset::kIdeal;
  scene.truth.mass_fraction = 0.07;
  const double mass = scene.vehicle.mass_kg;
  const int rotors = scene.vehicle.num_rotors();
  const double healthy = modular::CapacityOf(*scene.assembly, RotorVector::Ones(rotors)).max_thrust_n;
  RotorVector eta = RotorVector::Ones(rotors);
  eta.tail(4).setZero();
  const double dead_end = modular::CapacityOf(*scene.assembly, eta).max_thrust_n;
  // CapacityOf bisects the thrust to 1e-4 of the rotors' total; per kilogram of the lightest draw.
  const double bisection_n = 1e-4 * scene.vehicle.total_max_thrust_n();
  const double tolerance = bisection_n / ((1.0 - *scene.truth.mass_fraction) * mass);
  int cannot_hover = 0;
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    scene.seed = seed;
    scene.faults.clear();
    const double ratio = sim::DrawTruth(scene.truth, scene.vehicle, seed).mass_ratio;
    EXPECT_NEAR(TruthThrustAcceleration(scene), healthy / (mass * ratio), tolerance) << "seed " << seed;
    for (int r = rotors - 4; r < rotors; ++r) {
      sim::FaultSpec f;
      f.rotor = r;
      scene.faults.push_back(f);  // a motor stop
    }
    const double weight = kGravity * mass * ratio;
    if (std::abs(dead_end - weight) < bisection_n) continue;  // hover or not is within the bisection
    if (dead_end < weight) {
      ++cannot_hover;
      EXPECT_EQ(TruthThrustAcceleration(scene), 0.0) << "seed " << seed;
    } else {
      EXPECT_NEAR(TruthThrustAcceleration(scene), dead_end / (mass * ratio), tolerance) << "seed " << seed;
    }
  }
  EXPECT_GT(cannot_hover, 0);
  EXPECT_LT(cannot_hover, 60);
}

// Table II on hand-made records: 5 rows x 2 planners (baseline, ours) x 3 trials. In row 0 the
// baseline plans trials 0 and 1 (errors 0.2, 0.4 m; trial 1 crashed) and not trial 2, ours all three
// (0.1, 0.1, 0.7 m): the cells are over each method's own plans, the comparison over trials 0 and 1.
// Trial 2's drawn assembly cannot hover (its thrust per kilogram below g; ours crashes there).
TEST(MarsTableTwo, CellsAreOverEachMethodsPlansAndTheComparisonOverTheTrialsBothPlanned) {
  const auto flight = [](double rmse, bool success, double truth_capacity = 11.0) {
    return nlohmann::json{{"status", "ok"},
                          {"message", success ? "" : "crash: collision with box 0"},
                          {"params", {{"shape", "mars_4x1"}, {"fault", "normal"}}},
                          {"metrics",
                           {{"planned", true},
                            {"success", success},
                            {"rmse_m", rmse},
                            {"rmse_flown_m", rmse / 2},
                            {"max_error_m", 2 * rmse},
                            {"duration_s", 6.0},
                            {"attitude_deviation_deg", 1.0},
                            {"plan_ms", 10.0},
                            {"max_accel_m_s2", 1.0},
                            {"max_thrust_accel_m_s2", 11.0},
                            {"max_yaw_accel_rad_s2", 2.0},
                            {"max_roll_accel_rad_s2", 3.0},
                            {"max_pitch_accel_rad_s2", 1.0},
                            {"capacity_accel_m_s2", 5.0},
                            {"capacity_thrust_accel_m_s2", 20.0},
                            {"capacity_yaw_accel_rad_s2", 4.0},
                            {"capacity_roll_accel_rad_s2", 30.0},
                            {"capacity_pitch_accel_rad_s2", 10.0},
                            {"truth_capacity_thrust_accel_m_s2", truth_capacity}}}};
  };
  const nlohmann::json no_plan = {{"status", "ok"},
                                  {"message", "A*: no_path"},
                                  {"params", {{"shape", "mars_4x1"}, {"fault", "normal"}}},
                                  {"metrics", {{"planned", false}, {"truth_capacity_thrust_accel_m_s2", 9.0}}}};
  std::vector<nlohmann::json> records;
  for (int row = 0; row < 5; ++row) {
    for (const nlohmann::json& r : {flight(0.2, true), flight(0.4, false), no_plan}) records.push_back(r);  // baseline
    for (const nlohmann::json& r : {flight(0.1, true), flight(0.1, true), flight(0.7, false, 9.0)}) records.push_back(r);
  }
  std::vector<const nlohmann::json*> pointers;
  for (const nlohmann::json& r : records) pointers.push_back(&r);
  const nlohmann::json t = MarsTableTwo(pointers, 3);
  const nlohmann::json& row = t["table2"][0];
  EXPECT_NEAR(row["baseline_error_m"].get<double>(), 0.3, 1e-12);             // its two plans
  EXPECT_NEAR(row["baseline_success_rate"].get<double>(), 1.0 / 3.0, 1e-12);  // of three trials
  EXPECT_NEAR(row["baseline_plan_rate"].get<double>(), 2.0 / 3.0, 1e-12);
  EXPECT_EQ(row["baseline_plan_failure"], "A*: no_path");
  EXPECT_NEAR(row["ours_error_m"].get<double>(), 0.3, 1e-12);  // (0.1 + 0.1 + 0.7) / 3
  EXPECT_EQ(row["paired_trials"], 2);
  EXPECT_EQ(row["hover_capable_trials"], 2);  // trials 0 and 1
  EXPECT_NEAR(row["baseline_success_rate_hover_capable"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(row["ours_success_rate_hover_capable"].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(row["ours_success_rate"].get<double>(), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(row["improvement"].get<double>(), 1.0 - 0.1 / 0.3, 1e-12);  // trials 0 and 1 only
  EXPECT_NEAR(t["table2_improvement_average"].get<double>(), 1.0 - 0.1 / 0.3, 1e-12);
  EXPECT_TRUE(t["table2_ours_better_in_every_row"].get<bool>());
  records.pop_back();
  pointers.pop_back();
  EXPECT_THROW(MarsTableTwo(pointers, 3), std::invalid_argument);
}

TEST(Reconfiguration, AUnitSeparatesFliesOverAndDocksWhileTheAssemblyStaysLevel) {
  ReconfigurationOptions o;
  o.base = harness::LoadScenario(Config("scenarios/mars_reconfigure_3x1.yaml"));
  o.base.truth.preset = sim::TruthPreset::kIdeal;  // the paper's floor: the vehicles as their files
  const ReconfigurationResult prepared = RunReconfiguration(o);
  ASSERT_TRUE(prepared.success) << prepared.failure;
  EXPECT_GT(prepared.docking_s, prepared.separation_s + 3.0);  // up, across and down at 0.3 m/s
  EXPECT_LT(prepared.separation_max_attitude_deg, 1.0);        // paper: at most about 1 degree
  EXPECT_LT(prepared.docking_max_attitude_deg, 1.0);
  o.naive = true;
  const ReconfigurationResult naive = RunReconfiguration(o);
  ASSERT_TRUE(naive.success) << naive.failure;
  // Prepared, nothing acts through the latch when it opens: the assembly's acceleration does not
  // jump as it does when the unit is let go carrying its share of the fault's compensation.
  EXPECT_LT(prepared.separation_max_accel_m_s2, naive.separation_max_accel_m_s2);
  o.target_slot = Eigen::Vector2i(1, 0);  // occupied
  RG_EXPECT_THROW_WITH(RunReconfiguration(o), std::invalid_argument, "target_slot");
}

TEST(Reconfiguration, InTheDrawnWorldTheUnitDocksByItsCameraNotByItsOdometry) {
  // Each unit drawn about its file, each body's odometry drifting on its own: the two bodies'
  // estimates part by centimetres over the transfer, more than the latch's 3 cm.
  ReconfigurationOptions o;
  o.base = harness::LoadScenario(Config("scenarios/mars_reconfigure_3x1.yaml"));
  ASSERT_EQ(o.base.truth.preset, sim::TruthPreset::kRealistic);
  const ReconfigurationResult guided = RunReconfiguration(o);
  // Docked (the docked assembly's hold is judged after, on its own drifting odometry).
  EXPECT_GT(guided.docking_s, guided.separation_s + 3.0) << guided.failure;
  o.dock_camera_range_m = 1.01 * o.dock_tolerance_m;  // sees the slot only once docked: blind
  const ReconfigurationResult blind = RunReconfiguration(o);
  EXPECT_FALSE(blind.success);
  EXPECT_NE(blind.failure.find("did not reach its slot"), std::string::npos) << blind.failure;
  o.dock_camera_noise_m = o.dock_tolerance_m;
  RG_EXPECT_THROW_WITH(RunReconfiguration(o), std::invalid_argument, "dock_camera_noise_m");
}

}  // namespace
}  // namespace rotorguard::benchmarks
