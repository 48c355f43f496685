// The sensor log (write, read back, reject corruption) and the offline FDD calibration, checked
// against the live runs that recorded the logs.

#include "rotorguard/benchmarks/fdd_calibration.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>

#include "rotorguard/campaign_kinds/scenario_sweep.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/core/error.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/record/sensor_log.h"
#include "test_util.h"
#include "vehicle_fixture.h"

namespace rotorguard::benchmarks {
namespace {

namespace fs = std::filesystem;

std::string Config(const std::string& name) {
  return testing::SourcePath("configs/scenarios/" + name);
}

class TempFolder : public rotorguard::testing::TempFolderTest {
 protected:
  /// The reason of the InputFileError that reading `text` as a sensor log gives ("" if none).
  std::string ReadError(const std::string& text) {
    try {
      record::ReadSensorLog(Write("sensors.csv", text), 4);
    } catch (const io::InputFileError& e) {
      return e.reason();
    }
    return "";
  }
};

using SensorLog = TempFolder;

TEST_F(SensorLog, RoundTripsEveryMessageExactly) {
  std::string text(record::kSensorLogHeader);
  ImuSample imu{123, Vector3(0.1, -0.2, 9.81), Vector3(1.0 / 3.0, 2e-7, -5.5)};
  EscTelemetry esc{124, RotorVector(4)};
  esc.motor_speed_rad_s << 1480.123456789, 0.0, 1e3 / 7.0, 2000.0;
  OdometrySample odom{125, Vector3(1, 2, 3), Quaternion(0.9, 0.1, -0.3, 0.2).normalized(), Vector3(-1, 0.5, 0)};
  RotorCommand cmd{126, RotorVector(4)};
  cmd.thrust_n << 2.8, 0.0, 11.5, std::nextafter(3.0, 4.0);
  record::AppendImu(imu, &text);
  record::AppendEsc(esc, &text);
  record::AppendOdometry(odom, &text);
  record::AppendCommand(cmd, &text);
  const std::vector<record::SensorRecord> r = record::ReadSensorLog(Write("sensors.csv", text), 4);
  ASSERT_EQ(r.size(), 4u);
  EXPECT_EQ(std::get<ImuSample>(r[0]).t_ns, 123);
  EXPECT_EQ(std::get<ImuSample>(r[0]).specific_force_B, imu.specific_force_B);
  EXPECT_EQ(std::get<ImuSample>(r[0]).w_B, imu.w_B);
  EXPECT_EQ(std::get<EscTelemetry>(r[1]).motor_speed_rad_s, esc.motor_speed_rad_s);
  EXPECT_EQ(std::get<OdometrySample>(r[2]).p_W, odom.p_W);
  EXPECT_EQ(std::get<OdometrySample>(r[2]).q_WB.coeffs(), odom.q_WB.coeffs());
  EXPECT_EQ(std::get<OdometrySample>(r[2]).v_W, odom.v_W);
  EXPECT_EQ(std::get<RotorCommand>(r[3]).t_ns, 126);
  EXPECT_EQ(std::get<RotorCommand>(r[3]).thrust_n, cmd.thrust_n);
}

TEST_F(SensorLog, RejectsCorruptionNamingTheLineAndByte) {
  const std::string header(record::kSensorLogHeader);
  const std::string imu = "imu,0,0,0,9.8,0,0,0\n";
  // The byte offset is where the bad line starts.
  EXPECT_EQ(ReadError(header + imu + "imu,1,0,0,9.8,0,0"),
            fmt::format("line 3 (byte {}): truncated: the last line has no end of line", header.size() + imu.size()));
  EXPECT_EQ(ReadError(header + imu + "imu,1,0,0,9.8,0,0\n"),
            fmt::format("line 3 (byte {}): imu has 5 values; expected 6", header.size() + imu.size()));
  EXPECT_EQ(ReadError(header + "gps,0,1\n"),
            fmt::format("line 2 (byte {}): unknown message type 'gps'; expected imu, esc, odom or cmd", header.size()));
  EXPECT_EQ(ReadError(header + "esc,0,1,2,1.5x,4\n"),
            fmt::format("line 2 (byte {}): value 3 is not a number", header.size()));
  EXPECT_EQ(ReadError(header + "esc,0,1,2,nan,inf\n"), "") << "non-finite values are kept for the replay";
  EXPECT_EQ(ReadError(header + "esc,x,1,2,3,4\n"), fmt::format("line 2 (byte {}): t_ns is not an integer", header.size()));
  EXPECT_EQ(ReadError(header + "imu,5,0,0,9.8,0,0,0\n" + imu),
            fmt::format("line 3 (byte {}): imu time stamp 0 ns is before the previous one (5 ns)",
                        header.size() + imu.size()));
  EXPECT_NE(ReadError("t,p_x\n" + imu).find("line 1 (byte 0): expected the header"), std::string::npos);
  EXPECT_NE(ReadError("").find("empty file"), std::string::npos);
}

TEST_F(TempFolder, VehicleYamlRoundTripsThroughTheLoader) {
  vehicle::VehicleParams v = rotorguard::testing::ReferenceQuad();
  // Collision spheres as an assembly has them (one per unit), within the bounding radius.
  v.collision_spheres = {{Vector3(0.08, -0.04, 0.0), 0.1}, {Vector3(-0.1, 0.05, 0.0), 0.1 / 3.0}};
  const vehicle::VehicleParams back = harness::LoadVehicle(Write("vehicle.yaml", harness::VehicleToYaml(v)));
  EXPECT_EQ(back.name, v.name);
  EXPECT_EQ(back.mass_kg, v.mass_kg);
  EXPECT_EQ(back.inertia_kg_m2, v.inertia_kg_m2);
  EXPECT_EQ(back.rotor_drag_kg_s, v.rotor_drag_kg_s);
  EXPECT_EQ(back.yaw_damping_n_m_s, v.yaw_damping_n_m_s);
  EXPECT_NEAR(back.thrust_coefficient_n_s2, v.thrust_coefficient_n_s2, 1e-15 * v.thrust_coefficient_n_s2);
  EXPECT_EQ(back.motor_time_constant_s, v.motor_time_constant_s);
  EXPECT_EQ(back.motor_stop_time_constant_s, v.motor_stop_time_constant_s);
  EXPECT_EQ(back.unloaded_speed_ratio, v.unloaded_speed_ratio);
  EXPECT_EQ(back.collision_radius_m, v.collision_radius_m);
  ASSERT_EQ(back.collision_spheres.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back.collision_spheres[i].centre_B, v.collision_spheres[i].centre_B);
    EXPECT_EQ(back.collision_spheres[i].radius_m, v.collision_spheres[i].radius_m);
  }
  ASSERT_EQ(back.rotors.size(), v.rotors.size());
  for (std::size_t i = 0; i < v.rotors.size(); ++i) {
    EXPECT_EQ(back.rotors[i].p_B, v.rotors[i].p_B);
    EXPECT_EQ(back.rotors[i].direction, v.rotors[i].direction);
    EXPECT_EQ(back.rotors[i].max_thrust_n, v.rotors[i].max_thrust_n);
    EXPECT_EQ(back.rotors[i].yaw_coefficient_m, v.rotors[i].yaw_coefficient_m);
  }
}

using FddReplay = TempFolder;

// The replay is the detector of the live run: the same diagnosis, to the sample, for a motor
// failure, a propeller loss in hover and one during take-off, and no diagnosis for a fault-free
// flight.
TEST_F(FddReplay, FindsTheLiveRunsDiagnosisExactly) {
  const std::vector<std::pair<std::string, std::vector<harness::Override>>> runs = {
      {"fdd_hover_motor_stop.yaml", {{"faults.0.rotor", "2"}}},
      {"fdd_hover_propeller_loss.yaml", {{"faults.0.rotor", "1"}}},
      {"fdd_takeoff_propeller_loss.yaml", {{"faults.0.rotor", "3"}}},
      {"lemniscate_2ms.yaml", {{"stack.controller", "nmpc"}, {"stack.fdd", "composite"}, {"duration_s", "8"}}},
  };
  for (const auto& [file, overrides] : runs) {
    const harness::Scenario s = harness::LoadScenario(Config(file), overrides);
    const fs::path out = dir_ / s.name;
    harness::RunOptions o;
    o.out_dir = out.string();
    const harness::RunSummary live = harness::RunScenario(s, o);
    ASSERT_TRUE(live.fdd.has_value()) << file;
    const CalibrationLog log = LoadCalibrationLog(out.string());
    ASSERT_EQ(log.faults.size(), s.faults.size());
    ASSERT_TRUE(log.recorded_fdd.has_value());
    const ReplayOutcome replay = ReplayCompositeFdd(log, *log.recorded_fdd);
    const harness::FddRecord scored = harness::ScoreFdd(replay.statuses, FaultEvents(log));
    ASSERT_EQ(scored.detected(), live.fdd->detected()) << file;
    if (scored.detected()) {
      EXPECT_EQ(scored.diagnosis->rotor, live.fdd->diagnosis->rotor) << file;
      EXPECT_EQ(scored.diagnosis->kind, live.fdd->diagnosis->kind) << file;
      EXPECT_EQ(scored.diagnosis->detector, live.fdd->diagnosis->detector) << file;
      EXPECT_EQ(scored.diagnosis->detection_s, live.fdd->diagnosis->detection_s) << file;
    }
    EXPECT_EQ(scored.correct, live.fdd->correct) << file;
    EXPECT_EQ(scored.false_alarm, live.fdd->false_alarm) << file;
  }
}

// Records are in delivery order: a delayed sample stamped before the onset may come after samples
// of the failed motor. The fault-free extremes end at the first record stamped at the onset, as if
// the log had been cut there, whatever comes later.
TEST_F(FddReplay, FaultFreeExtremesEndAtTheFirstRecordOfTheOnset) {
  const harness::Scenario s = harness::LoadScenario(Config("fdd_hover_motor_stop.yaml"));
  harness::RunOptions o;
  o.out_dir = (dir_ / s.name).string();
  harness::RunScenario(s, o);
  CalibrationLog log = LoadCalibrationLog(o.out_dir);
  ASSERT_EQ(log.faults.size(), 1u);
  const double onset = log.faults.front().onset_s;
  const auto stamp = [](const record::SensorRecord& r) { return ToSeconds(record::RecordTime(r)); };
  // Deliver the last IMU sample before the onset late: after the telemetry 20 ms into the stop.
  std::vector<record::SensorRecord>& records = log.records;
  std::size_t late = 0, after = 0;
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (std::holds_alternative<ImuSample>(records[i]) && stamp(records[i]) < onset) late = i;
    if (!after && std::holds_alternative<EscTelemetry>(records[i]) && stamp(records[i]) >= onset + 0.02) after = i;
  }
  ASSERT_LT(late, after);
  const record::SensorRecord moved = records[late];
  records.erase(records.begin() + static_cast<std::ptrdiff_t>(late));
  records.insert(records.begin() + static_cast<std::ptrdiff_t>(after), moved);
  // Nothing fires: the replay runs through the whole log.
  const fdd::CompositeFddOptions disarmed = fdd::CompositeFddOptions{}.Disarmed();
  const fdd::IndexExtremes whole = ReplayCompositeFdd(log, disarmed).extremes;
  CalibrationLog cut = log;
  const auto first_at_onset =
      std::find_if(cut.records.begin(), cut.records.end(), [&](const auto& r) { return stamp(r) >= onset; });
  cut.records.erase(first_at_onset, cut.records.end());
  const fdd::IndexExtremes before = ReplayCompositeFdd(cut, disarmed).extremes;
  for (const auto& [name, member] : fdd::kIndexExtremesFields) EXPECT_EQ(whole.*member, before.*member) << name;
  EXPECT_GT(whole.debounced_motor_index, 0.5) << "the stopped motor's samples stay out";
}

