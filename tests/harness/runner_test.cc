// Closed-loop flights of the shipped scenarios: the nominal stack through sensors only. Behaviour
// (a take-off settles, a fault is isolated and survived, no false alarm, a crash without FTC) is
// held in the realistic world, the scenarios' default; tests that hold the stack to a figure of
// the model itself (a tracking error of centimetres, an exact latency) pin `truth: ideal` and say
// so. shipped_scenarios_test.cc flies every shipped scenario in both worlds at three seeds.

#include "rotorguard/harness/runner.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "rotorguard/harness/scenario.h"
#include "rotorguard/harness/world_raster.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/csv.h"
#include "rotorguard/sim/truth.h"
#include "test_util.h"

namespace rotorguard::harness {
namespace {

std::string Config(const std::string& name) {
  return testing::SourcePath("configs/scenarios/" + name);
}

TEST(Runner, NominalControllerTracksThe2msLemniscateWithinTenCentimetres) {
  const Scenario s = LoadScenario(Config("lemniscate_2ms.yaml"), {{"truth", "ideal"}});
  const RunSummary r = RunScenario(s);
  EXPECT_TRUE(r.success) << r.crash_reason.value_or("");
  EXPECT_LT(r.tracking_rmse_m, 0.10);
  EXPECT_NEAR(r.sim_time_s, s.duration_s, 1e-6);
}

TEST(Runner, NominalControllerTracksTheLemniscateOverManySeeds) {
  // Sensor noise and gusts differ per seed; the bound must hold for each, not on average.
  for (std::uint64_t seed = 10; seed < 16; ++seed) {
    Scenario s = LoadScenario(Config("lemniscate_2ms.yaml"), {{"truth", "ideal"}, {"duration_s", "20"}});
    s.seed = seed;
    const RunSummary r = RunScenario(s);
    EXPECT_TRUE(r.success) << "seed " << seed;
    EXPECT_LT(r.tracking_rmse_m, 0.10) << "seed " << seed;
  }
}

TEST(Runner, HoverHoldsPosition) {
  const RunSummary r = RunScenario(LoadScenario(Config("hover.yaml"), {{"truth", "ideal"}}));
  EXPECT_TRUE(r.success);
  EXPECT_LT(r.max_position_error_m, 0.05);
  EXPECT_GT(r.min_altitude_m, 0.95);
}

/// Runs that write their files into a fresh folder.
class RunnerFiles : public testing::TempFolderTest {};

TEST_F(RunnerFiles, TheStackFliesTheVehicleFileWhileTheSimulatorFliesTheDraw) {
  Scenario s = LoadScenario(Config("hover.yaml"), {{"truth", "ideal"}, {"duration_s", "3"}});
  s.truth.preset = sim::TruthPreset::kRealistic;
  RunOptions o;
  o.out_dir = dir_.string();
  const RunSummary r = RunScenario(s, o);
  const auto read = [&](const char* name) { return io::ReadInputFile((dir_ / name).string()); };
  // What the stack was told: the file's vehicle and the file's IMU mounting point ...
  EXPECT_EQ(read("vehicle.yaml"), VehicleToYaml(s.vehicle));
  EXPECT_EQ(r.sensors.imu_position_m, s.sim.imu.position_m);
  // ... what the simulator flew: the draw the summary records, which differs from the file.
  EXPECT_EQ(r.truth.preset, sim::TruthPreset::kRealistic);
  EXPECT_EQ(read("truth_vehicle.yaml"), VehicleToYaml(sim::TruthVehicle(s.vehicle, r.truth)));
  EXPECT_NE(read("truth_vehicle.yaml"), read("vehicle.yaml"));
  const nlohmann::json summary = nlohmann::json::parse(read("summary.json"));
  EXPECT_EQ(summary["truth"]["preset"], "realistic");
  EXPECT_EQ(summary["truth"]["mass_ratio"].get<double>(), r.truth.mass_ratio);
}

TEST_F(RunnerFiles, TheSameSeedFliesTheSameDrawAndAnotherSeedAnother) {
  Scenario s = LoadScenario(Config("hover.yaml"), {{"truth", "ideal"}, {"duration_s", "2"}});
  s.truth.preset = sim::TruthPreset::kRealistic;
  const auto fly = [&](std::uint64_t seed) {
    Scenario t = s;
    t.seed = seed;
    RunOptions o;
    o.out_dir = (dir_ / std::to_string(seed)).string();
    const RunSummary r = RunScenario(t, o);
    return std::make_pair(r.truth.mass_ratio, io::ReadInputFile((dir_ / std::to_string(seed) / "log.csv").string()));
  };
  const auto a = fly(3), b = fly(3), c = fly(4);
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.second, b.second) << "two runs of one seed must log the same bytes";
  EXPECT_NE(a.first, c.first);
}

TEST(Runner, TakesOffFromTheGroundAndSettlesAtAltitude) {
  const Scenario s = LoadScenario(Config("takeoff.yaml"));
  ASSERT_EQ(s.truth.preset, sim::TruthPreset::kRealistic);
  ASSERT_EQ(s.initial_position_m.z(), 0.0);
  const RunSummary r = RunScenario(s);
  EXPECT_TRUE(r.success) << r.crash_reason.value_or("");
  EXPECT_FALSE(r.altitude_change_m.has_value()) << "no fault";
  EXPECT_LT(r.tracking_rmse_m, 0.10);
}

TEST(Runner, NominalControllerCrashesAfterAMotorStop) {
  const RunSummary r = RunScenario(LoadScenario(Config("hover_motor_stop_nominal.yaml")));
  EXPECT_EQ(r.truth.preset, sim::TruthPreset::kRealistic);
  EXPECT_TRUE(r.crashed);
  EXPECT_FALSE(r.success);
  ASSERT_EQ(r.faults.size(), 1u);
  EXPECT_EQ(r.faults[0].kind, "motor_stop");
  EXPECT_GT(r.sim_time_s, 2.0);  // it was flying until the failure
}

class RunnerWindowTest : public rotorguard::testing::TempFolderTest {
 protected:
  /// hover_motor_stop_nominal.yaml with a metrics block, its vehicle named by an absolute path.
  std::string WithMetrics(const std::string& metrics) {
    std::string text = io::ReadInputFile(Config("hover_motor_stop_nominal.yaml"));
    text.replace(text.find("../vehicles/"), 12, testing::SourcePath("configs/vehicles/"));
    text.replace(text.find("truth: realistic"), 16, "truth: ideal");  // the figures of the exact model
    return Write("s.yaml", text + "metrics: " + metrics + "\n");
  }
};

TEST_F(RunnerWindowTest, ACrashedVehicleIsHeldAtItsCrashSiteForTheRestOfTheWindow) {
  // The hover reference stays at the start, [0, 0, 2]; the wreck lies where log.csv's last row
  // (the final state) puts it. Over [0, T] the window's mean square error is the flown part's
  // plus the wreck's constant distance over (t_crash, T]:
  //   rmse_window^2 T = rmse_flown^2 t_crash + |wreck - p_ref|^2 (T - t_crash).
  const Scenario s = LoadScenario(Config("hover_motor_stop_nominal.yaml"), {{"truth", "ideal"}});
  RunOptions o;
  o.out_dir = dir_.string();
  const RunSummary r = RunScenario(s, o);
  ASSERT_TRUE(r.crashed);
  const io::NumericTable log = io::ReadNumericCsv((dir_ / "log.csv").string());
  const std::size_t last = log.rows() - 1;
  const Vector3 wreck(log.Column("p_x")[last], log.Column("p_y")[last], log.Column("p_z")[last]);
  const double d2 = (wreck - s.initial_position_m).squaredNorm();
  const double T = s.duration_s, t_crash = r.sim_time_s;
  const double expected = std::sqrt((r.tracking_rmse_m * r.tracking_rmse_m * t_crash + d2 * (T - t_crash)) / T);
  EXPECT_NEAR(r.tracking_rmse_window_m, expected, 1e-6);  // the log's 9 significant digits
  EXPECT_GT(r.tracking_rmse_window_m, 2.0 * r.tracking_rmse_m);
  // A window that opens after the crash holds the wreck only: its error is the constant distance.
  const RunSummary late = RunScenario(LoadScenario(WithMetrics("{tracking_start_s: 4.0005}")));
  ASSERT_TRUE(late.crashed);
  EXPECT_EQ(late.tracking_rmse_m, 0.0);  // nothing flown inside the window
  EXPECT_NEAR(late.tracking_rmse_window_m, std::sqrt(d2), 1e-6);
}

TEST(RunnerWindow, AFlightThatDoesNotCrashHasOneError) {
  const RunSummary r = RunScenario(LoadScenario(Config("hover.yaml"), {{"truth", "ideal"}}));
  ASSERT_FALSE(r.crashed);
  EXPECT_EQ(r.tracking_rmse_window_m, r.tracking_rmse_m);
}

TEST_F(RunnerWindowTest, TheWindowsEndLeavesOutWhatComesAfterIt) {
  // The motor stops at 2 s: a window that ends at 1.5 s holds only the steady hover, and the
  // crash after it adds nothing to the window.
  const Scenario whole = LoadScenario(Config("hover_motor_stop_nominal.yaml"), {{"truth", "ideal"}});
  const Scenario early = LoadScenario(WithMetrics("{tracking_end_s: 1.5}"));
  ASSERT_TRUE(early.tracking_end_s.has_value());
  const RunSummary a = RunScenario(whole), b = RunScenario(early);
  ASSERT_TRUE(b.crashed);
  EXPECT_EQ(a.sim_time_s, b.sim_time_s);  // the same flight
  EXPECT_LT(b.tracking_rmse_m, 0.02);
  EXPECT_GT(a.tracking_rmse_m, 10.0 * b.tracking_rmse_m);
  EXPECT_EQ(b.tracking_rmse_window_m, b.tracking_rmse_m);
  EXPECT_LT(b.max_position_error_m, 0.05);
  // A window that holds no physics step's sample (the physics runs at 1 kHz), or ends after the
  // flight, names the file and the key that closes it.
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"{tracking_start_s: 2, tracking_end_s: 2}", "metrics.tracking_end_s"},
      {"{tracking_start_s: 1.0001, tracking_end_s: 1.0002}", "metrics.tracking_end_s"},
      {"{tracking_end_s: 9}", "metrics.tracking_end_s"},
      {"{tracking_start_s: 7.9999}", "metrics.tracking_start_s"}};
  for (const auto& [metrics, key] : bad) {
    SCOPED_TRACE(metrics);
    const std::string path = WithMetrics(metrics);
    RG_EXPECT_THROW_WITH(LoadScenario(path, {{"truth", "ideal"}}), io::ConfigError, "s.yaml");
    RG_EXPECT_THROW_WITH(LoadScenario(path, {{"truth", "ideal"}}), io::ConfigError, key);
  }
  // One step's window is enough.
  EXPECT_NO_THROW(LoadScenario(WithMetrics("{tracking_start_s: 1, tracking_end_s: 1.001}")));
}

