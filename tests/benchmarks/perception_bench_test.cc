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
