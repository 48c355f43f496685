#include "rotorguard/perception/voxel_map.h"

#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"

namespace rotorguard::perception {
namespace {

/// Points of the plane x = `x` over y in [-0.99, 0.99], z in [0.51, 1.49], every 2 cm: 20 x 10
/// voxels of 0.1 m.
std::vector<Eigen::Vector3f> Wall(double x) {
  std::vector<Eigen::Vector3f> pts;
  for (int k = 0; k < 100; ++k) {
    for (int m = 0; m < 50; ++m) pts.emplace_back(x, -0.99 + 0.02 * k, 0.51 + 0.02 * m);
  }
  return pts;
}

VoxelMapOptions Small() {
  VoxelMapOptions o;
  o.window_size_m = Vector3(12, 12, 4);
  return o;
}

TEST(VoxelMap, AWallIsOccupiedTheSpaceBeforeItFreeAndBehindItUnknown) {
  VoxelMap map(Small());
  const MapUpdateSummary s = map.Insert(Vector3(0, 0, 1), Wall(2.05));
  EXPECT_EQ(s.points_used, static_cast<int>(Wall(2.05).size()));
  EXPECT_EQ(s.points_dropped, 0);
  EXPECT_TRUE(map.IsOccupied(Vector3(2.05, 0.0, 1.0)));
  EXPECT_TRUE(map.IsOccupied(Vector3(2.05, 0.93, 1.41)));
  EXPECT_FALSE(map.IsOccupied(Vector3(1.0, 0.0, 1.0)));
  EXPECT_TRUE(map.IsKnown(Vector3(1.0, 0.0, 1.0))) << "observed free";
  EXPECT_FALSE(map.IsKnown(Vector3(3.0, 0.0, 1.0))) << "behind the wall";
  EXPECT_EQ(map.occupied_count(), 20 * 10) << "one layer of 2 x 1 m at 0.1 m";
}

TEST(VoxelMap, AnObstacleThatMovedAwayIsClearedByTheRaysThroughIt) {
  VoxelMap map(Small());
  for (int f = 0; f < 3; ++f) map.Insert(Vector3(0, 0, 1), Wall(2.05));
  ASSERT_TRUE(map.IsOccupied(Vector3(2.05, 0, 1)));
  int frames = 0;
  while (map.IsOccupied(Vector3(2.05, 0, 1)) && frames < 50) {
    map.Insert(Vector3(0, 0, 1), Wall(4.05));
    ++frames;
  }
  // From 3 hits (2.55) to below 0.7 takes 5 misses of 0.4.
  EXPECT_EQ(frames, 5);
  EXPECT_TRUE(map.IsOccupied(Vector3(4.05, 0, 1)));
  EXPECT_FALSE(map.IsInflated(Vector3(2.05, 0, 1)));
}

// Inflation by the vehicle radius: every voxel whose centre is within the radius of an occupied
// voxel's centre, checked exhaustively against the list of occupied voxels, also after the window
// has moved (the layer is kept incrementally and across recentring).
TEST(VoxelMap, InflationMatchesBruteForceAlsoAfterTheWindowMoves) {
  VoxelMapOptions o = Small();
  o.inflation_radius_m = 0.25;
  VoxelMap map(o);
  Rng rng(4);
  std::vector<Eigen::Vector3f> pts;
  for (int k = 0; k < 300; ++k) pts.emplace_back(rng.Uniform(-5, 5), rng.Uniform(-5, 5), rng.Uniform(0.1, 1.9));
  map.Insert(Vector3(0, 0, 1), pts);
  const auto check = [&](const char* when) {
    const std::vector<Vector3> occ = map.OccupiedVoxels();
    ASSERT_EQ(static_cast<int>(occ.size()), map.occupied_count()) << when;
    Rng q(8);
    for (int k = 0; k < 4000; ++k) {
      // Voxel centres around the occupied ones.
      const Vector3& near = occ[static_cast<std::size_t>(q.Uniform() * occ.size())];
      const Vector3 p = near + Vector3(q.Uniform(-0.5, 0.5), q.Uniform(-0.5, 0.5), q.Uniform(-0.5, 0.5));
      if (!map.InWindow(p)) continue;
      const Vector3 c = ((p / 0.1).array().floor() + 0.5).matrix() * 0.1;
      bool truth = false;
      for (const Vector3& v : occ) truth |= (v - c).norm() <= 0.25 + 1e-9;
      ASSERT_EQ(map.IsInflated(p), truth) << when << " at " << p.transpose();
    }
  };
  check("after insertion");
  map.Recenter(Vector3(1.37, -0.82, 0.3));
  check("after a small move");
  map.Recenter(Vector3(4.9, 3.1, 0.6));
  check("after a larger move");
  map.Recenter(Vector3(100, 0, 0));
  EXPECT_EQ(map.occupied_count(), 0) << "everything left";
  EXPECT_TRUE(map.OccupiedVoxels().empty());
}

TEST(VoxelMap, NearestObstacleAndSegmentQueries) {
  VoxelMapOptions o = Small();
  o.inflation_radius_m = 0.2;
  VoxelMap map(o);
  map.Insert(Vector3(0, 0, 1), {Eigen::Vector3f(2.05f, 0.05f, 1.05f)});
  const Vector3 c(2.05, 0.05, 1.05);  // the voxel's centre
  const auto n = map.Nearest(c + Vector3(0.5, 0, 0), 1.0);
  ASSERT_TRUE(n);
  EXPECT_NEAR(n->distance_m, 0.5, 1e-9);
  EXPECT_NEAR((n->point_W - c).norm(), 0.0, 1e-9);
  EXPECT_NEAR((n->normal_W - Vector3::UnitX()).norm(), 0.0, 1e-9);
  EXPECT_FALSE(map.Nearest(c + Vector3(0.5, 0, 0), 0.4)) << "beyond the search radius";
  EXPECT_TRUE(map.SegmentCollides(Vector3(2.05, -2, 1.05), Vector3(2.05, 2, 1.05)));
  EXPECT_TRUE(map.SegmentCollides(Vector3(2.24, -2, 1.05), Vector3(2.24, 2, 1.05))) << "within the radius";
  EXPECT_FALSE(map.SegmentCollides(Vector3(2.55, -2, 1.05), Vector3(2.55, 2, 1.05)));
  EXPECT_TRUE(map.SegmentCollides(Vector3(std::nan(""), 0, 0), Vector3(1, 1, 1))) << "a corrupt query is not safe";
}

TEST(VoxelMap, NonFiniteAndOutOfWindowPointsAreDroppedAndCountedEmptyFramesAreHarmless) {
  VoxelMap map(Small());
  EXPECT_EQ(map.Insert(Vector3(0, 0, 1), {}).points_used, 0);
  const MapUpdateSummary s = map.Insert(
      Vector3(0, 0, 1), {Eigen::Vector3f(std::nanf(""), 0, 1), Eigen::Vector3f(30, 0, 1), Eigen::Vector3f(2, 0, 1)});
  EXPECT_EQ(s.points_used, 1);
  EXPECT_EQ(s.points_dropped, 2);
  EXPECT_TRUE(map.IsKnown(Vector3(5.5, 0, 1))) << "the far return still clears the window";
  EXPECT_EQ(map.Insert(Vector3(std::nan(""), 0, 1), {Eigen::Vector3f(2, 0, 1)}).points_dropped, 1);
  EXPECT_FALSE(map.IsOccupied(Vector3(std::nan(""), 0, 0)));
}

TEST(VoxelMapOptions, ValidationNamesTheField) {
  VoxelMapOptions o;
  o.resolution_m = 0.0;
  try {
    o.Validate();
    ADD_FAILURE();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "resolution_m");
  }
  o = {};
  o.occupied_threshold = 5.0;
  EXPECT_THROW(o.Validate(), ValidationError);
  o = {};
  o.log_odds_max = 40.0;  // beyond the fixed-point store's range
  try {
    o.Validate();
    ADD_FAILURE();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "log_odds_max");
  }
}

}  // namespace
}  // namespace rotorguard::perception