// Closed-loop NMPC flights (paper 000, Sec. VI-A/B), the failure handed to the controller.

TEST(NmpcClosedLoop, HoversAndTracksTheNominal2msLemniscate) {
  const RunSummary hover =
      RunScenario(LoadScenario(Config("hover.yaml"), {{"truth", "ideal"}, {"stack.controller", "nmpc"}}));
  EXPECT_TRUE(hover.success) << hover.failure_reason.value_or("");
  EXPECT_LT(hover.max_position_error_m, 0.05);
  const RunSummary lem = RunScenario(LoadScenario(
      Config("lemniscate_2ms.yaml"), {{"truth", "ideal"}, {"stack.controller", "nmpc"}, {"duration_s", "20"}}));
  EXPECT_TRUE(lem.success) << lem.failure_reason.value_or("");
  EXPECT_LT(lem.tracking_rmse_m, 0.10);
}

TEST(NmpcClosedLoop, SurvivesAKnownMotorFailureInHoverAndRecoversRollAndPitch) {
  const Scenario s = LoadScenario(Config("nmpc_hover_motor_stop_known.yaml"), {{"truth", "ideal"}});
  const RunSummary r = RunScenario(s);
  EXPECT_TRUE(r.success) << r.failure_reason.value_or("");
  EXPECT_GT(r.min_altitude_m, 2.0 - 0.2);  // altitude within 0.2 m of the hover height
  EXPECT_GE(r.tilt_recovery_s.value_or(-1.0), 0.0);
  EXPECT_LE(r.tilt_recovery_s.value_or(-1.0), 3.0);  // roll and pitch recovered within 3 s (paper: about 3 s)
}

