// Software in the loop (harness/sitl.h): the stack on the onboard executor's threads.
//  - On the simulator's clock, where the simulator waits for each cycle's command, the threaded
//    stack flies the lockstep runner's flight to the bit: the executor runs the stack's own tasks,
//    in the lockstep order, with nothing copied or left out. Checked in the realistic world (drawn
//    vehicle, delays, vibration) on a propeller loss with external odometry, with the map built on
//    the perception thread, and in the forest on the LiDAR-inertial odometry and the replanner.
//  - In real time, a propeller loss is isolated and flown out, every command stamped and counted.
#include "rotorguard/harness/sitl.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <ostream>
#include <string>
#include <vector>

#include "rotorguard/harness/runner.h"
#include "rotorguard/io/json_archive.h"
#include "rotorguard/harness/scenario.h"
#include "same_flight.h"
#include "test_util.h"
#include "thread_cpus.h"

namespace rotorguard::harness {
namespace {

using testing::AllowedCpus;

Scenario Load(const std::string& name, std::vector<Override> overrides) {
  return LoadScenario(testing::SourcePath("configs/scenarios/" + name + ".yaml"), overrides);
}

/// A scenario flown short, its failure moved into the flight.
struct ShortFlight {
  const char* name;
  const char* duration_s;
  const char* onset_s;
};

void PrintTo(const ShortFlight& f, std::ostream* os) { *os << f.name << " for " << f.duration_s << " s"; }

class SitlOnTheSimulatorsClock : public ::testing::TestWithParam<ShortFlight> {};

TEST_P(SitlOnTheSimulatorsClock, TheThreadedStackFliesTheLockstepFlightToTheBit) {
  const auto& [name, duration_s, onset_s] = GetParam();
  const Scenario sc = Load(name, {{"truth", "realistic"},
                                  {"seed", "3"},
                                  {"duration_s", duration_s},
                                  {"faults.0.onset.at_time_s", onset_s}});
  const RunSummary lockstep = RunScenario(sc);
  SitlOptions o;
  o.lockstep_clock = true;
  const SitlResult sitl = RunSitl(sc, {}, o);
  ASSERT_TRUE(lockstep.fdd && lockstep.fdd->correct) << "the comparison needs a flight with an isolation";
  testing::ExpectSameFlight(lockstep, sitl.summary);
  EXPECT_EQ(sitl.loops.at("control").at("runs").get<std::uint64_t>(), lockstep.control_cycles);
  EXPECT_EQ(sitl.link.commands, lockstep.control_cycles);
}

// External odometry; the same with the map built on the perception thread; the forest on the
// stack's own LiDAR-inertial odometry with the MINCO replanner on its thread.
INSTANTIATE_TEST_SUITE_P(Flights, SitlOnTheSimulatorsClock,
                         ::testing::Values(ShortFlight{"fdd_hover_propeller_loss", "4", "2"},
                                           ShortFlight{"room_lidar_propeller_loss", "4", "1"},
                                           ShortFlight{"forest", "6", "4"}),
                         [](const ::testing::TestParamInfo<ShortFlight>& p) { return std::string(p.param.name); });

TEST(SitlInRealTime, APropellerLossIsIsolatedAndFlownOutWithEveryCommandStampedAndCounted) {
  // At half real time: the flight's timing has twice its budget on a loaded test machine (the
  // figures at real time are the benchmark's, docs/runtime.md).
  const Scenario sc = Load("fdd_hover_propeller_loss", {{"seed", "5"}, {"duration_s", "4"}});
  SitlOptions o;
  o.realtime_factor = 0.5;
  // The time-critical threads pinned to the first CPU this process may use, the simulator's (this
  // thread) among them for the flight only: it gets its CPUs back after.
  const std::vector<int> cpus = AllowedCpus();
  o.executor.realtime.control_cpu = cpus.front();
  const SitlResult r = RunSitl(sc, {}, o);
  EXPECT_EQ(AllowedCpus(), cpus);
  EXPECT_TRUE(r.loops.at("realtime").at("note").get<std::string>().ends_with(fmt::format("pinned to CPU {}", cpus.front())))
      << r.loops.at("realtime").at("note");
  const RunSummary& s = r.summary;
  EXPECT_TRUE(s.success) << s.failure_reason.value_or("");
  ASSERT_TRUE(s.fdd && s.fdd->diagnosis);
  EXPECT_TRUE(s.fdd->correct);
  EXPECT_EQ(s.fdd->diagnosis->rotor, 0);
  // 4 s at 200 Hz: a cycle per control instant, unless the thread was late (counted as skipped).
  const nlohmann::json& control = r.loops.at("control");
  const auto runs = control.at("runs").get<std::uint64_t>();
  EXPECT_EQ(runs + control.at("skipped").get<std::uint64_t>(), 800u);
  // Every cycle's command arrives, and every command the deadline guard held in a late cycle's place.
  EXPECT_EQ(r.link.commands + r.link.commands_after_end,
            runs + r.loops.at("deadline_policy").at("holds").get<std::uint64_t>());
  // No command is stamped as sent before the IMU sample it was computed from.
  EXPECT_EQ(r.link.commands_before_their_sample, 0u);
  EXPECT_GT(control.at("cpu_s").get<double>(), 0.0);
}

/// The node sends the stack's summary as JSON (io/json_archive.h); every field comes back as it
/// was, maps, optional blocks and enum names included.
TEST(SitlNode, TheStacksSummaryCrossesAsJsonWhole) {
  stack::FlightStackSummary a;
  stack::NavigationSummary n;
  n.waypoints_reached = 3;
  n.plans_by_reason = {{"goal", 2}, {"obstacle ahead", 5}};
  n.failed_plans = {"12.30 s periodic: no_path"};
  n.unreachable = "waypoint 4";
  a.navigation = n;
  a.ukf = stack::UkfSummary{{0.1, 0.0, 0.85, 0.0}, 3.25};
  a.final_mode = stack::FlightMode::kEmergencyLanding;
  a.transitions = {{1.5, stack::FlightMode::kNominal, stack::FlightMode::kFailureRecovery, "rotor failure isolated"}};
  a.map_voxels_occupied = 18579;
  stack::LioSummary o;
  o.frames = 180;
  o.lidar_rotation_rad = {0.001, -0.002, 0.003};
  a.odometry = o;
  a.reconfigurations = {{2, 16.055}};
  planning::FlatnessDecision d;
  d.kind = "return";
  d.w_hat = {0.0, 0.5, 0.0, 0.0};
  a.flatness_decisions = {d};
  const nlohmann::json j = io::ToJson(a);
  stack::FlightStackSummary b;
  io::FromJson(j, &b);
  EXPECT_EQ(io::ToJson(b), j);
  ASSERT_TRUE(b.navigation && b.ukf && b.odometry && b.map_voxels_occupied);
  EXPECT_EQ(b.navigation->plans_by_reason, n.plans_by_reason);
  EXPECT_EQ(b.navigation->unreachable, "waypoint 4");
  EXPECT_EQ(b.ukf->settled_s, 3.25);
  EXPECT_EQ(b.final_mode, stack::FlightMode::kEmergencyLanding);
  EXPECT_EQ(b.transitions.at(0).to, stack::FlightMode::kFailureRecovery);
  EXPECT_EQ(b.odometry->lidar_rotation_rad, o.lidar_rotation_rad);
  EXPECT_EQ(b.reconfigurations.at(0).t_s, 16.055);
  EXPECT_EQ(b.flatness_decisions.at(0).w_hat, d.w_hat);
  // Absent blocks stay absent.
  stack::FlightStackSummary empty, back;
  back.navigation = n;
  io::FromJson(io::ToJson(empty), &back);
  EXPECT_FALSE(back.navigation.has_value());
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