// The sweep on two fault-free flights (a take-off among them) and two faulty ones: the configured
// thresholds detect both faults without a false alarm. Each rule's statistic is the boundary of its
// alarms, so a row false-alarms exactly when its value is not beyond the fault-free extreme
// (margin below 1). The suggestion keeps the margin, detects both faults, and is no slower than the
// configured value; what the margin costs is its latency over the fastest row without an alarm.
TEST_F(FddReplay, CalibrationTableAndSuggestionAreConsistent) {
  std::vector<CalibrationLog> logs;
  const std::vector<std::pair<std::string, std::vector<harness::Override>>> runs = {
      {"lemniscate_2ms.yaml", {{"duration_s", "12"}}},
      {"takeoff.yaml", {{"stack.controller", "nmpc"}, {"stack.fdd", "composite"}}},
      {"fdd_hover_motor_stop.yaml", {}},
      {"fdd_hover_propeller_loss.yaml", {}},
  };
  for (const auto& [file, overrides] : runs) {
    // The realistic world: its sensors' delays deliver some samples out of time order, which the
    // fault-free extremes must not let past the onset.
    const harness::Scenario s = harness::LoadScenario(Config(file), overrides);
    harness::RunOptions o;
    o.out_dir = (dir_ / s.name).string();
    harness::RunScenario(s, o);
    logs.push_back(LoadCalibrationLog(o.out_dir));
  }
  FddCalibrationOptions options;
  const nlohmann::json c = CalibrateCompositeFdd(logs, {}, options);
  for (const auto& l : c["logs"]) {
    EXPECT_FALSE(l["with_configured_thresholds"]["false_alarm"].get<bool>()) << l["dir"];
    EXPECT_EQ(l["with_configured_thresholds"]["correct"].get<bool>(), l["faulty"].get<bool>()) << l["dir"];
  }
  // The healthy index stays far above γ_M = 0.2; it dips below 1 where the commands change fast and
  // the motors answer after a delay the stack knows only roughly (measured 0.79 in the realistic
  // world's take-off).
  const double debounced = c["fault_free_extremes"]["debounced_motor_index"].get<double>();
  EXPECT_GT(debounced, 0.6);
  EXPECT_LT(debounced, 1.0);
  EXPECT_GE(debounced, c["fault_free_extremes"]["min_motor_index"].get<double>());
  int rows_alarming = 0;
  for (const auto& sw : c["sweeps"]) {
    ASSERT_TRUE(sw["exercised"].get<bool>()) << sw["threshold"];
    for (const auto& r : sw["rows"]) {
      if (!r["margin"].is_number()) {  // unbounded: the rule's statistic never moved
        EXPECT_EQ(r["false_alarms"].get<int>(), 0) << sw["threshold"] << " " << r["value"];
        continue;
      }
      const double margin = r["margin"].get<double>();
      if (std::abs(margin - 1.0) < 1e-9) continue;
      EXPECT_EQ(r["false_alarms"].get<int>() > 0, margin < 1.0) << sw["threshold"] << " " << r["value"];
      rows_alarming += margin < 1.0 ? 1 : 0;
    }
    ASSERT_FALSE(sw["fastest_without_alarm"].is_null());
    if (!sw["rows"][0]["margin"].is_number()) {
      // The rule's gates held throughout (the take-off detector's, in these flights): its margin is
      // unbounded, and bounds no suggestion.
      EXPECT_TRUE(sw["suggested"].is_null()) << sw["threshold"];
      EXPECT_NE(sw["note"].get<std::string>().find("gates held"), std::string::npos) << sw["note"];
      continue;
    }
    ASSERT_FALSE(sw["suggested"].is_null()) << sw["threshold"] << ": " << sw["note"];
    EXPECT_GE(sw["suggested"]["margin"].get<double>(), options.margin);
    EXPECT_LE(sw["fastest_without_alarm"]["latency_s_mean"].get<double>(),
              sw["suggested"]["latency_s_mean"].get<double>());
    // At the suggested value the replays detect both faults, with no false alarm.
    fdd::CompositeFddOptions at = options.fdd;
    const double suggested = sw["suggested"]["value"].get<double>();
    if (sw["threshold"] == "motor_index_threshold") at.motor_index_threshold = suggested;
    if (sw["threshold"] == "propeller_index_threshold") at.propeller_index_threshold = suggested;
    if (sw["threshold"] == "takeoff_index_threshold") at.takeoff_index_threshold = suggested;
    for (const CalibrationLog& log : logs) {
      const ReplayOutcome r = ReplayCompositeFdd(log, at);
      EXPECT_EQ(r.isolated_rotor.has_value(), !log.faults.empty()) << sw["threshold"] << " " << log.dir;
      if (r.isolated_rotor) {
        EXPECT_EQ(*r.isolated_rotor, log.faults.front().rotor);
      }
    }
    const double configured = sw["configured"].get<double>();
    for (const auto& r : sw["rows"]) {
      if (r["value"].get<double>() == configured && r["margin"].is_number() &&
          r["margin"].get<double>() >= options.margin && r["latency_s_mean"].is_number()) {
        EXPECT_LE(sw["suggested"]["latency_s_mean"].get<double>(), r["latency_s_mean"].get<double>() + 1e-12);
      }
    }
  }
  EXPECT_GT(rows_alarming, 0) << "the sweeps reach past the fault-free extremes";
  const std::string md = CalibrationMarkdown(c);
  EXPECT_NE(md.find("Suggested: motor_index_threshold ="), std::string::npos);
  EXPECT_NE(md.find("the margin costs"), std::string::npos);
}