TEST(FddClosedLoop, TheControllerIsReconfiguredAtTheFirstControlCycleAfterTheIsolation) {
  // The isolation is taken by the next control cycle: the reconfiguration follows the detection by
  // at most one control period (both include the ESC telemetry's delay).
  const Scenario s = LoadScenario(Config("fdd_hover_motor_stop.yaml"), {{"truth", "ideal"}});
  const RunSummary r = RunScenario(s);
  ASSERT_TRUE(r.fdd.has_value());
  ASSERT_TRUE(r.fdd->correct);
  ASSERT_TRUE(r.fdd->reconfiguration_latency_s.has_value());
  EXPECT_GE(*r.fdd->reconfiguration_latency_s, *r.fdd->latency_s);
  EXPECT_LE(*r.fdd->reconfiguration_latency_s, *r.fdd->latency_s + 1.0 / s.stack.control_rate_hz + 1e-9);
}

TEST(NmpcClosedLoop, TheSpinAfterAMotorStopIsWhereYawDampingBalancesTheReactionTorque) {
  // With a motor stopped and its twin idle, the two rotors left carry the weight and both push the
  // body the same way about z: in steady spin κ_t m g = k_dψ r (paper 000, eq. 3), so r = κ_t m g /
  // k_dψ. The vehicle file's k_dψ was chosen to give the paper's 11 rad/s; the law must hold for
  // others too, each predicted from the vehicle's κ_t, m and g alone.
  for (const double k_d : {0.0088, 0.011, 0.022}) {
    const Scenario s = LoadScenario(Config("nmpc_hover_motor_stop_known.yaml"),
                                    {{"truth", "ideal"}, {"vehicle.yaw_damping_n_m_s", std::to_string(k_d)}});
    const RunSummary r = RunScenario(s);
    const double predicted = s.vehicle.rotors[0].yaw_coefficient_m * s.vehicle.weight_n() / k_d;
    EXPECT_TRUE(r.success) << "k_d " << k_d << ": " << r.failure_reason.value_or("");
    EXPECT_NEAR(r.max_spin_rad_s, predicted, 0.03 * predicted) << "k_d " << k_d;
  }
}

