#include "rotorguard/perception/point_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"

namespace rotorguard::perception {
namespace {

std::vector<Vector3> RandomPoints(int n, double half_extent, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<Vector3> points;
  for (int i = 0; i < n; ++i) {
    points.emplace_back(rng.Uniform(-half_extent, half_extent), rng.Uniform(-half_extent, half_extent),
                        rng.Uniform(-half_extent, half_extent));
  }
  return points;
}

// Within a voxel edge the neighbour search is exact: against a brute-force search over every
// point (all stored: no spacing, room in every voxel), the same points in the same order, for
// queries anywhere, on voxel corners included.
TEST(PointMap, NearestNeighboursWithinAVoxelEdgeMatchABruteForceSearch) {
  PointMapOptions o;
  o.voxel_m = 0.5;
  o.min_point_spacing_m = 0.0;
  o.max_points_per_voxel = 32;
  PointMap map(o);
  const std::vector<Vector3> points = RandomPoints(4000, 2.0, 1);  // ~2 points per voxel: nothing refused
  ASSERT_EQ(map.Insert(points), 4000);
  EXPECT_EQ(map.size(), 4000);
  Rng rng(2);
  std::vector<Vector3> found;
  std::vector<double> d2;
  for (int trial = 0; trial < 500; ++trial) {
    Vector3 q(rng.Uniform(-2, 2), rng.Uniform(-2, 2), rng.Uniform(-2, 2));
    if (trial % 5 == 0) q = (q / 0.5).array().round().matrix() * 0.5;  // on a voxel corner
    const double radius = rng.Uniform(0.1, 0.5);
    const int k = 1 + trial % 8;
    std::vector<std::pair<double, Vector3>> brute;
    for (const Vector3& p : points) {
      const double d = (p.cast<float>().cast<double>() - q).squaredNorm();
      if (d <= radius * radius) brute.push_back({d, p.cast<float>().cast<double>()});
    }
    std::sort(brute.begin(), brute.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const int n = map.Nearest(q, k, radius, &found, &d2);
    ASSERT_EQ(n, std::min<int>(k, static_cast<int>(brute.size()))) << "trial " << trial;
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(d2[i], brute[i].first, 1e-5) << "trial " << trial << " neighbour " << i;
      EXPECT_LT((found[i] - brute[i].second).norm(), 1e-6);
    }
  }
}

// The down-sampling on the map: a point within the spacing of one its voxel holds is refused, a
// full voxel refuses everything, and inserting the same surface again adds nothing.
TEST(PointMap, RefusesPointsTooCloseToStoredOnesAndBeyondAVoxelsCapacity) {
  PointMapOptions o;
  o.voxel_m = 1.0;
  o.min_point_spacing_m = 0.1;
  o.max_points_per_voxel = 3;
  PointMap map(o);
  EXPECT_EQ(map.Insert({Vector3(0.5, 0.5, 0.5), Vector3(0.55, 0.5, 0.5), Vector3(0.7, 0.5, 0.5)}), 2);
  EXPECT_EQ(map.Insert({Vector3(0.2, 0.2, 0.2), Vector3(0.9, 0.9, 0.9)}), 1);  // the voxel is full
  EXPECT_EQ(map.Insert({Vector3(1.5, 0.5, 0.5)}), 1);                          // the next voxel
  EXPECT_EQ(map.size(), 4);
  const std::vector<Vector3> surface = RandomPoints(500, 3.0, 3);
  PointMap fresh(PointMapOptions{});
  const int first = fresh.Insert(surface);
  EXPECT_GT(first, 0);
  EXPECT_EQ(fresh.Insert(surface), 0);
  EXPECT_EQ(fresh.size(), first);
}

// Pruning deletes exactly the blocks (4 voxels a side: 2 m here) whose centre lies beyond the
// window, and the search still finds what remains; points inserted after a pruning reuse the
// freed voxels and are found as well.
TEST(PointMap, PruningKeepsTheBlocksWithinTheWindowAndTheirPoints) {
  PointMapOptions o;
  o.voxel_m = 0.5;
  o.min_point_spacing_m = 0.0;
  o.window_radius_m = 3.0;
  PointMap map(o);
  std::vector<Vector3> line;
  for (int i = -40; i < 40; ++i) line.emplace_back(0.25 + 0.5 * i, 0.25, 0.25);  // one point per voxel centre
  EXPECT_EQ(map.Insert(line), 80);
  EXPECT_EQ(map.voxels(), 80);
  const Vector3 centre(1.0, 0.0, 0.0);
  // A point's block is [2 b, 2 b + 2) on each axis; its centre 2 b + 1 (b = 0 across y and z).
  const auto block_centre = [](const Vector3& p) { return Vector3(2.0 * std::floor(p.x() / 2.0) + 1.0, 1.0, 1.0); };
  const auto stays = [&](const Vector3& p) { return (block_centre(p) - centre).norm() <= 3.0; };
  int kept = 0;
  for (const Vector3& p : line) kept += stays(p);
  ASSERT_GT(kept, 0);
  ASSERT_LT(kept, 80);
  EXPECT_EQ(map.Prune(centre), 80 - kept);
  EXPECT_EQ(map.size(), kept);
  EXPECT_EQ(map.voxels(), kept);
  EXPECT_EQ(map.Prune(centre), 0);  // nothing more to delete
  std::vector<Vector3> found;
  for (const Vector3& p : line) EXPECT_EQ(map.Nearest(p, 1, 0.1, &found), stays(p) ? 1 : 0) << p.transpose();
  // The pruned voxels' storage serves new points, which are found where they were put.
  std::vector<Vector3> other;
  for (int i = 0; i < 20; ++i) other.emplace_back(0.25 + 0.5 * i, 5.25, 0.25);
  EXPECT_EQ(map.Insert(other), 20);
  EXPECT_EQ(map.voxels(), kept + 20);
  for (const Vector3& p : other) {
    ASSERT_EQ(map.Nearest(p, 1, 0.1, &found), 1);
    EXPECT_LT((found[0] - p).norm(), 1e-6);
  }
  for (const Vector3& p : line) EXPECT_EQ(map.Nearest(p, 1, 0.1, &found), stays(p) ? 1 : 0) << p.transpose();
}

// The smallest window allowed (6 voxel edges) never deletes what lies within a voxel edge of the
// vehicle, wherever the vehicle stands in its block: the block's centre is at most 2 sqrt(3)
// edges from any of its points. Against a brute-force count of those points before and after.
TEST(PointMap, TheSmallestWindowKeepsTheVehiclesSurroundings) {
  PointMapOptions o;
  o.voxel_m = 0.5;
  o.min_point_spacing_m = 0.0;
  o.max_points_per_voxel = 32;
  o.window_radius_m = 6.0 * o.voxel_m;
  const std::vector<Vector3> points = RandomPoints(4000, 3.0, 5);
  Rng rng(6);
  std::vector<Vector3> found;
  for (int trial = 0; trial < 50; ++trial) {
    PointMap map(o);
    ASSERT_EQ(map.Insert(points), 4000);
    const Vector3 vehicle(rng.Uniform(-1.5, 1.5), rng.Uniform(-1.5, 1.5), rng.Uniform(-1.5, 1.5));
    map.Prune(vehicle);
    for (const Vector3& p : points) {
      if ((p - vehicle).norm() > o.voxel_m) continue;
      EXPECT_EQ(map.Nearest(p, 1, 1e-3, &found), 1) << "trial " << trial << ": " << p.transpose();
    }
  }
}

// Points and queries beyond the keys' range (2^20 voxels: 524 km at 0.5 m) are refused and find
// nothing, rather than aliasing onto a cell near the origin or overflowing an int.
TEST(PointMap, IgnoresCoordinatesBeyondTheKeysRange) {
  PointMap map(PointMapOptions{});
  const Vector3 near(0.25, 0.25, 0.25);
  ASSERT_EQ(map.Insert({near}), 1);
  const double alias = std::ldexp(0.5, 21);  // one whole key period away: the same key, were it masked
  EXPECT_EQ(map.Insert({near + Vector3(alias, 0.0, 0.0), Vector3(1e300, 0.0, 0.0)}), 0);
  std::vector<Vector3> found;
  EXPECT_EQ(map.Nearest(near + Vector3(alias, 0.0, 0.0), 1, 0.5, &found), 0);
  EXPECT_EQ(map.Nearest(Vector3(-1e300, 0.0, 0.0), 1, 0.5, &found), 0);
  EXPECT_EQ(map.Nearest(near, 1, 0.5, &found), 1);
  // At the range's edge: a point just inside is stored, and a query just outside finds nothing,
  // though the point lies within its radius.
  const double edge = 0.99 * std::ldexp(0.5, 20);
  ASSERT_EQ(map.Insert({Vector3(edge - 0.1, 0.25, 0.25)}), 1);
  EXPECT_EQ(map.Nearest(Vector3(edge - 0.05, 0.25, 0.25), 1, 0.5, &found), 1);
  EXPECT_EQ(map.Nearest(Vector3(edge + 0.05, 0.25, 0.25), 1, 0.5, &found), 0);
}

TEST(PointMap, RejectsOptionsOutsideTheirRanges) {
  PointMapOptions o;
  o.min_point_spacing_m = o.voxel_m;  // not below the voxel edge
  EXPECT_THROW(PointMap{o}, ValidationError);
  o = {};
  o.max_points_per_voxel = 33;
  EXPECT_THROW(PointMap{o}, ValidationError);
  o = {};
  o.window_radius_m = 0.5;
  EXPECT_THROW(PointMap{o}, ValidationError);
  o.window_radius_m = 5.9 * o.voxel_m;  // below the block pruning's floor
  EXPECT_THROW(PointMap{o}, ValidationError);
}

}  // namespace
}  // namespace rotorguard::perception
