// The scenario loader on hand-written files: every section's keys land in the fields they name
// (the oracle is the file's own numbers), absent keys keep the options structs' defaults, errors
// name the file, line and key, the mission comes back as a value, and docs/scenarios.md's key
// tables are the ones the loader reads.

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <vector>

#include "rotorguard/harness/assembly_mission.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/harness/scenario_keys.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/json_archive.h"
#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/vehicle/faults.h"
#include "test_util.h"

namespace rotorguard::harness {
namespace {

const std::string kVehicle = testing::SourcePath("configs/vehicles/zhou2025_quad.yaml");

class ScenarioLoader : public testing::TempFolderTest {
 protected:
  /// A scenario file of the reference vehicle with `body` after its first lines.
  std::string File(const std::string& body, const std::string& name = "s.yaml") {
    return Write(name, "vehicle: " + kVehicle + "\nduration_s: 10\n" + body);
  }
  /// The message of the ConfigError loading `body` raises ("(no error)" without one).
  std::string Error(const std::string& body) {
    try {
      LoadScenario(File(body));
    } catch (const io::ConfigError& e) {
      return e.what();
    }
    return "(no error)";
  }
};

// Every name of the fault kinds' table loads as its kind, and a name outside it is refused with the
// table's names: the loader reads the one table (vehicle::kFaultKindNames), not a list of its own.
TEST_F(ScenarioLoader, FaultKindsComeFromTheirNameTable) {
  std::vector<std::string> names;
  for (const EnumName<vehicle::FaultKind>& n : vehicle::kFaultKindNames) {
    names.emplace_back(n.name);
    const std::string eta = n.value == vehicle::FaultKind::kLossOfEffectiveness ? ", eta: 0.3" : "";
    const Scenario s = LoadScenario(File(fmt::format(
        "mission: {{type: hover}}\nfaults: [{{rotor: 1, kind: {}{}, onset: {{at_time_s: 2.0}}}}]\n", n.name, eta)));
    ASSERT_EQ(s.faults.size(), 1u) << n.name;
    EXPECT_EQ(s.faults[0].kind, n.value) << n.name;
    EXPECT_EQ(vehicle::ToString(n.value), n.name);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"motor_stop", "propeller_loss", "loss_of_effectiveness", "stuck"}));
  EXPECT_EQ(vehicle::ToString(vehicle::FaultKind::kNone), "none");  // a healthy rotor, never a file's kind
  for (const char* refused : {"none", "propeller"}) {
    const std::string error = Error(fmt::format(
        "mission: {{type: hover}}\nfaults: [{{rotor: 1, kind: {}, onset: {{at_time_s: 2.0}}}}]\n", refused));
    EXPECT_NE(error.find("faults.0.kind"), std::string::npos) << error;
    EXPECT_NE(error.find(fmt::format("{}", fmt::join(names, ", "))), std::string::npos) << error;
  }
}