// The mixed-level iteration (NmpcOptions::relinearise_every = 3, as the navigation scenarios fly)
// against the paper's every-call linearisation, through a motor stop and its spin-up to 11 rad/s:
// the same recovery, to within a few percent of the error.
TEST(NmpcClosedLoop, ReusingTheLinearisationBetweenEveryThirdPreparationFliesTheSameFailure) {
  EXPECT_EQ(LoadScenario(Config("forest.yaml"), {{"truth", "ideal"}}).stack.nmpc.relinearise_every, 3)
      << "the key is read";
  EXPECT_EQ(LoadScenario(Config("forest.yaml"), {{"truth", "ideal"}}).stack.lidar.map.clearing_stride, 2)
      << "and the map's";
  Scenario s = LoadScenario(Config("nmpc_hover_motor_stop_known.yaml"), {{"truth", "ideal"}});
  EXPECT_EQ(s.stack.nmpc.relinearise_every, 1) << "the default";
  const RunSummary every = RunScenario(s);
  s.stack.nmpc.relinearise_every = 3;
  const RunSummary third = RunScenario(s);
  ASSERT_TRUE(every.success) << every.failure_reason.value_or("");
  EXPECT_TRUE(third.success) << third.failure_reason.value_or("");
  EXPECT_NE(third.tracking_rmse_m, every.tracking_rmse_m) << "the option reached the controller";
  EXPECT_NEAR(third.tracking_rmse_m, every.tracking_rmse_m, 0.05 * every.tracking_rmse_m);
  EXPECT_NEAR(third.max_position_error_m, every.max_position_error_m, 0.05 * every.max_position_error_m);
  EXPECT_NEAR(third.max_spin_rad_s, every.max_spin_rad_s, 0.1);
  EXPECT_NEAR(third.tilt_recovery_s.value_or(-1.0), every.tilt_recovery_s.value_or(-1.0), 0.05);
  EXPECT_GT(third.min_altitude_m, 2.0 - 0.2);
}

