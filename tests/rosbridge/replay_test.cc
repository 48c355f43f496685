// Replay against the flights that recorded the bags: a lockstep run's and a real-time software
// in the loop's (threads, queues and all) are replayed to the same estimates and FDD diagnosis;
// a stack that differs from the recorded one is caught; a bag without cycles is replayed on the
// control grid.
#include "rotorguard/rosbridge/replay.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/sitl.h"
#include "rotorguard/io/csv.h"
#include "rotorguard/io/json_file.h"
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
  ASSERT_TRUE(s.fdd && s.fdd->diagnosis) << "the flight diagnosed nothing: " << s.ToJson().dump();
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
  const fs::path dir = fs::temp_directory_path() / "rotorguard-replay-run";
  const ReplaySummary r = Replay(sc, bag, {.out_dir = dir.string()});
  EXPECT_EQ(r.recorded_cycles.size(), s.control_cycles);
  EXPECT_EQ(r.compared, s.control_cycles);
  EXPECT_LT(r.position_max_diff_m, 1e-6);  // the frames as the flight's odometry saw them (see below)
  EXPECT_LT(r.attitude_max_diff_rad, 1e-6);
  EXPECT_EQ(r.diagnosis, r.recorded_diagnosis) << r.diagnosis.ToString() << " vs " << r.recorded_diagnosis.ToString();
  ExpectDiagnosedAsTheFlight(r, s);

  // The run folder: what `run` writes, without the truth. summary.json's truth fields are null,
  // its FDD diagnosis is the flight's; log.csv's rows are the replay's cycles at the log's rate.
  const nlohmann::json j = io::ReadJsonObject((dir / "summary.json").string());
  for (const char* key : {"success", "crashed", "truth", "tracking_rmse_m", "faults", "estimate_position_rmse_m"}) {
    EXPECT_TRUE(j.at(key).is_null()) << key;
  }
  EXPECT_EQ(j.at("fdd").at("rotor").get<int>(), s.fdd->diagnosis->rotor);
  EXPECT_EQ(j.at("fdd").at("kind").get<std::string>(), s.fdd->diagnosis->kind);
  EXPECT_FALSE(j.at("fdd").contains("false_alarm")) << "scoring needs the injected faults";
  EXPECT_EQ(j.at("replay").at("compared").get<std::uint64_t>(), r.compared);
  EXPECT_EQ(j.at("supervisor"), s.ToJson().at("supervisor")) << "the stack's account is the flight's";
  const io::NumericTable log = io::ReadNumericCsv((dir / "log.csv").string());
  EXPECT_FALSE(log.Has("p_x") || log.Has("thrust_0") || log.Has("fault_0")) << "no truth columns";
  ASSERT_TRUE(log.Has("est_p_x") && log.Has("mi_0") && log.Has("cmd_3"));
  EXPECT_NEAR(static_cast<double>(log.rows()), sc.log_rate_hz * sc.duration_s, 2.0);
  const std::size_t last = log.rows() - 1;
  const runtime::CycleTelemetry* at_last = nullptr;
  for (const runtime::CycleTelemetry& c : r.cycles) {
    if (std::abs(ToSeconds(c.command.state_t_ns) - log.Column("t")[last]) < 1e-9) at_last = &c;
  }
  ASSERT_NE(at_last, nullptr) << "a row is a cycle's";
  EXPECT_NEAR(log.Column("est_p_z")[last], at_last->estimate.p_W.z(), 1e-8);
  EXPECT_NEAR(log.Column("cmd_1")[last], at_last->command.thrust_n[1], 1e-8);
  for (const char* file : {"scene.json", "sensors.csv", "vehicle.yaml"}) EXPECT_TRUE(fs::exists(dir / file)) << file;
  fs::remove_all(dir);

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
  // The bag's point times are float32 seconds (FAST-LIO2's layout) and the simulated sensor
  // stamps its returns at that resolution: the replay's odometry sees the very frames the flight's
  // did, so only the order of floating-point sums may differ.
  EXPECT_LT(r.position_max_diff_m, 1e-6) << "first divergence at " << r.first_divergence_s.value_or(-1.0) << " s; "
                                         << result.RuntimeJson().dump();
  EXPECT_LT(r.velocity_max_diff_m_s, 1e-6);
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
