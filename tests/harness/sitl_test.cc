// Software in the loop (harness/sitl.h): the stack on the onboard executor's threads.
//  - On the simulator's clock, where the simulator waits for each cycle's command, the threaded
//    stack flies the lockstep runner's flight to the bit: the executor runs the stack's own tasks,
//    in the lockstep order, with nothing copied or left out. Checked in the realistic world (drawn
//    vehicle, delays, vibration) on a propeller loss with external odometry, and on one with the
//    LiDAR-inertial odometry registering frames on its own thread.
//  - In real time, a propeller loss is isolated and flown out, every command stamped and counted.
#include "rotorguard/harness/sitl.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "same_flight.h"
#include "test_util.h"

namespace rotorguard::harness {
namespace {

Scenario Load(const std::string& name, std::vector<Override> overrides) {
  return LoadScenario(testing::SourcePath("configs/scenarios/" + name + ".yaml"), overrides);
}

class SitlOnTheSimulatorsClock : public ::testing::TestWithParam<const char*> {};

TEST_P(SitlOnTheSimulatorsClock, TheThreadedStackFliesTheLockstepFlightToTheBit) {
  const Scenario sc = Load(GetParam(), {{"truth", "realistic"}, {"seed", "3"}, {"duration_s", "4"}});
  const RunSummary lockstep = RunScenario(sc);
  SitlOptions o;
  o.lockstep_clock = true;
  const SitlResult sitl = RunSitl(sc, {}, o);
  ASSERT_TRUE(lockstep.fdd && lockstep.fdd->correct) << "the comparison needs a flight with an isolation";
  testing::ExpectSameFlight(lockstep, sitl.summary);
  EXPECT_EQ(sitl.runtime.control.runs, lockstep.control_cycles);
  EXPECT_EQ(sitl.link.commands, lockstep.control_cycles);
}

INSTANTIATE_TEST_SUITE_P(Flights, SitlOnTheSimulatorsClock,
                         ::testing::Values("fdd_hover_propeller_loss", "room_lidar_propeller_loss"));

TEST(SitlInRealTime, APropellerLossIsIsolatedAndFlownOutWithEveryCommandStampedAndCounted) {
  // At half real time: the flight's timing has twice its budget on a loaded test machine (the
  // figures at real time are the benchmark's, docs/runtime.md).
  const Scenario sc = Load("fdd_hover_propeller_loss", {{"seed", "5"}, {"duration_s", "4"}});
  SitlOptions o;
  o.realtime_factor = 0.5;
  const SitlResult r = RunSitl(sc, {}, o);
  const RunSummary& s = r.summary;
  EXPECT_TRUE(s.success) << s.failure_reason.value_or("");
  ASSERT_TRUE(s.fdd && s.fdd->diagnosis);
  EXPECT_TRUE(s.fdd->correct);
  EXPECT_EQ(s.fdd->diagnosis->rotor, 0);
  // 4 s at 200 Hz: a cycle per control instant, unless the thread was late (counted as skipped).
  EXPECT_EQ(r.runtime.control.runs + r.runtime.control.skipped, 800u);
  EXPECT_EQ(r.link.commands + r.link.commands_after_end, r.runtime.control.runs);
  // A command never acts before the IMU sample it was computed from.
  EXPECT_GE(r.link.command_delay.min_s(), 0.0);
  EXPECT_GT(r.runtime.control.cpu_s, 0.0);
}

TEST(SitlOptions, AFactorOutsideItsRangeIsRefusedNamingTheField) {
  SitlOptions o;
  o.realtime_factor = 0.0;
  try {
    o.Validate();
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("realtime_factor"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rotorguard::harness