// Campaign flights count by hand: a flight false-alarms at a value when its rule's statistic passes
// the value (one that alarmed as flown is counted as such); the margin is to the most alarming flight.
TEST(FddCalibration, CampaignFlightsCountAsTheirStatisticsSay) {
  const auto flight = [](double persistent_p, double debounced_m, bool alarmed) {
    FlightExtremes f;
    f.extremes.max_propeller_index = persistent_p + 0.2;
    f.extremes.persistent_propeller_index = persistent_p;
    f.extremes.min_motor_index = debounced_m - 0.1;
    f.extremes.debounced_motor_index = debounced_m;
    f.false_alarm = alarmed;
    return f;
  };
  CampaignFlights flights;
  flights.dir = "hand";
  flights.flights = {flight(0.5, 0.9, false), flight(0.7, 0.6, false), flight(0.1, 0.95, true)};
  const nlohmann::json c = CalibrateCompositeFdd({}, {flights}, FddCalibrationOptions{});
  ASSERT_EQ(c["campaigns"].size(), 1u);
  EXPECT_EQ(c["campaigns"][0]["flights"].get<int>(), 3);
  EXPECT_EQ(c["campaigns"][0]["false_alarms"].get<int>(), 1);
  EXPECT_DOUBLE_EQ(c["fault_free_extremes"]["persistent_propeller_index"].get<double>(), 0.7);
  EXPECT_DOUBLE_EQ(c["fault_free_extremes"]["debounced_motor_index"].get<double>(), 0.6);
  EXPECT_TRUE(c["fault_free_extremes"]["gated_takeoff_index"].is_null());  // no flight took off
  const std::map<std::string, std::map<double, std::pair<int, double>>> expected = {
      // value -> (false alarms, margin)
      {"propeller_index_threshold", {{0.4, {2, 0.4 / 0.7}}, {0.6, {1, 0.6 / 0.7}}, {0.7, {0, 1.0}}}},
      {"motor_index_threshold", {{0.5, {0, 0.6 / 0.5}}, {0.6, {1, 1.0}}, {0.9, {2, 0.6 / 0.9}}}},
  };
  for (const auto& sw : c["sweeps"]) {
    const std::string name = sw["threshold"];
    EXPECT_TRUE(sw["suggested"].is_null()) << name << ": no faulty log, no latency";
    if (!expected.count(name)) {
      EXPECT_FALSE(sw["exercised"].get<bool>()) << name;
      continue;
    }
    int checked = 0;
    for (const auto& r : sw["rows"]) {
      const auto it = expected.at(name).find(r["value"].get<double>());
      if (it == expected.at(name).end()) continue;
      EXPECT_EQ(r["false_alarms"].get<int>(), it->second.first) << name << " " << r["value"];
      EXPECT_NEAR(r["margin"].get<double>(), it->second.second, 1e-12) << name << " " << r["value"];
      ++checked;
    }
    EXPECT_EQ(checked, 3) << name;
  }
  EXPECT_NE(CalibrationMarkdown(c).find("3 flights of hand (false alarms as flown: 1)"), std::string::npos);
}

