// Paper 002's assemblies in the closed loop (configs/scenarios/mars_spiral_3x2.yaml): the assembly
// flies as one multirotor of 24 rotors in the simulator, the stack's assembly controller
// reallocates over the rotors it knows to be degraded.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "rotorguard/harness/assembly_mission.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "test_util.h"

namespace rotorguard::harness {
namespace {

std::string Config(const std::string& path) { return testing::SourcePath("configs/" + path); }

/// Unit No. 1 (rotors 0-3) dead from the start, known to the controller.
const std::vector<Override> kDeadUnit = {
    {"faults", "[{rotor: 0, kind: motor_stop, onset: {at_time_s: 0}}, {rotor: 1, kind: motor_stop, onset: "
               "{at_time_s: 0}}, {rotor: 2, kind: motor_stop, onset: {at_time_s: 0}}, {rotor: 3, kind: motor_stop, "
               "onset: {at_time_s: 0}}]"},
    {"stack.known_faults", "[{rotor: 0, at_time_s: 0}, {rotor: 1, at_time_s: 0}, {rotor: 2, at_time_s: 0}, "
                           "{rotor: 3, at_time_s: 0}]"},
    {"duration_s", "20"}};

RunSummary Fly(std::vector<Override> overrides, const std::string& reallocation) {
  overrides.emplace_back("stack.assembly.reallocation", reallocation);
  overrides.emplace_back("truth", "ideal");
  return RunScenario(LoadScenario(Config("scenarios/mars_spiral_3x2.yaml"), overrides), RunOptions{});
}

TEST(MarsScenario, TheAssemblyTracksTheSpiralWithAHalfThrustRotor) {
  const Scenario s = LoadScenario(Config("scenarios/mars_spiral_3x2.yaml"), {{"truth", "ideal"}, {"duration_s", "20"}});
  ASSERT_TRUE(s.assembly);
  EXPECT_EQ(s.vehicle.num_rotors(), 24);
  EXPECT_DOUBLE_EQ(s.vehicle.mass_kg, 3.0);
  const RunSummary r = RunScenario(s, RunOptions{});
  EXPECT_TRUE(r.success) << r.failure_reason.value_or("");
  EXPECT_LT(r.tracking_rmse_m, 0.05);
}

TEST(MarsScenario, ReallocationCarriesADeadUnitThatTheFaultBlindAllocationCannot) {
  const RunSummary full = Fly(kDeadUnit, "full");
  const RunSummary none = Fly(kDeadUnit, "none");
  EXPECT_TRUE(full.success) << full.failure_reason.value_or("");
  EXPECT_NE(full.stack.final_mode, stack::FlightMode::kEmergencyLanding) << "four failed rotors are within an assembly's allowance";
  EXPECT_NE(full.stack.final_mode, stack::FlightMode::kLanded);
  EXPECT_LT(full.tracking_rmse_m, 0.03);
  EXPECT_GT(none.tracking_rmse_m, 4.0 * full.tracking_rmse_m);
}

TEST(MarsScenario, AssemblyKeysAreCheckedNamingTheKey) {
  const auto message = [](const std::string& file, const std::vector<Override>& o) {
    try {
      LoadScenario(Config(file), o);
    } catch (const io::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  std::string m = message("scenarios/hover.yaml", {{"stack.controller", "assembly"}});
  EXPECT_NE(m.find("controller assembly flies an assembly"), std::string::npos) << m;
  // Found by generating flights (tests/fuzz): INDI on an assembly passed validate, then failed the run.
  m = message("scenarios/mars_plan_3x2.yaml", {{"stack.controller", "indi"}});
  EXPECT_NE(m.find("stack.controller: controller indi is for a quadrotor, and the vehicle has 24 rotors"),
            std::string::npos)
      << m;
  m = message("scenarios/mars_spiral_3x2.yaml", {{"stack.assembly.reallocation", "hybrid"}});
  EXPECT_NE(m.find("stack.assembly.reallocation"), std::string::npos) << m;
  m = message("scenarios/mars_spiral_3x2.yaml", {{"stack.known_faults.0.loss", "1.5"}});
  EXPECT_NE(m.find("known_faults.0.loss"), std::string::npos) << m;
  m = message("scenarios/nmpc_hover_motor_stop_known.yaml",
              {{"stack.known_faults", "[{rotor: 0, at_time_s: 1, loss: 0.5}]"}});
  EXPECT_NE(m.find("1 unless the controller is assembly"), std::string::npos) << m;
}

/// A scenario loaded, then its assembly's mission planned.
Scenario LoadPlanned(const std::string& path, std::vector<Override> overrides = {}) {
  overrides.emplace_back("truth", "ideal");
  Scenario s = LoadScenario(path, overrides);
  PlanMission(&s);
  return s;
}

TEST(MarsScenario, APlannedRowPassesTheDoorLengthwiseAndFliesItWithoutTouching) {
  const Scenario loaded = LoadScenario(Config("scenarios/mars_plan_4x1.yaml"), {{"truth", "ideal"}});
  ASSERT_TRUE(loaded.assembly_plan);
  EXPECT_EQ(loaded.reference, nullptr) << "the loader reads; it does not plan";
  Scenario s = loaded;
  PlanMission(&s);
  const auto* plan = dynamic_cast<const modular::AssemblyTrajectory*>(s.reference.get());
  ASSERT_NE(plan, nullptr);
  // The tracking error is measured while the plan is flown, not over the hover after it.
  EXPECT_FALSE(s.tracking_end_s.has_value());
  EXPECT_EQ(TrackingEndS(s), plan->duration());
  EXPECT_LT(plan->duration(), s.duration_s);
  // The truth geometry (not the planner's map): every unit's sphere clear of every obstacle along
  // the plan, and the row lengthwise (within 20 degrees of x) where it crosses the wall at x = 0.
  bool crossed = false;
  for (double t = 0.0; t <= plan->duration(); t += 0.01) {
    const modular::AssemblyPose pose = plan->PoseAt(t);
    const double c = std::cos(pose.yaw_rad), sn = std::sin(pose.yaw_rad);
    for (const Vector3& u : s.assembly->unit_position_B) {
      const Vector3 p = pose.p_W + Vector3(c * u.x() - sn * u.y(), sn * u.x() + c * u.y(), 0.0);
      ASSERT_GE(s.world.DistanceToObstacles(p, t), s.assembly->unit_radius_m) << "t = " << t;
    }
    if (std::abs(pose.p_W.x()) < 0.05) {
      crossed = true;
      EXPECT_LT(std::abs(sn), std::sin(20.0 * std::numbers::pi / 180.0)) << "t = " << t;
    }
  }
  EXPECT_TRUE(crossed);
  const RunSummary r = RunScenario(s, RunOptions{});
  EXPECT_TRUE(r.success) << r.failure_reason.value_or("");  // the simulator checks every unit's sphere
  EXPECT_LT(r.tracking_rmse_m, 0.03);
}

TEST(MarsScenario, AReplannedReferenceBringsItsOwnTrackingWindow) {
  // bench mars loads the scene once and swaps in each method's plan: each flight must be scored
  // over its own plan, not over the plan the scene was loaded with.
  Scenario s = LoadPlanned(Config("scenarios/mars_plan_4x1.yaml"));
  const double ours = s.reference->duration();
  Scenario b = s;
  b.assembly_plan->method = AssemblyPlanMethod::kBaseline;
  const AssemblyPlanResult plan = PlanAssemblyMission(b);
  ASSERT_TRUE(plan.ok) << plan.message;
  s.reference = plan.trajectory;
  const double baseline = plan.trajectory->duration();
  ASSERT_GT(std::abs(baseline - ours), 0.1);  // the two plans differ, so the check below can fail
  EXPECT_EQ(TrackingEndS(s), baseline);
  const RunSummary r = RunScenario(s, RunOptions{});
  ASSERT_FALSE(r.crashed) << r.failure_reason.value_or("");
  EXPECT_NEAR(r.tracking_end_s, baseline, 1e-3);  // to the physics step
}

class MarsScenarioFile : public rotorguard::testing::TempFolderTest {};

TEST_F(MarsScenarioFile, ATrackingWindowThatStartsAfterThePlanIsAnErrorNamingTheKey) {
  std::string text = io::ReadInputFile(Config("scenarios/mars_plan_4x1.yaml"));
  text.replace(text.find("../assemblies/"), 14, Config("assemblies/"));
  const std::string late = Write("late.yaml", text + "metrics: {tracking_start_s: 15}\n");
  for (const char* part : {"late.yaml", "metrics.tracking_start_s", "the plan's duration"}) {
    RG_EXPECT_THROW_WITH(LoadPlanned(late), io::ConfigError, part);
  }
  // With its own end the window may lie after the plan (the hover at the goal).
  const Scenario s = LoadPlanned(Write("s.yaml", text + "metrics: {tracking_start_s: 15, tracking_end_s: 20}\n"));
  EXPECT_EQ(TrackingEndS(s), 20.0);
}

TEST(MarsScenario, AnUnplannableAssemblyMissionIsAConfigErrorNamingTheMission) {
  const auto message = [](const std::vector<Override>& o) {
    try {
      LoadPlanned(Config("scenarios/mars_plan_4x1.yaml"), o);
    } catch (const io::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  std::string m = message({{"mission.goal_m", "[0.0, -2.0, 1.2]"}});  // inside the wall
  EXPECT_NE(m.find("cannot plan the assembly's path: A*: goal_blocked"), std::string::npos) << m;
  EXPECT_NE(m.find("mission"), std::string::npos) << m;
  m = message({{"mission.method", "fastest"}});
  EXPECT_NE(m.find("mission.method"), std::string::npos) << m;
  m = message({{"mission.safety_factor", "1.5"}});
  EXPECT_NE(m.find("mission.safety_factor"), std::string::npos) << m;
  try {
    LoadScenario(Config("scenarios/hover.yaml"),
                 {{"truth", "ideal"}, {"mission", "{type: assembly_plan, goal_m: [1, 0, 1]}"}});
    ADD_FAILURE() << "a single vehicle accepted mission assembly_plan";
  } catch (const io::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("plans for an assembly"), std::string::npos) << e.what();
  }
}

TEST(MarsScenario, TheFinestKnownMapAKeyAcceptsCanBeBuilt) {
  // Found by generating flights (tests/fuzz): mission.map_resolution_m 0.02, in the key's range
  // then, made a 432-million-voxel window that the map refused after `validate` had passed.
  Scenario s = LoadScenario(Config("scenarios/mars_plan_3x2.yaml"));
  AssemblyPlanSpec spec = *s.assembly_plan;
  spec.map_resolution_m = AssemblyPlanSpec::kMinMapResolutionM;
  EXPECT_NO_THROW(KnownMapOptions(spec, *s.assembly).Validate());
  // The voxel map's own limit lies at 0.038 m (24 * 24 * 6 m^3 over 64 million voxels); the key
  // stops at 0.05 m, where the window's power-of-two store (4 bytes a voxel) takes 128 MiB instead
  // of 1 GiB at 0.04 m.
  spec.map_resolution_m = 0.035;
  EXPECT_THROW(KnownMapOptions(spec, *s.assembly).Validate(), std::invalid_argument);
  RG_EXPECT_THROW_WITH(LoadScenario(Config("scenarios/mars_plan_3x2.yaml"), {{"mission.map_resolution_m", "0.02"}}),
                       io::ConfigError, "mission.map_resolution_m");
  // Set past the loader, the map the plan needs is the mission's error, not the map's.
  s.assembly_plan->map_resolution_m = 0.035;
  RG_EXPECT_THROW_WITH(PlanMission(&s), io::ConfigError,
                       "cannot plan the assembly's path: VoxelMapOptions::window_size_m");
}

class AssemblyFile : public testing::TempFolderTest {};

TEST_F(AssemblyFile, BadSlotsNameFileLineAndKey) {
  const std::string unit = Config("vehicles/mars_unit.yaml");
  const std::string path = Write("bad.yaml", "unit: " + unit + "\nspacing_m: 0.25\nslots:\n  - [0, 0]\n  - [0, 0]\n");
  try {
    LoadAssembly(path);
    ADD_FAILURE() << "expected an error";
  } catch (const io::ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("bad.yaml"), std::string::npos) << m;
    EXPECT_NE(m.find("slots.1"), std::string::npos) << m;
    EXPECT_NE(m.find("a grid cell no other unit occupies"), std::string::npos) << m;
  }
  const std::string close = Write("close.yaml", "unit: " + unit + "\nspacing_m: 0.1\nshape: 3x2\n");
  RG_EXPECT_THROW_WITH(LoadAssembly(close), io::ConfigError, "spacing_m");
  const std::string both = Write("both.yaml", "unit: " + unit + "\nspacing_m: 0.25\nshape: 3x2\nslots: [[0, 0]]\n");
  RG_EXPECT_THROW_WITH(LoadAssembly(both), io::ConfigError, "exactly one of 'shape' and 'slots'");
  const modular::Assembly a = LoadAssembly(Config("assemblies/3x3_plus.yaml"));
  EXPECT_EQ(a.num_units, 5);
}

TEST_F(AssemblyFile, AScenarioNamesEitherAVehicleOrAnAssembly) {
  const std::string path = Write("both.yaml", "vehicle: " + Config("vehicles/mars_unit.yaml") + "\nassembly: " +
                                                  Config("assemblies/3x2.yaml") +
                                                  "\nduration_s: 1\nmission: {type: hover}\n");
  RG_EXPECT_THROW_WITH(LoadScenario(path), io::ConfigError, "exactly one of 'vehicle' (a vehicle file) and 'assembly'");
}

}  // namespace
}  // namespace rotorguard::harness
