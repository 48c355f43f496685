// harness::Flight, the closed loop stepped by its caller: stepped by control periods or physics
// steps it is the flight RunScenario flies, and a command from outside is what the simulator
// flies.
#include "rotorguard/harness/flight.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "rotorguard/harness/flight_recorder.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/stack/flight_stack.h"
#include "rotorguard/vehicle/multirotor.h"
#include "same_flight.h"
#include "test_util.h"

namespace rotorguard::harness {
namespace {

Scenario FddHover(const char* duration_s) {
  return LoadScenario(testing::SourcePath("configs/scenarios/fdd_hover_propeller_loss.yaml"),
                      {{"duration_s", duration_s}});
}

/// The same flight, and the same tracking of the reference.
void ExpectSameFlight(const RunSummary& a, const RunSummary& b) {
  testing::ExpectSameFlight(a, b);
  EXPECT_EQ(a.tracking_rmse_m, b.tracking_rmse_m);
  EXPECT_EQ(a.max_position_error_m, b.max_position_error_m);
}

TEST(Flight, SteppedByControlPeriodsOrPhysicsStepsItIsTheFlightRunScenarioFlies) {
  const Scenario s = FddHover("3");
  const RunSummary whole = RunScenario(s);
  Flight by_period(s);
  while (by_period.StepControlPeriod()) {
  }
  ExpectSameFlight(by_period.Finish(), whole);
  Flight by_step(s);
  while (by_step.Step()) {
  }
  EXPECT_EQ(by_step.steps_taken(), by_step.steps_total());
  ExpectSameFlight(by_step.Finish(), whole);
  EXPECT_THROW(by_step.Finish(), std::logic_error);
}

TEST(Flight, ItRestsAtControlInstantsWithTheCycleRun) {
  const Scenario s = FddHover("2.5");
  Flight flight(s);
  const TimeNs period = flight.stack().control_period_ns();
  EXPECT_EQ(flight.simulator().time_ns(), 0);
  for (int k = 1; k <= 5; ++k) {
    flight.StepControlPeriod();
    EXPECT_EQ(flight.simulator().time_ns(), k * period);
    EXPECT_EQ(flight.stack().command().t_ns, k * period);  // this instant's cycle has run
  }
}

TEST(Flight, ACommandFromOutsideIsWhatTheSimulatorFlies) {
  Flight flight(FddHover("2.5"));
  const int n = flight.simulator().model().num_rotors();
  RotorVector u = RotorVector::Constant(n, 2.0);
  u[1] = 3.5;
  for (int k = 0; k < 10; ++k) {
    flight.StepControlPeriod(&u);
    for (int i = 0; i < n; ++i) EXPECT_EQ(flight.simulator().applied_command()[i], u[i]);
  }
}

TEST(Flight, ACommandOfTheWrongSizeOrNotFiniteIsRefusedAndNothingIsFlown) {
  Flight flight(FddHover("2.5"));
  const RotorVector three = RotorVector::Constant(3, 2.0);
  EXPECT_THROW(flight.StepControlPeriod(&three), std::invalid_argument);
  RotorVector nan = RotorVector::Constant(4, 2.0);
  nan[2] = std::nan("");
  EXPECT_THROW(flight.StepControlPeriod(&nan), std::invalid_argument);
  EXPECT_EQ(flight.steps_taken(), 0);
}

using RunFolderTest = testing::TempFolderTest;

TEST_F(RunFolderTest, PreparingARunFolderRemovesEveryRunFileAnEarlierRunLeftAndNothingElse) {
  // Every file any command writes, hand-listed (so that the list cannot lose one unnoticed).
  const std::vector<std::string> run_files = {"summary.json", "report.html", "flight.mcap",
                                              "log.csv",      "scene.json",  "sensors.csv",
                                              "vehicle.yaml", "truth_vehicle.yaml", "runtime.json"};
  for (const std::string& f : run_files) Write(f, "from an earlier run");
  Write("notes.txt", "the user's");
  PrepareRunFolder(dir_.string());
  for (const std::string& f : run_files) EXPECT_FALSE(std::filesystem::exists(dir_ / f)) << f;
  EXPECT_TRUE(std::filesystem::exists(dir_ / "notes.txt"));
  PrepareRunFolder((dir_ / "new" / "deeper").string());  // created where missing
  EXPECT_TRUE(std::filesystem::is_directory(dir_ / "new" / "deeper"));
}

}  // namespace
}  // namespace rotorguard::harness