TEST(NmpcClosedLoop, Tracks1msLemniscateWithAFailedRotorWithin15Centimetres) {
  const RunSummary r =
      RunScenario(LoadScenario(Config("nmpc_lemniscate_1ms_rotor0_failed.yaml"), {{"truth", "ideal"}}));
  EXPECT_TRUE(r.success) << r.failure_reason.value_or("");
  EXPECT_LE(r.tracking_rmse_m, 0.15);  // paper 000's hardware: 0.14-0.15 m
  EXPECT_GT(r.max_spin_rad_s, 9.0);
}

// Composite FDD + NMPC in closed loop: the stack discovers the failure from its sensors.

TEST(FddClosedLoop, IsolatesAndSurvivesEachFaultKindInHover) {
  for (const char* kind : {"propeller_loss", "motor_stop"}) {
    const RunSummary r =
        RunScenario(LoadScenario(Config(std::string("fdd_hover_") + kind + ".yaml")));  // realistic
    EXPECT_EQ(r.truth.preset, sim::TruthPreset::kRealistic);
    EXPECT_TRUE(r.success) << kind << ": " << r.failure_reason.value_or("");
    ASSERT_TRUE(r.fdd.has_value());
    ASSERT_TRUE(r.fdd->detected()) << kind;
    EXPECT_TRUE(r.fdd->correct) << kind << ": " << r.fdd->diagnosis->kind << " on rotor " << r.fdd->diagnosis->rotor;
    EXPECT_FALSE(r.fdd->false_alarm);
    // The realistic world's motor coasts down with a drawn stop time constant, and every command
    // acts after the drawn delay (bench ftc's latencies: docs/results.md).
    EXPECT_LT(r.fdd->latency_s.value_or(1e9), std::string(kind) == "motor_stop" ? 0.08 : 0.15) << kind;
    EXPECT_GT(r.min_altitude_m, 1.5) << kind;  // from 2 m
    // The indices' healthy extremes are those before the onset: the stopped motor's M_i near 0
    // and the lost propeller's P_i near 1 are not among them (the raw P_i moves with the drawn
    // vehicle's vibration; the rule's statistic, held for its persistence, stays well below 0.8).
    ASSERT_TRUE(r.fdd->healthy_extremes) << kind;
    EXPECT_GT(r.fdd->healthy_extremes->min_motor_index, 0.8) << kind;
    EXPECT_LT(r.fdd->healthy_extremes->max_propeller_index, 0.6) << kind;
    EXPECT_LT(r.fdd->healthy_extremes->persistent_propeller_index, 0.4) << kind;
  }
}

TEST(FddClosedLoop, ASecondFailureFliesOnOnTheTwinAndStopsTheMotorsBesideIt) {
  // Rotor 0's motor stops at 2 s in hover, in the realistic world; at 5 s a propeller is lost on
  // its idle diagonal twin (1) or on a rotor beside it (2). (Seeds whose drawn vehicle recovers
  // from the first failure; seed 2 draws one whose spin diverges, CHANGELOG.md,
  // "Measurements of earlier releases".)
  for (std::uint64_t seed : {1u, 3u, 4u}) {
    for (int second : {1, 2}) {
      Scenario s = LoadScenario(Config("fdd_hover_motor_stop.yaml"), {{"duration_s", "8"}});
      s.seed = seed;
      sim::FaultSpec f;
      f.rotor = second;
      f.kind = vehicle::FaultKind::kPropellerLoss;
      f.onset = {sim::FaultOnset::Kind::kAtTime, 5.0};
      s.faults.push_back(f);
      const RunSummary r = RunScenario(s);
      const std::string what = fmt::format("seed {} rotor {}", seed, second);
      ASSERT_TRUE(r.fdd && r.fdd->second) << what;
      EXPECT_TRUE(r.fdd->correct) << what;
      if (second == 1) {
        // The twin carries nothing: the vehicle flies on as before, and nothing else is isolated.
        EXPECT_TRUE(r.success) << what << ": " << r.failure_reason.value_or("");
        EXPECT_NE(r.stack.final_mode, stack::FlightMode::kFlightTermination) << what;
        EXPECT_EQ(r.stack.reconfigurations.size(), r.fdd->second->isolated ? 2u : 1u) << what;
      } else {
        EXPECT_TRUE(r.fdd->second->correct) << what;
        // Isolated well before the fall from 2 m ends (0.64 s). The latency's distribution is bench
        // ftc's (hover/motor_stop_then_adjacent; docs/results.md, its second failures), whose tail passes
        // 0.1 s: three seeds can only say that it is not far out.
        EXPECT_LT(r.fdd->second->latency_s.value_or(1e9), 0.3) << what;
        EXPECT_EQ(r.stack.final_mode, stack::FlightMode::kFlightTermination) << what;
        EXPECT_TRUE(r.crashed) << what;
        EXPECT_NE(r.failure_reason.value_or("").find("after flight termination"), std::string::npos) << what;
        ASSERT_TRUE(r.crash_speed_m_s) << what;
        // Falling from 2 m: at most sqrt(2 g h) = 6.26 m/s, drag only slowing it.
        EXPECT_LT(*r.crash_speed_m_s, std::sqrt(2.0 * kGravity * 2.0)) << what;
        // The parachute's release goes out with the termination's command: after the second
        // isolation, within a control period and the drawn computation and ESC delays.
        ASSERT_TRUE(r.parachute_release_s) << what;
        const double isolated_s = 5.0 + *r.fdd->second->latency_s;
        EXPECT_GE(*r.parachute_release_s, isolated_s) << what;
        EXPECT_LT(*r.parachute_release_s, isolated_s + 0.012) << what;
      }
      if (second == 1) {
        EXPECT_FALSE(r.parachute_release_s) << what << ": a vehicle that flies on releases nothing";
      }
    }
  }
}

