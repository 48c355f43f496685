// Paper 002's assemblies in the closed loop (configs/scenarios/mars_spiral_3x2.yaml): the assembly
// flies as one multirotor of 24 rotors in the simulator, the stack's assembly controller
// reallocates over the rotors it knows to be degraded.
#include <string>

#include <gtest/gtest.h>

#include "rotorguard/bench/runner.h"
#include "rotorguard/bench/scenario.h"
#include "rotorguard/io/config_node.h"
#include "test_util.h"

namespace rotorguard::bench {
namespace {

std::string Config(const std::string& path) { return std::string(ROTORGUARD_SOURCE_DIR) + "/configs/" + path; }

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
  return RunScenario(LoadScenario(Config("scenarios/mars_spiral_3x2.yaml"), overrides), RunOptions{});
}

TEST(MarsScenario, TheAssemblyTracksTheSpiralWithAHalfThrustRotor) {
  const Scenario s = LoadScenario(Config("scenarios/mars_spiral_3x2.yaml"), {{"duration_s", "20"}});
  ASSERT_TRUE(s.assembly);
  EXPECT_EQ(s.vehicle.num_rotors(), 24);
  EXPECT_DOUBLE_EQ(s.vehicle.mass_kg, 3.0);
  const RunSummary r = RunScenario(s, RunOptions{});
  EXPECT_TRUE(r.success) << r.failure_reason;
  EXPECT_LT(r.tracking_rmse_m, 0.05);
}

TEST(MarsScenario, ReallocationCarriesADeadUnitThatTheFaultBlindAllocationCannot) {
  const RunSummary full = Fly(kDeadUnit, "full");
  const RunSummary none = Fly(kDeadUnit, "none");
  EXPECT_TRUE(full.success) << full.failure_reason;
  EXPECT_NE(full.final_mode, "emergency_landing") << "four failed rotors are within an assembly's allowance";
  EXPECT_NE(full.final_mode, "landed");
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
  m = message("scenarios/mars_spiral_3x2.yaml", {{"stack.assembly.reallocation", "hybrid"}});
  EXPECT_NE(m.find("stack.assembly.reallocation"), std::string::npos) << m;
  m = message("scenarios/mars_spiral_3x2.yaml", {{"stack.known_faults.0.loss", "1.5"}});
  EXPECT_NE(m.find("known_faults.0.loss"), std::string::npos) << m;
  m = message("scenarios/nmpc_hover_motor_stop_known.yaml",
              {{"stack.known_faults", "[{rotor: 0, at_time_s: 1, loss: 0.5}]"}});
  EXPECT_NE(m.find("1 unless the controller is assembly"), std::string::npos) << m;
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
}  // namespace rotorguard::bench
