#include "rotorguard/benchmarks/octomap_reference.h"

#include <gtest/gtest.h>

#include <vector>

#include "rotorguard/perception/voxel_map.h"

namespace rotorguard::benchmarks {
namespace {

perception::VoxelMapOptions SmallMap() {
  perception::VoxelMapOptions o;
  o.window_size_m = Vector3(3.2, 3.2, 3.2);  // 32 voxels per axis: [-1.6, 1.6) m
  return o;
}

// One ray along x from a voxel's centre: both maps hit the return's voxel and miss the ten
// before it, and know nothing beyond it or beside it. The same sensor model in both: one hit
// (0.85) is above the threshold (0.7), one miss (-0.4) below it.
TEST(OctomapReference, OneRayMarksTheSameReturnOccupiedAndTheCellsBeforeItFree) {
  const perception::VoxelMapOptions options = SmallMap();
  perception::VoxelMap map(options);
  OctomapReference reference(options);
  const Vector3 origin(0.05, 0.05, 0.05);
  const std::vector<Eigen::Vector3f> points = {Eigen::Vector3f(1.05F, 0.05F, 0.05F)};
  map.Insert(origin, points);
  reference.Insert(origin, points, 40.0);
  const Vector3 end = points[0].cast<double>();
  EXPECT_TRUE(map.IsOccupied(end));
  EXPECT_TRUE(reference.IsOccupied(end));
  for (int i = 0; i < 10; ++i) {
    const Vector3 c = origin + Vector3(0.1 * i, 0.0, 0.0);
    SCOPED_TRACE(i);
    EXPECT_TRUE(map.IsKnown(c));
    EXPECT_FALSE(map.IsOccupied(c));
    EXPECT_TRUE(reference.IsKnown(c));
    EXPECT_FALSE(reference.IsOccupied(c));
  }
  for (const Vector3& c :
       {Vector3(end + Vector3(0.1, 0, 0)), Vector3(end + Vector3(0, 0.1, 0)), Vector3(0.55, 0.05, 0.15)}) {
    EXPECT_FALSE(map.IsKnown(c)) << c.transpose();
    EXPECT_FALSE(reference.IsKnown(c)) << c.transpose();
  }
  EXPECT_EQ(reference.OccupiedCells(map.window_min_W(), map.window_max_W()), map.OccupiedVoxels());
}

// Oblique rays (no endpoint on a voxel boundary, so neither walk meets a tie between axes), in
// one frame and then a second: every voxel of the window is known and occupied alike in both
// maps, the two implementations of the same model agreeing cell by cell. The second frame's
// rays cross the first's returns, which a miss then takes back below the threshold in both.
TEST(OctomapReference, ObliqueRaysMarkTheSameCellsInBothMaps) {
  const perception::VoxelMapOptions options = SmallMap();
  perception::VoxelMap map(options);
  OctomapReference reference(options);
  const Vector3 origin(0.013, -0.027, 0.031);
  const std::vector<Eigen::Vector3f> first = {Eigen::Vector3f(1.234F, 0.717F, 0.391F),
                                              Eigen::Vector3f(-0.873F, 1.162F, -0.448F),
                                              Eigen::Vector3f(0.561F, -1.307F, 1.093F)};
  // The first ray continued beyond its return, and one more.
  const std::vector<Eigen::Vector3f> second = {(origin + 1.2 * (first[0].cast<double>() - origin)).cast<float>(),
                                               Eigen::Vector3f(-1.421F, -0.219F, 0.652F)};
  int known = 0, occupied = 0;
  for (const std::vector<Eigen::Vector3f>* frame : {&first, &second}) {
    map.Insert(origin, *frame);
    reference.Insert(origin, *frame, 40.0);
    known = occupied = 0;
    const Vector3 lo = map.window_min_W();
    const Eigen::Vector3i n = map.size_voxels();
    for (int i = 0; i < n.x(); ++i) {
      for (int j = 0; j < n.y(); ++j) {
        for (int k = 0; k < n.z(); ++k) {
          const Vector3 c = lo + 0.1 * (Vector3(i, j, k) + Vector3::Constant(0.5));
          ASSERT_EQ(map.IsKnown(c), reference.IsKnown(c)) << c.transpose();
          ASSERT_EQ(map.IsOccupied(c), reference.IsOccupied(c)) << c.transpose();
          known += map.IsKnown(c) ? 1 : 0;
          occupied += map.IsOccupied(c) ? 1 : 0;
        }
      }
    }
  }
  EXPECT_GT(known, 50);  // the rays did cross the window
  EXPECT_EQ(occupied, 4) << "the second frame's two returns and the first's but the one it passed through";
}

}  // namespace
}  // namespace rotorguard::benchmarks
