#include "rotorguard/benchmarks/perception_bench.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

namespace rotorguard::benchmarks {
namespace {

// One simulated second per run: the map, scored against the world's own surfaces, is sharp with
// deskewing and smeared without it, in both scenes.
TEST(PerceptionBench, DeskewedMapsAreSharpAndRawOnesAreNot) {
  PerceptionBenchOptions o;
  o.duration_s = 1.0;
  const nlohmann::json r = RunPerceptionBenchmark(o);
  ASSERT_EQ(r["runs"].size(), 4u);
  for (int scene = 0; scene < 2; ++scene) {
    const nlohmann::json& on = r["runs"][2 * scene];
    const nlohmann::json& off = r["runs"][2 * scene + 1];
    ASSERT_TRUE(on["deskew"].get<bool>());
    ASSERT_FALSE(off["deskew"].get<bool>());
    EXPECT_EQ(on["frames"].get<long>(), 10);
    EXPECT_GT(on["points_per_frame_mean"].get<double>(), 10000.0);
    EXPECT_GT(on["truth_voxels_in_window"].get<long>(), 1000);
    // Measured over this second, forest and room: precision 1.000 and 1.000, recall 0.987 and
    // 1.000 with deskewing; precision 0.365 and 0.594 without.
    EXPECT_GE(on["map_precision"].get<double>(), 0.95) << on.dump();
    EXPECT_GE(on["map_recall"].get<double>(), 0.9) << on.dump();
    EXPECT_LT(off["map_precision"].get<double>(), 0.8) << off.dump();
  }
  EXPECT_GT(r["points_per_s_simulated"].get<double>(), 0.0);
}

TEST(PerceptionBench, TheForestLeavesTheFlightLaneClear) {
  const sim::World w = PerceptionForest(3);
  ASSERT_EQ(w.cylinders.size(), 500u);
  for (const sim::Cylinder& c : w.cylinders) EXPECT_GT(std::abs(c.center_m.y()) - c.radius_m, 1.0);
  EXPECT_NE(PerceptionForest(4).cylinders[0].center_m, w.cylinders[0].center_m) << "the seed draws the layout";
}

// Four simulated seconds at 11 rad/s: the four conditions of one spin, each followed within
// centimetres (hovering) and a decimetre (flying), the frames all registered but the first, the
// drift reported when flying only. The drift is the displacement's error over each 10 m: at 1 m/s
// a 3 s flight has none to report, so this one flies 4 m/s (12 m after the 2 s from rest).
TEST(LioBench, FollowsEveryConditionOfASpinAndReportsWhatItMeasured) {
  LioBenchOptions o;
  o.duration_s = 4.0;
  o.speed_m_s = 4.0;
  o.spins = {11.0};
  int progress = 0;
  o.progress = [&](int done, int total) {
    progress = done;
    EXPECT_EQ(total, 4);
  };
  const nlohmann::json r = RunLioBenchmark(o);
  EXPECT_EQ(progress, 4);
  ASSERT_EQ(r["runs"].size(), 4u);
  for (const nlohmann::json& x : r["runs"]) {
    const bool flying = x["motion"].get<std::string>() == "flying";
    EXPECT_EQ(x["frames"].get<long>(), 40);
    EXPECT_EQ(x["frames_used"].get<long>(), 39) << "the first frame starts the map";
    EXPECT_FALSE(x["diverged"].get<bool>());
    EXPECT_LT(x["ate_rmse_m"].get<double>(), flying ? 0.1 : 0.03) << x.dump();
    EXPECT_LT(x["attitude_max_deg"].get<double>(), 2.0) << x.dump();
    EXPECT_EQ(x["drift_percent"].is_null(), !flying) << x.dump();
    EXPECT_GT(x["frame_ms_p99"].get<double>(), 0.0);
  }
}

TEST(PerceptionBench, InvalidOptionsAreNamed) {
  PerceptionBenchOptions o;
  o.spin_rad_s = -1.0;
  try {
    RunPerceptionBenchmark(o);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("PerceptionBenchOptions::spin_rad_s"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rotorguard::benchmarks
