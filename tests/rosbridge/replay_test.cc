// Replay against the flights that recorded the bags: a lockstep run's and a real-time software
// in the loop's (threads, queues and all) are replayed to the same estimates and FDD diagnosis;
// a stack that differs from the recorded one is caught; a bag without cycles is replayed on the
// control grid.
#include "rotorguard/rosbridge/replay.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/sitl.h"
#include "rotorguard/rosbridge/bag_recorder.h"
#include "test_util.h"

namespace rotorguard::rosbridge {
namespace {

namespace fs = std::filesystem;
using harness::Override;
using harness::Scenario;

Scenario Load(const std::string& name, std::vector<Override> overrides = {}) {
  return harness::LoadScenario(testing::SourcePath("configs/scenarios/" + name + ".yaml"), overrides);
}

std::string TempBag(const char* name) { return (fs::temp_directory_path() / (std::string("rotorguard-replay-") + name + ".bag")).string(); }

/// The recorded flight's diagnosis of rotor 0 as its summary gives it.
void ExpectDiagnosedAsTheFlight(const ReplaySummary& r, const harness::RunSummary& s) {
  ASSERT_TRUE(s.fdd && s.fdd->diagnosis);
  const int rotor = s.fdd->diagnosis->rotor;
  ASSERT_LT(rotor, static_cast<int>(r.diagnosis.health.size()));
  EXPECT_EQ(r.diagnosis.health[static_cast<std::size_t>(rotor)], s.fdd->diagnosis->kind);
  ASSERT_TRUE(r.diagnosis.first_not_ok_s[static_cast<std::size_t>(rotor)]);
  EXPECT_NEAR(*r.diagnosis.first_not_ok_s[static_cast<std::size_t>(rotor)], s.fdd->diagnosis->detection_s, 0.0051)
      << "the first cycle that saw it";
}

TEST(Replay, ALockstepRunIsReplayedToItsEstimatesAndDiagnosis) {
  const Scenario sc = Load("room_lidar_propeller_loss", {{"truth", "realistic"}, {"seed", "7"}});
  const std::string bag = TempBag("run");
  harness::RunSummary s;
  {
    BagRecorder recorder(bag);
    harness::RunOptions o;
    o.observer = &recorder;
    s = harness::RunScenario(sc, o);
  }
  ASSERT_TRUE(fs::exists(bag)) << "Finish names the bag";
  const ReplaySummary r = Replay(sc, bag);
  EXPECT_EQ(r.recorded_cycles.size(), s.control_cycles);
  EXPECT_EQ(r.compared, s.control_cycles);
  EXPECT_LT(r.position_max_diff_m, 1e-6);  // float32 point times: the LiDAR-inertial odometry sees them within 8 ns
  EXPECT_LT(r.attitude_max_diff_rad, 1e-6);
  EXPECT_EQ(r.diagnosis, r.recorded_diagnosis) << r.diagnosis.ToString() << " vs " << r.recorded_diagnosis.ToString();
  ExpectDiagnosedAsTheFlight(r, s);

  // The same bag through a stack tuned otherwise: the comparison sees it.
  const ReplaySummary other = Replay(Load("room_lidar_propeller_loss", {{"truth", "realistic"}, {"seed", "7"}, {"stack.fdd", "none"}}), bag);
  EXPECT_FALSE(other.diagnosis == other.recorded_diagnosis);
  fs::remove(bag);
}

TEST(Replay, ARealTimeFlightOnThreadsIsReplayedExactly) {
  // Real time, the stack on the executor's threads: its cycles ran on whatever messages and
  // odometry updates had reached them; the replay runs each on exactly those.
  const Scenario sc = Load("forest", {{"duration_s", "18"}});
  const std::string bag = TempBag("sitl");
  harness::SitlResult result;
  {
    BagRecorder recorder(bag);
    harness::RunOptions o;
    o.observer = &recorder;
    result = harness::RunSitl(sc, o, {});
  }
  const ReplaySummary r = Replay(sc, bag);
  EXPECT_GT(r.inputs.at("points"), 150u) << "the LiDAR-inertial odometry had frames to fuse";
  EXPECT_EQ(r.compared + r.recorded_held, r.recorded_cycles.size()) << "every cycle of its own compared";
  EXPECT_EQ(r.compared, result.summary.control_cycles);
  EXPECT_LT(r.position_max_diff_m, 1e-6) << "first divergence at " << r.first_divergence_s.value_or(-1.0) << " s; "
                                         << result.RuntimeJson().dump();
  EXPECT_LT(r.velocity_max_diff_m_s, 1e-5);
  EXPECT_EQ(r.diagnosis, r.recorded_diagnosis) << r.diagnosis.ToString() << " vs " << r.recorded_diagnosis.ToString();
  ExpectDiagnosedAsTheFlight(r, result.summary);
  fs::remove(bag);
}

TEST(Replay, ABagWithoutCyclesIsReplayedOnTheControlGrid) {
  const Scenario sc = Load("fdd_hover_propeller_loss");
  const std::string bag = TempBag("sensors");
  {
    // The sensors alone, as `rosbag record` of a vehicle's drivers would have them.
    class SensorsOnly final : public harness::StackObserver {
     public:
      explicit SensorsOnly(const std::string& path) : bag_(path) {}
      void OnSensors(TimeNs t, const sim::SensorOutputs& o) override { bag_.OnSensors(t, o); }
      void OnCycle(const runtime::CycleTelemetry&) override {}
      void Finish() override { bag_.Finish(); }

     private:
      BagRecorder bag_;
    } recorder(bag);
    harness::RunOptions o;
    o.observer = &recorder;
    harness::RunScenario(sc, o);
  }
  const ReplaySummary r = Replay(sc, bag);
  EXPECT_TRUE(r.recorded_cycles.empty());
  EXPECT_EQ(r.compared, 0u);
  const double rate = sc.stack.control_rate_hz;
  EXPECT_NEAR(static_cast<double>(r.cycles.size()), rate * sc.duration_s, 2.0);
  // The propeller lost at its onset is found from the sensors alone.
  ASSERT_FALSE(r.diagnosis.health.empty());
  EXPECT_EQ(r.diagnosis.health[0], "propeller_failed");
  fs::remove(bag);
}

TEST(Replay, ABagWithoutImuSamplesIsRefusedNamingIt) {
  const std::string bag = TempBag("empty");
  { BagRecorder(bag).Finish(); }
  try {
    Replay(Load("hover"), bag);
    FAIL() << "replayed a bag without IMU samples";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bag), std::string::npos) << e.what();
  }
  fs::remove(bag);
}

}  // namespace
}  // namespace rotorguard::rosbridge