TEST(FddClosedLoop, AParachuteReleasedOnTerminationSlowsTheFallOfTwoAdjacentRotorsLost) {
  // The second test's adjacent double failure, with and without a parachute: the canopy only
  // drags, so the vehicle reaches the ground later and slower (from 2 m it has about 0.6 s).
  std::optional<double> without, with;
  for (const bool fitted : {false, true}) {
    Scenario s = LoadScenario(Config("fdd_hover_motor_stop.yaml"), {{"duration_s", "8"}});
    s.seed = 1;
    s.sim.parachute.fitted = fitted;
    sim::FaultSpec f;
    f.rotor = 2;
    f.kind = vehicle::FaultKind::kPropellerLoss;
    f.onset = {sim::FaultOnset::Kind::kAtTime, 5.0};
    s.faults.push_back(f);
    const RunSummary r = RunScenario(s);
    ASSERT_TRUE(r.crashed && r.crash_speed_m_s && r.parachute_release_s) << fitted;
    (fitted ? with : without) = r.crash_speed_m_s;
  }
  EXPECT_LT(*with, *without - 0.3) << "without " << *without << " m/s";
}

TEST(FddClosedLoop, NoFalseAlarmOnTheAggressiveNominalLemniscate) {
  for (std::uint64_t seed : {21u, 22u}) {
    Scenario s = LoadScenario(Config("lemniscate_2ms.yaml"), {{"stack.controller", "nmpc"}, {"stack.fdd", "composite"}});
    s.seed = seed;
    const RunSummary r = RunScenario(s);
    ASSERT_TRUE(r.fdd.has_value());
    const std::optional<FddRecord::Diagnosis>& d = r.fdd->diagnosis;
    EXPECT_FALSE(d.has_value()) << "seed " << seed << ": " << d->kind << " on rotor " << d->rotor << " by "
                                << d->detector << " at " << d->detection_s;
  }
}

TEST(FddClosedLoop, AFaultDuringTakeoffOnEachRotorEndsInAStableHover) {
  for (int rotor = 0; rotor < 4; ++rotor) {
    for (const char* kind : {"propeller_loss", "motor_stop"}) {
      const Scenario s =
          LoadScenario(Config("fdd_takeoff_propeller_loss.yaml"),
                       {{"truth", "ideal"}, {"faults.0.rotor", std::to_string(rotor)}, {"faults.0.kind", kind}});
      const RunSummary r = RunScenario(s);
      EXPECT_TRUE(r.success) << "rotor " << rotor << " " << kind << ": " << r.failure_reason.value_or("");
      ASSERT_TRUE(r.fdd.has_value());
      EXPECT_TRUE(r.fdd->correct) << "rotor " << rotor << " " << kind;
      EXPECT_LT(r.fdd->latency_s, 0.025) << "rotor " << rotor << " " << kind;
      // MiniA: at most 5 cm lost from the altitude of the onset (docs/metrics.md).
      ASSERT_TRUE(r.altitude_change_m.has_value());
      EXPECT_GE(*r.altitude_change_m, -0.05) << "rotor " << rotor << " " << kind;
    }
  }
}