// A scenario's options (sim, sensors, wind, stack, metrics) as the keys their structs declare:
// written back unchanged they change nothing; a key set through them gives the scenario the loader
// gives with the same key overridden (one set of keys, one loader); a bad value or a section that
// defines what is flown is refused naming the key, and leaves the scenario as it was.
TEST_F(ScenarioLoader, OptionsWrittenBackChangeNothingAndASetKeyEqualsTheLoadersOverride) {
  const std::string file = File("mission: {type: hover, position_m: [0, 0, 1.5]}\nstack: {controller: nmpc}\n");
  Scenario s = LoadScenario(file);
  const nlohmann::json before = ScenarioOptions(s);
  ASSERT_TRUE(before.contains("stack") && before["stack"].contains("nmpc"));
  SetScenarioOptions(&s, before.dump(1), "<options>");
  EXPECT_EQ(ScenarioOptions(s), before);

  SetScenarioOptions(&s, "stack: {nmpc: {q_position: [50, 60, 700]}}\nsim: {physics_rate_hz: 2000}\n", "<options>");
  const Scenario overridden =
      LoadScenario(file, {{"stack.nmpc.q_position", "[50, 60, 700]"}, {"sim.physics_rate_hz", "2000"}});
  EXPECT_EQ(ScenarioOptions(s), ScenarioOptions(overridden));
  EXPECT_EQ(s.stack.nmpc.q_position, Vector3(50, 60, 700));
  EXPECT_EQ(s.sim.physics_rate_hz, 2000.0);
  // An optional number is written null when unset, and null unsets it.
  SetScenarioOptions(&s, "stack: {planner: {post_failure_clearance_m: 0.5}}", "<options>");
  EXPECT_EQ(s.stack.navigation.replanner.post_failure_clearance_m, 0.5);
  SetScenarioOptions(&s, "stack: {planner: {post_failure_clearance_m: null}}", "<options>");
  EXPECT_FALSE(s.stack.navigation.replanner.post_failure_clearance_m.has_value());

  const nlohmann::json set = ScenarioOptions(s);
  const auto refused = [&](const std::string& text) {
    try {
      SetScenarioOptions(&s, text, "<options>");
    } catch (const io::ConfigError& e) {
      EXPECT_EQ(ScenarioOptions(s), set) << "unchanged after: " << e.what();
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string range = refused("stack:\n  nmpc:\n    horizon_steps: 0\n");
  EXPECT_NE(range.find("<options>:3"), std::string::npos) << range;
  EXPECT_NE(range.find("stack.nmpc.horizon_steps"), std::string::npos) << range;
  const std::string flown = refused("faults: []\n");
  EXPECT_NE(flown.find("set when it is loaded"), std::string::npos) << flown;
  const std::string unknown = refused("stack: {no_such_key: 1}\n");
  EXPECT_NE(unknown.find("no_such_key"), std::string::npos) << unknown;
}

// Setting one section re-runs the loader's readers of the others (the stack is fitted to the
// sensors again): a value the file gave, or a default of the loaded vehicle overridden there, stays.
TEST_F(ScenarioLoader, SettingOneSectionKeepsTheOthersAsLoaded) {
  const std::string file = testing::SourcePath("configs/scenarios/mars_reconfigure_3x1.yaml");
  Scenario s = LoadScenario(file, {{"stack.supervisor.max_failed_rotors", "2"}});
  ASSERT_TRUE(s.assembly);
  ASSERT_NE(s.assembly->FailedRotorAllowance(), 2) << "the override must differ from the assembly's default";
  nlohmann::json expected = ScenarioOptions(s);
  SetScenarioOptions(&s, "sim: {log_rate_hz: 50}\n", "<options>");
  EXPECT_EQ(s.stack.supervisor.max_failed_rotors, 2);
  expected["sim"]["log_rate_hz"] = 50.0;
  EXPECT_EQ(ScenarioOptions(s), expected);
}

TEST_F(ScenarioLoader, AbsentKeysKeepEveryDefault) {
  const Scenario s = LoadScenario(File("mission: {type: hover}\n"));
  EXPECT_EQ(s.name, "s");  // the file's name
  EXPECT_EQ(s.seed, 1u);
  EXPECT_EQ(s.mission_kind, MissionKind::kHover);
  // Every stack key at its default: compared through the keys' own JSON, so a new key counts too.
  // The composite FDD's thresholds are the vehicle's own (its file names them).
  stack::FlightStackOptions defaults;
  defaults.composite_fdd = LoadVehicleFdd(kVehicle)->first;
  EXPECT_NE(defaults.composite_fdd.motor_index_threshold, fdd::CompositeFddOptions{}.motor_index_threshold);
  EXPECT_EQ(io::ToJson(s.stack), io::ToJson(defaults));
  EXPECT_EQ(io::ToJson(s.sim.imu), io::ToJson(sim::ImuOptions{}));
  EXPECT_FALSE(s.sim.lidar.enabled);
  EXPECT_EQ(s.success.error_m, 0.5);
  EXPECT_FALSE(s.tracking_end_s.has_value());
}

TEST_F(ScenarioLoader, TruthIsAPresetWordOrABlockThatOverridesItsRanges) {
  EXPECT_EQ(LoadScenario(File("mission: {type: hover}\n")).truth.preset, sim::TruthPreset::kRealistic);
  EXPECT_EQ(LoadScenario(File("truth: ideal\nmission: {type: hover}\n")).truth.preset, sim::TruthPreset::kIdeal);
  const Scenario s = LoadScenario(File("truth: {preset: realistic, mass_fraction: 0.02}\nmission: {type: hover}\n"));
  EXPECT_EQ(s.truth.Ranges().mass_fraction, 0.02);
  EXPECT_EQ(s.truth.Ranges().inertia_fraction, sim::RangesOf(sim::TruthPreset::kRealistic).inertia_fraction);
  const std::string f = (dir_ / "s.yaml").string();
  EXPECT_EQ(Error("truth: exact\nmission: {type: hover}\n"),
            f + ":3:8: truth: 'exact' is not allowed; expected one of: ideal, realistic");
  EXPECT_EQ(Error("truth: {mass_fraction: 0.9}\nmission: {type: hover}\n"),
            f + ":3:24: truth.mass_fraction: '0.9' is out of range; expected a number in [0, 0.5]");
  EXPECT_EQ(Error("truth: {motor_stop_time_constant_min_s: 0.01}\nmission: {type: hover}\n"),
            f + ":3:8: truth.motor_stop_time_constant_max_s: motor_stop_time_constant_max_s is missing; expected both "
                "motor_stop_time_constant_min_s and motor_stop_time_constant_max_s or neither");
}

TEST_F(ScenarioLoader, EverySectionsKeysLandInTheirFields) {
  const Scenario s = LoadScenario(File(R"(seed: 42
initial: {position_m: [1, 2, 3], yaw_rad: 0.5}
sim: {physics_rate_hz: 2000, log_rate_hz: 50}
sensors:
  imu: {rate_hz: 400}
  odometry: {outages: [{start_s: 2, duration_s: 0.5}]}
  lidar: {frame_rate_hz: 5}
wind: {gust_std_m_s: 0.2}
world:
  cylinders: [{center_m: [4, 5], radius_m: 0.2, height_m: 3}]
mission: {type: navigate, waypoints_m: [[3, 0, 1], [6, 0, 1]], rounds: 2}
stack:
  controller: nmpc
  fdd: composite
  nmpc: {horizon_steps: 15, q_attitude: [1, 2, 3, 4]}
  composite_fdd: {motor_index_samples: 3}
  planner: {rate_hz: 5, v_max: 1.5, altitude_band_m: [0.8, 2.0], weights: {time: 20}, clearance_m: 0.8}
  flatness: {theta_max_deg: 15}
  map: {clearing_stride: 2, inflation_margin_m: 0.2}
  deskew_frames: false
  known_faults: [{rotor: 2, at_time_s: 1.5}]
metrics: {tracking_start_s: 1, success_hold_s: 3}
)"));
  EXPECT_EQ(s.seed, 42u);
  EXPECT_EQ(s.initial_position_m, Vector3(1, 2, 3));
  EXPECT_EQ(s.initial_yaw_rad, 0.5);
  EXPECT_EQ(s.sim.physics_rate_hz, 2000.0);
  EXPECT_EQ(s.log_rate_hz, 50.0);
  EXPECT_EQ(s.sim.imu.rate_hz, 400.0);
  ASSERT_EQ(s.sim.odometry.outages.size(), 1u);
  EXPECT_EQ(s.sim.odometry.outages[0].duration_s, 0.5);
  EXPECT_TRUE(s.sim.lidar.enabled) << "a lidar block switches the sensor on";
  EXPECT_EQ(s.sim.lidar.frame_rate_hz, 5.0);
  EXPECT_EQ(s.sim.wind.gust_std_m_s, 0.2);
  ASSERT_EQ(s.world.cylinders.size(), 1u);
  EXPECT_EQ(s.world.cylinders[0].center_m, Eigen::Vector2d(4, 5));
  // The mission's waypoints are what the stack's navigation flies.
  EXPECT_EQ(s.mission_kind, MissionKind::kNavigate);
  EXPECT_EQ(s.stack.navigation.waypoints.size(), 2u);
  EXPECT_EQ(s.stack.navigation.rounds, 2);
  EXPECT_EQ(s.stack.controller, stack::ControllerKind::kNmpc);
  EXPECT_EQ(s.stack.fdd, stack::FddKind::kComposite);
  EXPECT_EQ(s.stack.nmpc.horizon_steps, 15);
  EXPECT_EQ(s.stack.nmpc.q_attitude, Eigen::Vector4d(1, 2, 3, 4));
  EXPECT_EQ(s.stack.composite_fdd.motor_index_samples, 3);
  EXPECT_EQ(s.stack.navigation.planner_rate_hz, 5.0);
  EXPECT_EQ(s.stack.navigation.replanner.nominal.v_max, 1.5);
  EXPECT_EQ(s.stack.navigation.replanner.planner.search.z_min_m, 0.8);
  EXPECT_EQ(s.stack.navigation.replanner.planner.search.z_max_m, 2.0);
  EXPECT_EQ(s.stack.navigation.replanner.planner.optimizer.weights.time, 20.0);
  EXPECT_EQ(s.stack.navigation.replanner.planner.optimizer.weights.smoothness, 1.0) << "the others keep theirs";
  EXPECT_EQ(s.stack.navigation.replanner.planner.plane_search_m, 0.8) << "widened to the clearance kept";
  EXPECT_NEAR(s.stack.navigation.flatness.limits.theta_max_rad, 15.0 * std::numbers::pi / 180.0, 1e-15);
  EXPECT_EQ(s.stack.lidar.map.clearing_stride, 2);
  EXPECT_FALSE(s.stack.lidar.deskew_frames);
  // The inflation radius follows the vehicle's collision radius (0.2 m) and the margin.
  EXPECT_NEAR(s.stack.lidar.map.inflation_radius_m, 0.4, 1e-15);
  ASSERT_EQ(s.stack.known_faults.size(), 1u);
  EXPECT_EQ(s.stack.known_faults[0].rotor, 2);
  EXPECT_EQ(s.stack.known_faults[0].at_time_s, 1.5);
  EXPECT_EQ(s.stack.known_faults[0].loss, 1.0);
  // The fault detectors know the IMU that the sensors section describes.
  EXPECT_EQ(s.stack.composite_fdd.imu_rate_hz, 400.0);
  EXPECT_EQ(s.tracking_start_s, 1.0);
  EXPECT_EQ(s.success.hold_s, 3.0);
}

TEST_F(ScenarioLoader, APlannerWordIsShortForItsMethod) {
  // Paper 004's planner needs a vehicle with a PWM model.
  const Scenario s = LoadScenario(Write("q.yaml", "vehicle: " + testing::SourcePath("configs/vehicles/qball_x4.yaml") +
                                                      "\nduration_s: 10\n"
                                                      "mission: {type: hover}\nstack: {planner: flatness}\n"));
  EXPECT_EQ(s.stack.navigation.method, stack::NavigationMethod::kFlatness);
  EXPECT_NE(Error("mission: {type: hover}\nstack: {planner: astar}\n").find("expected one of: minco, flatness"),
            std::string::npos);
}

// The estimator: a word for its kind, or a block; the LiDAR-inertial odometry needs a LiDAR and
// learns both mounts from the sensors.
TEST_F(ScenarioLoader, TheEstimatorIsAWordOrABlockAndLioNeedsALidar) {
  Scenario s =
      LoadScenario(File("mission: {type: hover}\nsensors: {lidar: {position_m: [0, 0.01, 0.07]}}\n"
                        "stack: {estimator: lio}\n"));
  EXPECT_EQ(s.stack.estimator.kind, stack::EstimatorKind::kLio);
  EXPECT_EQ(s.stack.estimator.lio.lidar_position_m, Vector3(0, 0.01, 0.07));
  EXPECT_EQ(s.stack.estimator.lio.imu_position_m, s.sim.imu.position_m);
  s =
      LoadScenario(File("mission: {type: hover}\nsensors: {lidar: {}}\n"
                        "stack: {estimator: {kind: lio, lio: {max_iterations: 3, map: {voxel_m: 0.8}}}}\n"));
  EXPECT_EQ(s.stack.estimator.lio.max_iterations, 3);
  EXPECT_EQ(s.stack.estimator.lio.map.voxel_m, 0.8);
  EXPECT_EQ(LoadScenario(File("mission: {type: hover}\n")).stack.estimator.kind, stack::EstimatorKind::kOdometry);
  std::string m = Error("mission: {type: hover}\nstack: {estimator: lio}\n");
  EXPECT_NE(m.find("stack.estimator"), std::string::npos) << m;
  EXPECT_NE(m.find("estimator lio registers the LiDAR's frames; expected sensors.lidar"), std::string::npos) << m;
  m = Error(
      "mission: {type: hover}\nsensors: {lidar: {}}\nstack: {estimator: {kind: lio, lio: {plane_search_radius_m: "
      "2}}}\n");
  EXPECT_NE(m.find("plane_search_radius_m"), std::string::npos) << m;
  EXPECT_NE(m.find("(0, map.voxel_m]"), std::string::npos) << m;
}

TEST_F(ScenarioLoader, TheMissionComesBackAsAValue) {
  const io::ConfigDocument doc =
      io::ConfigDocument::LoadString("type: lemniscate\nmax_speed_m_s: 1.5\nsize_m: [4, 2, 0]\n", "m.yaml");
  const Mission m = ParseMission(doc.root(), Vector3(0, 0, 2), 0.3);
  EXPECT_EQ(m.kind, MissionKind::kLemniscate);
  const auto* lemniscate = dynamic_cast<const planning::LemniscateReference*>(m.reference.get());
  ASSERT_NE(lemniscate, nullptr);
  EXPECT_EQ(lemniscate->options().center_m, Vector3(0, 0, 2)) << "the centre defaults to the start";
  EXPECT_EQ(lemniscate->options().yaw_rad, 0.3) << "the heading too";
  EXPECT_EQ(lemniscate->options().size_x_m, 4.0);
  EXPECT_EQ(lemniscate->options().size_z_m, 0.0);
  EXPECT_FALSE(m.navigate.has_value());
  // Waypoints start where the vehicle does.
  const io::ConfigDocument w =
      io::ConfigDocument::LoadString("type: waypoints\nwaypoints_m: [[1, 0, 2]]\nmax_speed_m_s: 1\n", "w.yaml");
  const Mission waypoints = ParseMission(w.root(), Vector3(0, 0, 2), 0.0);
  const auto* legs = dynamic_cast<const planning::WaypointReference*>(waypoints.reference.get());
  ASSERT_NE(legs, nullptr);
  ASSERT_EQ(legs->options().waypoints_m.size(), 2u);
  EXPECT_EQ(legs->options().waypoints_m.front(), Vector3(0, 0, 2));
}

TEST_F(ScenarioLoader, AnAssemblysPlanIsMadeAfterLoadingNotInIt) {
  std::string text = io::ReadInputFile(testing::SourcePath("configs/scenarios/mars_plan_4x1.yaml"));
  text.replace(text.find("../assemblies/"), 14, testing::SourcePath("configs/assemblies/"));
  Scenario s = LoadScenario(Write("plan.yaml", text));
  ASSERT_TRUE(s.assembly_plan.has_value());
  EXPECT_EQ(s.reference, nullptr);
  EXPECT_EQ(s.assembly_plan->method, AssemblyPlanMethod::kOurs);
  PlanMission(&s);
  ASSERT_NE(s.reference, nullptr);
  EXPECT_GT(s.reference->duration(), 1.0);
  const std::shared_ptr<const ReferenceTrajectory> plan = s.reference;
  PlanMission(&s);  // planned once
  EXPECT_EQ(s.reference, plan);
}

TEST_F(ScenarioLoader, ErrorsNameTheFileLineAndKey) {
  std::string m = Error("mission: {type: hover}\nstack:\n  nmpc: {horizon_steps: 0}\n");
  EXPECT_NE(m.find("s.yaml:5:"), std::string::npos) << m;
  EXPECT_NE(m.find("stack.nmpc.horizon_steps"), std::string::npos) << m;
  EXPECT_NE(m.find("[1, 200]"), std::string::npos) << m;
  // A block's own rule, found after reading it, at the key that broke it.
  m = Error("mission: {type: hover}\nstack:\n  fdd: composite\n  composite_fdd: {motor_index_threshold: -1}\n");
  EXPECT_NE(m.find("s.yaml:6:"), std::string::npos) << m;
  EXPECT_NE(m.find("stack.composite_fdd.motor_index_threshold"), std::string::npos) << m;
  m = Error("mission: {type: hover}\nstack:\n  planner: {weights: {time: 1, speed: 2}}\n");
  EXPECT_NE(m.find("stack.planner.weights.speed: unknown key 'speed'; expected one of: time, smoothness, "
                   "feasibility, collision"),
            std::string::npos)
      << m;
  m = Error("mission: {type: cruise}\n");
  EXPECT_NE(m.find("hover, takeoff, land, lemniscate, circle, waypoints, navigate, assembly_plan"), std::string::npos) << m;
  m = Error("mission: {type: lemniscate}\n");
  EXPECT_NE(m.find("missing required key 'max_speed_m_s'"), std::string::npos) << m;
  m = Error("mission: {type: hover}\nstack: {known_faults: [{rotor: 1}]}\n");
  EXPECT_NE(m.find("missing required key 'at_time_s'"), std::string::npos) << m;
  m = Error("mission: {type: hover}\nstack: {known_faults: {rotor: 1}}\n");
  EXPECT_NE(m.find("expected a list of {rotor, at_time_s, loss}"), std::string::npos) << m;
  m = Error("mission: {type: hover}\nstack: {flatness: {theta_max_deg: 95}}\n");
  EXPECT_NE(m.find("theta_max_deg = 95 is invalid; expected an angle in (0, 90) deg"), std::string::npos) << m;
  m = Error("mission: {type: hover}\nworld: {boxes: [{center_m: [0, 0, 1], size_m: [1, 0, 1]}]}\n");
  EXPECT_NE(m.find("world.boxes.0.size_m.1: '0' is out of range; expected a number in (0, 20000]"), std::string::npos)
      << m;
}

TEST_F(ScenarioLoader, VehicleOverridesApplyToTheVehicleFile) {
  const Scenario s = LoadScenario(File("mission: {type: hover}\n"), {{"vehicle.mass_kg", "1.3"}});
  EXPECT_EQ(s.vehicle.mass_kg, 1.3);
  RG_EXPECT_THROW_WITH(LoadScenario(File("mission: {type: hover}\n"), {{"vehicle.mass", "1.3"}}), io::ConfigError,
                       "vehicle.mass");
  // A value the vehicle's rules reject is named as it was written, prefix included.
  RG_EXPECT_THROW_WITH(LoadScenario(File("mission: {type: hover}\n"), {{"vehicle.mass_kg", "-1"}}), io::ConfigError,
                       "--set: vehicle.mass_kg: '-1' is out of range");
  RG_EXPECT_THROW_WITH(LoadScenario(File("mission: {type: hover}\n"), {{"vehicle.rotors.0.max_thrust_n", "0.1"}}),
                       io::ConfigError, "vehicle.rotors.0.max_thrust_n: VehicleParams::rotors.0.max_thrust_n = 0.1");
}

TEST_F(ScenarioLoader, AVehiclesFddThresholdsFileIsTheDefaultAScenarioOverrides) {
  Write("thresholds.yaml", "propeller_index_threshold: 0.7\ntakeoff_index_threshold: 0.6\n");
  const std::string vehicle =
      Write("quad.yaml", rotorguard::testing::ReferenceVehicleWithoutFdd() + "fdd: thresholds.yaml\n");
  const auto scenario = [&](const std::string& stack) {
    return Write("fdd.yaml", "vehicle: quad.yaml\nduration_s: 10\nmission: {type: hover}\n" + stack);
  };
  Scenario s = LoadScenario(scenario(""));
  EXPECT_EQ(s.stack.composite_fdd.propeller_index_threshold, 0.7);
  EXPECT_EQ(s.stack.composite_fdd.takeoff_index_threshold, 0.6);
  EXPECT_EQ(s.stack.composite_fdd.motor_index_threshold, fdd::CompositeFddOptions{}.motor_index_threshold);
  EXPECT_NE(s.vehicle_fdd_file.find("thresholds.yaml"), std::string::npos);
  s = LoadScenario(scenario("stack: {composite_fdd: {propeller_index_threshold: 0.6}}\n"));
  EXPECT_EQ(s.stack.composite_fdd.propeller_index_threshold, 0.6);  // the scenario's word is the last
  EXPECT_EQ(s.stack.composite_fdd.takeoff_index_threshold, 0.6);
  // A bad key or value in the thresholds file is named there; a missing file where it is named.
  Write("thresholds.yaml", "propeller_index_threshold: 0.7\ngamma_p: 0.8\n");
  RG_EXPECT_THROW_WITH(LoadScenario(scenario("")), io::ConfigError, "thresholds.yaml:2:");
  Write("thresholds.yaml", "propeller_index_threshold: 0.1\n");  // below the partial-loss threshold
  RG_EXPECT_THROW_WITH(LoadScenario(scenario("")), io::ConfigError, "propeller_index_threshold");
  Write("quad.yaml", rotorguard::testing::ReferenceVehicleWithoutFdd() + "fdd: no_such.yaml\n");
  RG_EXPECT_THROW_WITH(LoadScenario(scenario("")), io::InputFileError, "named by 'fdd' at");
}

/// The keys a block's unknown-key error lists, from its message.
std::vector<std::string> ListedKeys(const std::string& message) {
  std::vector<std::string> keys;
  std::stringstream list(message.substr(message.find("expected one of: ") + 17));
  for (std::string k; std::getline(list, k, ',');) keys.push_back(k.substr(k.find_first_not_of(' ')));
  return keys;
}

// The tables cover exactly the keys the loader takes: a block's unknown-key error lists them.
TEST_F(ScenarioLoader, KeyTablesListEveryKeyTheLoaderTakes) {
  const std::string tables = ScenarioKeyTables();
  for (const std::string block : {"stack", "stack.nmpc", "stack.planner", "sensors.lidar", "metrics", "initial"}) {
    std::string yaml = "mission: {type: hover}\n";
    std::string indent;
    std::size_t start = 0;
    for (std::size_t dot = block.find('.');; dot = block.find('.', start)) {
      yaml += indent + block.substr(start, dot == std::string::npos ? std::string::npos : dot - start) + ":\n";
      indent += "  ";
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
    yaml += indent + "no_such_key: 1\n";
    const std::vector<std::string> keys = ListedKeys(Error(yaml));
    ASSERT_FALSE(keys.empty()) << block;
    for (const std::string& k : keys) {
      EXPECT_NE(tables.find("`" + block + "." + k), std::string::npos) << block << "." << k << " is not documented";
    }
  }
}

// The issue's example: a speed limit no multirotor reaches is refused where it is written, with
// its range, rather than flown (a collision check's step of check_step_m / v_max would vanish).
TEST_F(ScenarioLoader, AnAbsurdSpeedLimitIsRejectedWithItsRange) {
  const std::string f = (dir_ / "s.yaml").string();
  EXPECT_EQ(Error("mission: {type: hover}\nstack:\n  planner: {v_max: 1e9}\n"),
            f + ":5:20: stack.planner.v_max: '1e9' is out of range; expected a number in [0.001, 50]");
  EXPECT_EQ(Error("mission: {type: hover}\nstack:\n  planner: {v_max: 50}\n"), "(no error)");
  // The same bound for the options set in code.
  stack::NavigationOptions n;
  n.replanner.nominal.v_max = 1e9;
  RG_EXPECT_THROW_WITH(n.Validate(), ValidationError,
                       "NavigationOptions::v_max = 1000000000 is invalid; expected a number in [0.001, 50]");
  n.replanner.nominal.v_max = 50.0;
  EXPECT_NO_THROW(n.Validate());
}

TEST_F(ScenarioLoader, ClearancesBeyondTheMapsFastObstacleSearchAreRefusedNamingTheKey) {
  // Found by generating flights (tests/fuzz): stack.planner.clearance_m 10, in its range, made every
  // obstacle query of the planner scan a 20-m cube, and a 2.6-s forest flight plan for minutes.
  const std::string nav = "mission: {type: navigate, waypoints_m: [[5, 0, 1]]}\nsensors: {lidar: {}}\nstack:\n";
  const double fast = perception::VoxelMap::FastNearestRadiusM(0.1);  // the map's default voxel
  EXPECT_NEAR(fast, 1.11, 0.005);
  EXPECT_EQ(Error(nav + fmt::format("  planner: {{clearance_m: {}}}\n", fast)), "(no error)");
  std::string m = Error(nav + "  planner: {clearance_m: 1.2}\n");
  EXPECT_NE(m.find("stack.planner.clearance_m: FlightStackOptions::planner.clearance_m = 1.2 is invalid; expected a "
                   "distance of at most 1.11 m"),
            std::string::npos)
      << m;
  m = Error(nav + "  planner: {post_failure_clearance_m: 10}\n");
  EXPECT_NE(m.find("stack.planner.post_failure_clearance_m"), std::string::npos) << m;
  // A map too fine for the planner's own 0.5-m search is named by its resolution.
  m = Error(nav + "  planner: {clearance_m: 0.1}\n  map: {resolution_m: 0.02, window_size_m: [8, 8, 4]}\n");
  EXPECT_NE(m.find("stack.map.resolution_m"), std::string::npos) << m;
  EXPECT_NE(m.find("a voxel edge of at least 0.0449 m"), std::string::npos) << m;
}

/// The numeric keys of `rows` whose rule states no range bounded on both sides ("a number",
/// "> 0", "≥ 0", "[x, y, z]"), as "key: rule".
std::vector<std::string> UnboundedNumericKeys(const std::vector<io::KeyRow>& rows, const std::string& prefix) {
  std::vector<std::string> unbounded;
  for (const io::KeyRow& r : rows) {
    if (!r.numeric()) continue;
    std::string rule = r.rule;
    if (const std::string required = "**required**, "; rule.starts_with(required)) rule.erase(0, required.size());
    const bool bare = rule == "a number" || rule == "> 0" || rule == "≥ 0" || rule == "an integer";
    const bool bounded = rule.find("in [") != std::string::npos || rule.find("in (") != std::string::npos;
    if (bare || !bounded) unbounded.push_back(prefix + r.key + ": " + r.rule);
  }
  return unbounded;
}

// Every number a scenario or vehicle file takes has a range bounded on both sides, stated in the
// key tables (and so in docs/scenarios.md): a key added without one fails here.
TEST(ScenarioDocs, EveryNumericKeyHasABoundedRange) {
  std::vector<std::string> unbounded = UnboundedNumericKeys(VehicleKeyRows(), "vehicle: ");
  std::size_t numeric = 0;
  for (const KeyTableSection& section : ScenarioKeySections()) {
    const std::vector<std::string> more = UnboundedNumericKeys(section.rows, section.prefix);
    unbounded.insert(unbounded.end(), more.begin(), more.end());
    for (const io::KeyRow& r : section.rows) numeric += r.numeric() ? 1 : 0;
  }
  EXPECT_GT(numeric, 150u) << "the walk must see the numeric keys";
  std::string list;
  for (const std::string& k : unbounded) list += k + "\n";
  EXPECT_TRUE(unbounded.empty()) << "keys without a bounded range:\n" << list;
}

/// Keys with and without ranges, for the walk's own test.
struct MadeUpKeys {
  double free = 0.0, positive = 1.0, bounded = 1.0;
  Vector3 vector = Vector3::Zero();
  int count = 1;
  bool flag = false;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("free", &free, {.meaning = "x"});
    a->Visit("positive", &positive, {.meaning = "x", .positive = true, .required = true});
    a->Visit("bounded", &bounded, {.meaning = "x", .max = 2.0, .positive = true});
    a->Visit("vector", &vector, {.meaning = "x"});
    a->Visit("count", &count, {.meaning = "x", .min = 1});
    a->Visit("flag", &flag, {.meaning = "x"});
  }
};

// The walk above finds a key without a range, one bounded below only, and a vector without one.
TEST(ScenarioDocs, TheRangeCheckFindsUnboundedKeys) {
  MadeUpKeys made;
  io::KeyTableWriter writer;
  made.Serialize(&writer);
  EXPECT_EQ(UnboundedNumericKeys(writer.rows(), ""),
            (std::vector<std::string>{"free: a number", "positive: **required**, > 0", "vector: [x, y, z]",
                                      "count: an integer ≥ 1"}));
}

/// The text between `begin` and `end` in docs/scenarios.md.
std::string DocsRegion(const std::string& begin, const std::string& end) {
  std::ifstream in(testing::SourcePath("docs/scenarios.md"));
  std::stringstream doc;
  doc << in.rdbuf();
  const std::string text = doc.str();
  const std::size_t a = text.find(begin), b = text.find(end);
  if (a == std::string::npos || b == std::string::npos) return "(markers not found)";
  return text.substr(a + begin.size(), b - a - begin.size());
}

// docs/scenarios.md holds the tables the code writes (`rotorguard keys`), unedited.
TEST(ScenarioDocs, TheKeyTablesAreTheCodes) {
  EXPECT_EQ(DocsRegion("<!-- BEGIN rotorguard keys: generated, do not edit by hand -->\n", "<!-- END rotorguard keys -->"),
            ScenarioKeyTables())
      << "docs/scenarios.md's key tables are out of date: replace the lines between the markers with the output "
         "of `rotorguard keys`";
  EXPECT_EQ(DocsRegion("<!-- BEGIN rotorguard keys --vehicle: generated, do not edit by hand -->\n",
                       "<!-- END rotorguard keys --vehicle -->"),
            VehicleKeyTable())
      << "docs/scenarios.md's vehicle table is out of date: replace it with the output of `rotorguard keys --vehicle`";
}

}  // namespace
}  // namespace rotorguard::harness