using CampaignInput = TempFolder;

// A scenario campaign's records load as flights, each with the statistics its summary gave; a
// campaign that does not record them is refused, naming the missing metric.
TEST_F(CampaignInput, LoadsAScenarioCampaignsFlightsAndRefusesOneWithoutTheMetrics) {
  std::string metrics = "fdd.false_alarm";
  for (const auto& [name, member] : fdd::kIndexExtremesFields) metrics += ", fdd.healthy_extremes." + std::string(name);
  const auto spec = [&](const std::string& name, const std::string& list) {
    return Write(name + ".yaml", "name: " + name + "\nscenario: " + Config("takeoff.yaml") +
                                     "\nseed: 3\nrepeats: 2\ngrid:\n  duration_s: [3.0]\n  stack.controller: [nmpc]\n"
                                     "  stack.fdd: [composite]\nmetrics: [" +
                                     list + "]\n");
  };
  const auto run = [&](const std::string& file) {
    campaign::CampaignRunOptions o;
    o.out_dir = (dir_ / fs::path(file).stem()).string();
    o.version = "test";
    campaign::RunCampaign(ScenarioCampaign(LoadCampaignSpec(file)), o);
    return o.out_dir;
  };
  const CampaignFlights f = LoadCampaignFlights(run(spec("healthy", metrics)));
  ASSERT_EQ(f.flights.size(), 2u);
  // The seeds it used, from the campaign's own stream: an evaluation set can be shown disjoint.
  EXPECT_EQ(f.campaign, "healthy");
  EXPECT_EQ(f.seed, 3u);
  EXPECT_EQ(f.trial_seeds, (std::vector<std::uint64_t>{TrialSeed(3, "campaign healthy", 0),
                                                       TrialSeed(3, "campaign healthy", 1)}));
  const nlohmann::json c = CalibrateCompositeFdd({}, {f}, FddCalibrationOptions{});
  EXPECT_EQ(c["campaigns"][0]["seed_stream"], "campaign healthy");
  EXPECT_EQ(c["campaigns"][0]["trial_seeds"].size(), 2u);
  for (const FlightExtremes& x : f.flights) {
    EXPECT_FALSE(x.false_alarm);
    EXPECT_GT(x.extremes.max_takeoff_index, 0.0);  // they took off
    EXPECT_GE(x.extremes.debounced_motor_index, x.extremes.min_motor_index);
    EXPECT_LE(x.extremes.persistent_propeller_index, x.extremes.max_propeller_index);
    EXPECT_LE(x.extremes.gated_takeoff_index, x.extremes.max_takeoff_index);
  }
  EXPECT_NE(f.flights[0].extremes.max_takeoff_index, f.flights[1].extremes.max_takeoff_index) << "two drawn vehicles";
  const std::string partial = run(spec("partial", "fdd.false_alarm, fdd.healthy_extremes.min_motor_index"));
  RG_EXPECT_THROW_WITH(LoadCampaignFlights(partial), io::InputFileError,
                       "does not record the metric 'fdd.healthy_extremes.max_propeller_index'");
  // Found by fuzzing (tests/fuzz, results_jsonl): a record without one of the metrics its manifest
  // lists escaped as the JSON library's out_of_range; it is the folder's error, naming the trial.
  const std::string healthy = (dir_ / "healthy").string();
  const fs::path results = fs::path(healthy) / "results.jsonl";
  std::string text = io::ReadInputFile(results.string());
  text.replace(text.find("fdd.healthy_extremes.gated_takeoff_index"), 5, "xxx.h");
  std::ofstream(results) << text;
  RG_EXPECT_THROW_WITH(LoadCampaignFlights(healthy), io::InputFileError,
                       "has no fdd.healthy_extremes.gated_takeoff_index");
}

TEST(FddCalibration, RejectsNoInputAndABadMargin) {
  EXPECT_THROW(CalibrateCompositeFdd({}, {}, FddCalibrationOptions{}), std::invalid_argument);
  CampaignFlights empty;
  empty.dir = "empty";
  EXPECT_THROW(CalibrateCompositeFdd({}, {empty}, FddCalibrationOptions{}),
               std::invalid_argument);
  FddCalibrationOptions o;
  o.margin = 1.0;
  EXPECT_THROW(o.Validate(), ValidationError);
}

}  // namespace
}  // namespace rotorguard::benchmarks