TEST(PassiveClosedLoop, TracksTheNominalLemniscateWithYawLeftFree) {
  const RunSummary r = RunScenario(LoadScenario(
      Config("lemniscate_2ms.yaml"), {{"truth", "ideal"}, {"stack.controller", "passive"}, {"duration_s", "20"}}));
  EXPECT_TRUE(r.success) << r.failure_reason.value_or("");
  EXPECT_LT(r.tracking_rmse_m, 0.10);
}

// The INDI baseline, driven by the composite FDD's isolation, keeps a hover through either fault
// kind on every rotor (the reconfiguration path through the stack for the second FTC controller).
TEST(IndiClosedLoop, KeepsHoveringAfterEitherFaultOnEveryRotor) {
  for (int rotor = 0; rotor < 4; ++rotor) {
    for (const char* kind : {"propeller_loss", "motor_stop"}) {
      const RunSummary r =
          RunScenario(LoadScenario(Config("fdd_hover_propeller_loss.yaml"), {{"truth", "ideal"},
                                                                             {"stack.controller", "indi"},
                                                                             {"faults.0.rotor", std::to_string(rotor)},
                                                                             {"faults.0.kind", kind}}));
      EXPECT_TRUE(r.success) << "rotor " << rotor << " " << kind << ": " << r.failure_reason.value_or("");
      ASSERT_TRUE(r.fdd.has_value());
      EXPECT_TRUE(r.fdd->correct) << "rotor " << rotor << " " << kind;
      EXPECT_GT(r.max_spin_rad_s, 9.0) << "yaw is given up: the vehicle spins";
      EXPECT_GT(r.min_altitude_m, 1.0);
    }
  }
}

// The whole LiDAR path in the loop: a vehicle spinning at about 11 rad/s after a propeller loss
// maps the room's walls, ground and pillar from deskewed frames; without deskewing the same frames
// smear into free space.
TEST(LidarClosedLoop, MapsTheRoomWhileSpinningAndDeskewingIsWhatKeepsItSharp) {
  double precision[2] = {0.0, 0.0};
  const Scenario s = LoadScenario(Config("room_lidar_propeller_loss.yaml"), {{"truth", "ideal"}});
  for (int deskew = 0; deskew < 2; ++deskew) {
    Scenario variant = s;
    variant.stack.lidar.deskew_frames = deskew == 1;
    RunOptions o;
    double p = 0.0;
    o.on_control_cycle = [&](const stack::FlightStack& st) {
      if (st.map() && st.command().t_ns == FromSeconds(s.duration_s) - st.control_period_ns()) {
        p = MapPrecision(*st.map(), s.world);
      }
    };
    const RunSummary r = RunScenario(variant, o);
    EXPECT_TRUE(r.success) << r.failure_reason.value_or("");
    EXPECT_GT(r.max_spin_rad_s, 9.0);
    EXPECT_GT(r.stack.map_voxels_occupied.value_or(-1), 5000);
    EXPECT_GT(r.stack.lidar_points_dropped, 0) << "pulses into the open sky";
    EXPECT_GT(r.cost_ms_per_sim_s.mapper, 0.0) << "the stack's LiDAR frames are timed";
    precision[deskew] = p;
  }
  EXPECT_GT(precision[1], 0.95) << "deskewed";    // measured 1.000
  EXPECT_LT(precision[0], 0.9) << "raw frames";  // measured 0.70
}

