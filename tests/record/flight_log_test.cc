// The flight record (flight_log.h) and its two serialisations, CSV + JSON and MCAP, on real
// flights: what is written reads back, the scene's samples match the simulator's world, the map's
// changes rebuild the stack's map, and damaged files are rejected with their byte offset.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/report_html.h"
#include "rotorguard/record/flight_log.h"
#include "rotorguard/record/flight_mcap.h"
#include "rotorguard/record/report.h"
#include "test_util.h"

namespace rotorguard::record {
namespace {

namespace fs = std::filesystem;

std::string Config(const std::string& name) {
  return testing::SourcePath("configs/scenarios/" + name);
}

class FlightLogTest : public rotorguard::testing::TempFolderTest {};

/// Rebuilds the set of occupied voxels after each map snapshot of a scene.
std::vector<std::set<std::array<long, 3>>> ReplayMap(const nlohmann::json& scene) {
  std::vector<std::set<std::array<long, 3>>> out;
  std::set<std::array<long, 3>> voxels;
  for (const nlohmann::json& s : scene["map"]["snapshots"]) {
    const auto& removed = s["removed"];
    for (std::size_t k = 0; k + 2 < removed.size(); k += 3) voxels.erase({removed[k].get<long>(), removed[k + 1].get<long>(), removed[k + 2].get<long>()});
    const auto& added = s["added"];
    for (std::size_t k = 0; k + 2 < added.size(); k += 3) voxels.insert({added[k].get<long>(), added[k + 1].get<long>(), added[k + 2].get<long>()});
    out.push_back(voxels);
  }
  return out;
}

TEST_F(FlightLogTest, CsvAndMcapHoldTheSameFlightAndTheMapsChangesRebuildTheStacksMap) {
  harness::Scenario s = harness::LoadScenario(Config("room_lidar_propeller_loss.yaml"), {{"duration_s", "1.6"}});
  // The stack's map at every control cycle, as an independent record of what the scene must hold.
  std::map<double, int> occupied;
  std::map<double, std::set<std::array<long, 3>>> first_map;
  harness::RunOptions o;
  o.out_dir = dir_.string();
  o.log_format = harness::LogFormat::kBoth;
  double t = 0.0;
  o.on_control_cycle = [&](const stack::FlightStack& st) {
    if (const perception::VoxelMap* map = st.map()) {
      occupied[t] = map->occupied_count();
      if (first_map.empty()) {
        std::set<std::array<long, 3>> set;
        for (const Vector3& c : map->OccupiedVoxels()) {
          const Eigen::Vector3i i = (c / map->resolution()).array().floor().cast<int>();
          set.insert({i.x(), i.y(), i.z()});
        }
        first_map[t] = set;
      }
    }
    t += 1.0 / s.stack.control_rate_hz;
  };
  const harness::RunSummary summary = harness::RunScenario(s, o);
  ASSERT_TRUE(summary.success) << summary.failure_reason.value_or("");

  const FlightLog csv = ReadFlightLog(dir_.string());
  const FlightLog mcap = ReadFlightMcap((dir_ / "flight.mcap").string());
  ASSERT_EQ(csv.table.columns, mcap.table.columns);
  EXPECT_TRUE(csv.table.Has("mi_0") && csv.table.Has("pi_3") && csv.table.Has("health_2") && csv.table.Has("nmpc_ms"));
  EXPECT_FALSE(csv.table.Has("lio_matched")) << "the LiDAR odometry's columns only when it is the estimator";
  // One row per 1/log_rate_hz from t = 0, plus the final state.
  ASSERT_EQ(csv.table.rows(), static_cast<std::size_t>(std::llround(s.duration_s * s.log_rate_hz)) + 1);
  ASSERT_EQ(csv.table.rows(), mcap.table.rows());
  for (std::size_t c = 0; c < csv.table.columns.size(); ++c) {
    for (std::size_t r = 0; r < csv.table.rows(); ++r) {
      const double a = csv.table.values[c][r], b = mcap.table.values[c][r];
      ASSERT_LE(std::abs(a - b), 1e-8 * std::max(1.0, std::abs(b))) << csv.table.columns[c] << " row " << r;  // %.9g
    }
  }
  EXPECT_EQ(csv.scene, mcap.scene);
  EXPECT_EQ(csv.summary["scenario"], "room_lidar_propeller_loss");
  EXPECT_EQ(mcap.summary["fdd"]["rotor"], 0);

  // The map's snapshots, replayed, hold exactly as many voxels as the stack's map had then.
  const nlohmann::json& snapshots = csv.scene["map"]["snapshots"];
  ASSERT_GE(snapshots.size(), 3u);
  const auto maps = ReplayMap(csv.scene);
  for (std::size_t k = 0; k < snapshots.size(); ++k) {
    const double ts = snapshots[k]["t_s"].get<double>();
    const auto it = occupied.lower_bound(ts - 1e-9);
    ASSERT_NE(it, occupied.end());
    EXPECT_EQ(static_cast<int>(maps[k].size()), it->second) << "snapshot at " << ts << " s";
  }
  EXPECT_EQ(maps.front(), first_map.begin()->second);
}

// The forest's first seconds on the LiDAR-inertial odometry, its propeller lost at 1 s (the spin
// that follows is the odometry's hardest part): every row's lio_* columns hold the newest frame of
// the estimator's own record as it stood when the row was written (read at every control cycle,
// and once more after the last step for the final row), and nothing in the log is NaN or infinite.
TEST_F(FlightLogTest, TheLioColumnsHoldTheOdometrysNewestFrame) {
  const harness::Scenario s =
      harness::LoadScenario(Config("forest.yaml"), {{"duration_s", "2"}, {"faults.0.onset.at_time_s", "1"}});
  ASSERT_EQ(s.stack.estimator.kind, stack::EstimatorKind::kLio);
  std::vector<perception::LioFrameSummary> newest;  // per control cycle; default before the first frame
  const stack::FlightStack* flown = nullptr;
  std::optional<perception::LioFrameSummary> last;
  harness::RunOptions o;
  o.out_dir = dir_.string();
  o.on_control_cycle = [&](const stack::FlightStack& st) {
    flown = &st;
    const std::vector<perception::LioFrameSummary>& frames = st.lio()->frames();
    newest.push_back(frames.empty() ? perception::LioFrameSummary{} : frames.back());
  };
  // Called with 1 once the last step is done, the stack still alive: the final row's frame.
  o.progress = [&](double done) {
    if (done == 1.0 && flown != nullptr && !flown->lio()->frames().empty()) last = flown->lio()->frames().back();
  };
  const harness::RunSummary summary = harness::RunScenario(s, o);
  ASSERT_FALSE(summary.crashed) << summary.crash_reason.value_or("");
  ASSERT_TRUE(last.has_value());

  const FlightLog log = ReadFlightLog(dir_.string());
  for (const char* c : {"lio_used", "lio_degenerate", "lio_matched", "lio_residual_rms_m", "lio_weakest_std_m"}) {
    ASSERT_TRUE(log.table.Has(c)) << c;
  }
  for (std::size_t c = 0; c < log.table.columns.size(); ++c) {
    for (std::size_t r = 0; r < log.table.rows(); ++r) {
      ASSERT_TRUE(std::isfinite(log.table.values[c][r])) << log.table.columns[c] << " row " << r;
    }
  }
  const std::vector<double>& t = log.table.Column("t");
  const std::vector<double>& used = log.table.Column("lio_used");
  const std::vector<double>& degenerate = log.table.Column("lio_degenerate");
  const std::vector<double>& matched = log.table.Column("lio_matched");
  const std::vector<double>& residual = log.table.Column("lio_residual_rms_m");
  const std::vector<double>& weakest = log.table.Column("lio_weakest_std_m");
  const auto expect_row = [&](std::size_t r, const perception::LioFrameSummary& f) {
    EXPECT_EQ(used[r], f.used ? 1.0 : 0.0) << "row " << r;
    EXPECT_EQ(degenerate[r], f.degenerate ? 1.0 : 0.0) << "row " << r;
    EXPECT_EQ(matched[r], f.points_matched) << "row " << r;
    EXPECT_NEAR(residual[r], f.residual_rms_m, 1e-8 * std::max(1.0, f.residual_rms_m)) << "row " << r;  // %.9g
    const double capped = std::min(f.weakest_std_m, kLioWeakestStdCapM);
    EXPECT_NEAR(weakest[r], capped, 1e-8 * std::max(1.0, capped)) << "row " << r;
  };
  // Every row but the final one is written in the step of a control cycle, after it.
  int registered = 0;
  for (std::size_t r = 0; r + 1 < log.table.rows(); ++r) {
    const auto cycle = static_cast<std::size_t>(std::llround(t[r] * s.stack.control_rate_hz));
    ASSERT_NEAR(static_cast<double>(cycle) / s.stack.control_rate_hz, t[r], 1e-9) << "a row off the control cycles";
    ASSERT_LT(cycle, newest.size());
    expect_row(r, newest[cycle]);
    registered += newest[cycle].used;
  }
  // At the end: the estimator's last frame.
  expect_row(log.table.rows() - 1, *last);
  EXPECT_EQ(matched.back(), last->points_matched);
  EXPECT_GT(last->points_matched, 0);
  EXPECT_GT(registered, static_cast<int>(log.table.rows()) / 2) << "the frames were registered most of the time";
  // The threshold the frames were judged by is in the summary, for the report's plot.
  EXPECT_EQ(log.summary["odometry"]["degenerate_std_m"].get<double>(), s.stack.estimator.lio.degenerate_std_m);
}

TEST_F(FlightLogTest, MovingBoxesAreSampledWhereTheWorldPutsThem) {
  harness::Scenario s = harness::LoadScenario(Config("hover.yaml"), {{"duration_s", "2"}});
  sim::MovingBox box;
  box.size_m = Vector3(0.5, 0.5, 1.0);
  box.waypoints_m = {Vector3(3, -1, 0.5), Vector3(3, 1, 0.5), Vector3(4, 1, 0.5)};
  box.speed_m_s = 1.3;
  s.world.moving_boxes.push_back(box);
  harness::RunOptions o;
  o.out_dir = dir_.string();
  ASSERT_TRUE(harness::RunScenario(s, o).success);
  const FlightLog log = ReadFlightLog(dir_.string());
  const nlohmann::json& m = log.scene["world"]["moving_boxes"][0];
  ASSERT_GE(m["t_s"].size(), 19u);  // 10 Hz over 2 s
  for (std::size_t k = 0; k < m["t_s"].size(); ++k) {
    const double t = m["t_s"][k].get<double>();
    const Vector3 truth = box.At(t).center_m;
    for (int a = 0; a < 3; ++a) EXPECT_DOUBLE_EQ(m["center_m"][k][a].get<double>(), truth[a]) << "t = " << t;
  }
  EXPECT_TRUE(log.scene["map"].is_null());  // no LiDAR on this vehicle
}

TEST_F(FlightLogTest, AnAssemblysSceneCarriesItsUnitsAndEachRotorsUnit) {
  const harness::Scenario s = harness::LoadScenario(Config("mars_spiral_3x2.yaml"), {{"duration_s", "1"}});
  harness::RunOptions o;
  o.out_dir = dir_.string();
  ASSERT_TRUE(harness::RunScenario(s, o).success);
  const FlightLog log = ReadFlightLog(dir_.string());
  const nlohmann::json& v = log.scene["vehicle"];
  ASSERT_EQ(v["units"].size(), 6u);
  ASSERT_EQ(v["rotors"].size(), 24u);
  for (int r = 0; r < 24; ++r) {
    const int unit = v["rotors"][r]["unit"].get<int>();
    EXPECT_EQ(unit, r / 4);
    // Each rotor sits within the unit's arm of its unit's centre.
    const double dx = v["rotors"][r]["position_m"][0].get<double>() - v["units"][unit]["center_m"][0].get<double>();
    const double dy = v["rotors"][r]["position_m"][1].get<double>() - v["units"][unit]["center_m"][1].get<double>();
    EXPECT_NEAR(std::hypot(dx, dy), 0.075 * std::sqrt(2.0), 1e-9);
  }
}

TEST_F(FlightLogTest, PlansAreTheTrajectoriesTheReferenceFollowed) {
  // Logged at every physics step: a plan starts at a control instant and samples every 0.1 s, so
  // each of its samples falls on a row.
  const harness::Scenario s =
      harness::LoadScenario(Config("room_navigate.yaml"), {{"duration_s", "4"}, {"sim.log_rate_hz", "1000"}});
  harness::RunOptions o;
  o.out_dir = dir_.string();
  harness::RunScenario(s, o);
  const FlightLog log = ReadFlightLog(dir_.string());
  const nlohmann::json& plans = log.scene["plans"];
  ASSERT_GE(plans.size(), 1u);
  // Between two plans the reference is the earlier plan: its points at log instants match.
  const std::vector<double>& t = log.table.Column("t");
  const nlohmann::json& p = plans[0];
  const double start = p["start_s"].get<double>(), duration = p["duration_s"].get<double>();
  const double end = plans.size() > 1 ? plans[1]["t_s"].get<double>() : t.back();
  const double step = p["sample_s"].get<double>();
  int compared = 0;
  for (std::size_t k = 0; k + 1 < p["points_m"].size(); ++k) {  // the last point is the end
    const double tk = start + step * static_cast<double>(k);
    ASSERT_LE(tk, start + duration);
    if (tk > end) break;
    const auto row = static_cast<std::size_t>(std::llround(tk * s.log_rate_hz));
    if (std::abs(t[row] - tk) > 1e-9) continue;  // compare only where a log row falls on the plan's sample
    for (int a = 0; a < 3; ++a) {
      const char* col[] = {"ref_p_x", "ref_p_y", "ref_p_z"};
      EXPECT_NEAR(log.table.Column(col[a])[row], p["points_m"][k][a].get<double>(), 1e-6) << "t = " << tk;
    }
    ++compared;
  }
  EXPECT_GE(compared, 3);
}

TEST_F(FlightLogTest, ReportDataIsThinnedAndKeepsTheFinalState) {
  FlightLog log;
  log.summary = {{"scenario", "synthetic"}};
  log.scene = {{"world", nlohmann::json::object()}};
  log.table.columns = {"t", "p_x", "rpm_0"};
  log.table.values.resize(3);
  for (int k = 0; k <= 6000; ++k) {  // 60 s at 100 Hz
    log.table.values[0].push_back(0.01 * k);
    log.table.values[1].push_back(std::sin(0.01 * k) + 1e-7);
    log.table.values[2].push_back(12345.678);
  }
  const nlohmann::json d = FlightReportData(log);  // at most 50 Hz
  const auto& t = d["series"]["t"];
  ASSERT_EQ(t.size(), 3001u);
  EXPECT_DOUBLE_EQ(t[1].get<double>(), 0.02);
  EXPECT_DOUBLE_EQ(t.back().get<double>(), 60.0);
  EXPECT_DOUBLE_EQ(d["series"]["rpm_0"][0].get<double>(), 12346.0);  // whole rpm
  EXPECT_DOUBLE_EQ(d["series"]["p_x"][0].get<double>(), 0.0);        // 0.1 mm
  FlightReportOptions o;
  o.max_rows = 100;
  EXPECT_LE(FlightReportData(log, o)["series"]["t"].size(), 101u);
  o.max_rows = 1;
  EXPECT_THROW(FlightReportData(log, o), std::invalid_argument);
}

// Found by fuzzing (tests/fuzz, log_csv): rounding 1e308 to 4 decimals multiplied it past the
// largest double, and the report's data held inf.
TEST_F(FlightLogTest, ReportDataOfHugeFiniteValuesStaysFinite) {
  FlightLog log;
  log.summary = {{"scenario", "synthetic"}};
  log.scene = {{"world", nlohmann::json::object()}};
  log.table.columns = {"t", "p_x", "rpm_0"};
  log.table.values = {{0.0, 0.01}, {1e308, -1.7e308}, {1e300, 123456789012345678.0}};
  const nlohmann::json d = FlightReportData(log);
  EXPECT_DOUBLE_EQ(d["series"]["p_x"][0].get<double>(), 1e308);
  EXPECT_DOUBLE_EQ(d["series"]["p_x"][1].get<double>(), -1.7e308);
  EXPECT_DOUBLE_EQ(d["series"]["rpm_0"][1].get<double>(), 123456789012345678.0);  // nothing left to round
  // Found by fuzzing (tests/fuzz, summary_json): a "scenario" that is not text threw the JSON
  // library's type_error while making the title.
  log.summary = {{"scenario", {{"x", 1}}}};
  EXPECT_EQ(FlightReportData(log)["title"], "flight");
}

TEST_F(FlightLogTest, DamagedOrMissingFilesAreNamedWithTheirOffset) {
  const harness::Scenario s = harness::LoadScenario(Config("hover.yaml"), {{"duration_s", "0.5"}});
  harness::RunOptions o;
  o.out_dir = dir_.string();
  o.log_format = harness::LogFormat::kBoth;
  harness::RunScenario(s, o);
  const std::string csv = io::ReadInputFile((dir_ / "log.csv").string());
  // log.csv cut mid-row.
  Write("log.csv", csv.substr(0, csv.size() - 7));
  try {
    ReadFlightLog(dir_.string());
    ADD_FAILURE() << "a truncated log.csv was accepted";
  } catch (const io::CorruptFileError& e) {
    EXPECT_EQ(e.path(), (dir_ / "log.csv").string());
    EXPECT_EQ(e.byte_offset(), csv.size() - 7);
  }
  // A truncated scene.json is named with the offset where the JSON broke.
  Write("log.csv", csv);
  const std::string scene = io::ReadInputFile((dir_ / "scene.json").string());
  Write("scene.json", scene.substr(0, scene.size() / 2));
  EXPECT_THROW(ReadFlightLog(dir_.string()), io::CorruptFileError);
  // Found by fuzzing (tests/fuzz, scene_json): a number beyond a double escaped as the JSON
  // library's own out_of_range.
  Write("scene.json", "{\"world\": {\"x\": 1e999}}");
  RG_EXPECT_THROW_WITH(ReadFlightLog(dir_.string()), io::CorruptFileError, "scene.json");
  Write("scene.json", "[1, 2]");
  RG_EXPECT_THROW_WITH(ReadFlightLog(dir_.string()), io::CorruptFileError, "expected a JSON object");
  Write("scene.json", scene);
  // Without log.csv and scene.json the MCAP file is read instead, and checked.
  fs::remove(dir_ / "log.csv");
  fs::remove(dir_ / "scene.json");
  EXPECT_EQ(ReadFlightLog(dir_.string()).table.rows(), 51u);
  const std::string mcap = io::ReadInputFile((dir_ / "flight.mcap").string());
  Write("flight.mcap", mcap.substr(0, mcap.size() - 100));
  EXPECT_THROW(ReadFlightLog(dir_.string()), io::CorruptFileError);
  fs::remove(dir_ / "flight.mcap");
  EXPECT_THROW(ReadFlightLog(dir_.string()), io::InputFileError);
  EXPECT_THROW(ReadFlightLog((dir_ / "nowhere").string()), io::InputFileError);
}

TEST_F(FlightLogTest, ReportPageInlinesTheDataSafely) {
  FlightLog log;
  log.summary = {{"scenario", "a </script> name"}};
  log.scene = {{"world", nlohmann::json::object()}};
  log.table.columns = {"t"};
  log.table.values = {{0.0, 0.01}};
  const std::string path = (dir_ / "report.html").string();
  if (!io::HasViewer()) {
    EXPECT_THROW(WriteFlightReport(log, path), std::runtime_error);
    return;
  }
  WriteFlightReport(log, path);
  const std::string page = io::ReadInputFile(path);
  const std::size_t data = page.find("<script id=\"rotorguard-data\" type=\"application/json\">");
  ASSERT_NE(data, std::string::npos);
  const std::size_t end = page.find("</script>", data);
  const std::string json = page.substr(data + 53, end - data - 53);
  // The name's "</script>" is escaped, so the element ends where the data ends and parses back.
  const nlohmann::json back = nlohmann::json::parse(json);
  EXPECT_EQ(back["summary"]["scenario"], "a </script> name");
  EXPECT_EQ(back["kind"], "flight");
  EXPECT_NE(page.find("<title>rotorguard: a &lt;/script&gt; name</title>"), std::string::npos);
}

}  // namespace
}  // namespace rotorguard::record