// Navigation on the stack's own map: the room's furniture is only ever seen by the simulated
// LiDAR, the planner flies both waypoints around it, and the vehicle keeps its radius from every
// true surface (checked here against the world at each control cycle, beside the simulator's crash
// detection).
TEST(NavigationClosedLoop, FliesTheRoomsWaypointsOnItsLidarMap) {
  const Scenario s = LoadScenario(Config("room_navigate.yaml"), {{"truth", "ideal"}});
  double closest = 1e9;
  RunOptions o;
  o.on_control_cycle = [&](const stack::FlightStack& st) {
    // The planned reference, as flown, against the furniture and walls (not the floor).
    closest = std::min(closest, s.world.DistanceToObstacles(st.reference_point().p_W, 0.0));
  };
  const RunSummary r = RunScenario(s, o);
  EXPECT_TRUE(r.success) << r.failure_reason.value_or("");
  EXPECT_EQ(r.stack.navigation.value().waypoints_reached, 2);
  EXPECT_EQ(r.stack.navigation.value().waypoints_total, 2);
  EXPECT_GE(r.stack.navigation.value().plans, 5) << "replanned as the map filled in";
  EXPECT_GT(r.cost_ms_per_sim_s.planner, 0.0) << "the planning is timed";
  // The stack's real-time factor is the simulated time over the stack's parts of the wall-clock
  // time (the simulator and the runner left out), so it is the larger of the two factors.
  const RunCost& c = r.cost_ms_per_sim_s;
  EXPECT_NEAR(r.stack_realtime_factor, 1e3 / (c.odometry + c.mapper + c.planner + c.controller + c.stack_other),
              1e-9 * r.stack_realtime_factor);
  EXPECT_GT(r.stack_realtime_factor, r.realtime_factor);
  EXPECT_GT(closest, s.vehicle.collision_radius_m) << "the reference kept the vehicle's radius from the furniture";
  EXPECT_LT(r.tracking_rmse_m, 0.1);
}

// The stack localises itself: the forest's first 25 s in the realistic world, propeller 0 lost at
// 16 s, flown on the stack's LiDAR-inertial odometry instead of the simulated odometry. Every
// frame after the first eight is registered (they start the map; measured: 241 of 249), none
// degenerate (the trunks and the ground constrain every direction), the estimate stays within
// centimetres of the truth through the failure and the 15 rad/s spin that follows, and the
// vehicle flies where it should. The realistic world's LiDAR is turned from the body (up to 0.5°
// per axis) and its clock off (up to 2 ms); the odometry learns both, but the first frames start
// the map with the mount as the file gives it, and the map keeps that turn: most of the 6 cm
// measured here (2.4 cm with the mount exact; docs/navigation.md).
TEST(LioClosedLoop, TheForestFlightsFirstSecondsAndItsFailureOnTheStacksOwnOdometry) {
  Scenario s = LoadScenario(Config("forest.yaml"), {{"truth", "realistic"}, {"duration_s", "25"}});
  s.stack.estimator.kind = stack::EstimatorKind::kLio;
  const RunSummary r = RunScenario(s);
  ASSERT_FALSE(r.crashed) << r.crash_reason.value_or("");
  EXPECT_GT(r.max_spin_rad_s, 9.0) << "the failure happened";
  const stack::LioSummary& o = r.stack.odometry.value();
  // A frame arrives once its stamped end has come: a clock ahead holds the last one past 25 s.
  EXPECT_EQ(o.frames, r.truth.lidar_clock_offset_s > 0.0 ? 249 : 250);
  EXPECT_GE(o.frames_used, o.frames - s.stack.estimator.lio.seed_frames - 1)
      << "the first frames start the map, the next may extend it";
  EXPECT_LE(o.frames_degenerate, o.frames / 100);
  EXPECT_GT(r.cost_ms_per_sim_s.odometry, 0.0) << "the registration is timed";
  EXPECT_LT(r.estimate_position_rmse_m, 0.08);  // measured 0.060 (max 0.109)
  // The clock's offset it learnt: measured 1.458 ms against the drawn 1.452 ms.
  EXPECT_NEAR(o.lidar_time_offset_s, r.truth.lidar_clock_offset_s, 3e-4);
  // Measured 0.047: mostly the estimate's age at the control cycle (the newest IMU sample's, up to
  // 3 ms old) while the vehicle turns at up to 15 rad/s.
  EXPECT_LT(r.estimate_attitude_max_rad, 0.06);
  EXPECT_LT(r.tracking_rmse_m, 0.2);  // measured 0.180
}

}  // namespace
}  // namespace rotorguard::harness
