#include "rotorguard/perception/voxel_map.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/sim/lidar.h"
#include "test_util.h"

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

/// Frames of a wall at x = 4.05 m inserted until the voxel at (2.05, 0, 1) m, of a nearer wall
/// that moved away, is no longer occupied (at most 50).
int FramesUntilTheNearWallClears(VoxelMap* map) {
  int frames = 0;
  while (map->IsOccupied(Vector3(2.05, 0, 1)) && frames < 50) {
    map->Insert(Vector3(0, 0, 1), Wall(4.05));
    ++frames;
  }
  return frames;
}

TEST(VoxelMap, AnObstacleThatMovedAwayIsClearedByTheRaysThroughIt) {
  VoxelMap map(Small());
  for (int f = 0; f < 3; ++f) map.Insert(Vector3(0, 0, 1), Wall(2.05));
  ASSERT_TRUE(map.IsOccupied(Vector3(2.05, 0, 1)));
  // From 3 hits (2.55) to below 0.7 takes 5 misses of 0.4.
  EXPECT_EQ(FramesUntilTheNearWallClears(&map), 5);
  EXPECT_TRUE(map.IsOccupied(Vector3(4.05, 0, 1)));
  EXPECT_FALSE(map.IsInflated(Vector3(2.05, 0, 1)));
}

// clearing_stride on the same walls. The voxel watched, (2.05, 0, 1) m, is crossed by exactly four
// of the far wall's rays: the rays to its voxels (y, z) = (10, 5), (10, 6), (11, 5) and (11, 6) of
// 20 x 10, of index 10 y + z = 105, 106, 115 and 116 in the frame's list (one ray per hit voxel,
// in the returns' order; the next rays out pass beside it). With a
// stride of 2 each frame walks one ray of each pair of neighbours, so the wall still clears in
// five frames. With a stride of 5 only frames n = 0 and 1 (mod 5) walk one of the four (105 and
// 115 = 0, 106 and 116 = 1): after the near wall's frames 0-2, the five misses come in frames 5,
// 6, 10, 11 and 15, the 13th of the far wall's frames.
TEST(VoxelMap, AClearingStrideWalksOneRayInStrideAndClearsWhereThoseRaysPass) {
  for (const auto& [stride, expected_frames] : {std::pair{2, 5}, std::pair{5, 13}}) {
    VoxelMapOptions o = Small();
    o.clearing_stride = stride;
    VoxelMap map(o);
    for (int f = 0; f < 3; ++f) {
      const MapUpdateSummary s = map.Insert(Vector3(0, 0, 1), Wall(2.05));
      EXPECT_EQ(s.rays_walked, 200 / stride) << "stride " << stride << ", frame " << f;
      EXPECT_EQ(s.points_used, static_cast<int>(Wall(2.05).size())) << "every return is still hit";
    }
    EXPECT_EQ(map.occupied_count(), 20 * 10);
    EXPECT_EQ(FramesUntilTheNearWallClears(&map), expected_frames) << "stride " << stride;
  }
}

// Inflation by the vehicle radius: every voxel whose centre is within the radius of an occupied
// voxel's centre, checked exhaustively against the list of occupied voxels, after frames that
// occupy and free voxels and after the window has moved (queries read the occupied bits a column
// at a time and remember their answers until the map changes). Per window height: 8 voxels (a
// word of bits holds 8 columns, z wraps around the ring within a stencil), 64 (a column per word)
// and 256 (a column spans 4 words, runs cross them).
class VoxelMapInflation : public ::testing::TestWithParam<double> {};

TEST_P(VoxelMapInflation, MatchesBruteForceAlsoAfterChangesAndWindowMoves) {
  VoxelMapOptions o = Small();
  o.window_size_m.z() = GetParam();
  o.inflation_radius_m = 0.25;
  o.recenter_hysteresis_m = 0.0;  // every move below shifts all three axes
  VoxelMap map(o);
  // Returns in a layer at most 1.8 m thick around the sensor (denser rays free more voxels).
  const Vector3 sensor(0, 0, 0.5 * (map.window_min_W().z() + map.window_max_W().z()));
  const double half_layer = std::min(0.9, 0.5 * GetParam() - 0.05);
  const double z_lo = sensor.z() - half_layer, z_hi = sensor.z() + half_layer;
  Rng rng(4);
  const auto random_returns = [&] {
    std::vector<Eigen::Vector3f> pts;
    for (int k = 0; k < 300; ++k) pts.emplace_back(rng.Uniform(-5, 5), rng.Uniform(-5, 5), rng.Uniform(z_lo, z_hi));
    return pts;
  };
  map.Insert(sensor, random_returns());
  const auto check = [&](const char* when) {
    const std::vector<Vector3> occ = map.OccupiedVoxels();
    ASSERT_EQ(static_cast<int>(occ.size()), map.occupied_count()) << when;
    ASSERT_FALSE(occ.empty()) << when;
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
      // A segment within that voxel collides exactly when the voxel is inflated.
      ASSERT_EQ(map.SegmentCollides(c, c + Vector3(0.01, 0.0, 0.0)), truth) << when << " at " << p.transpose();
    }
  };
  check("after insertion");
  // Frames that free voxels and occupy others: other returns seen from another origin, so that
  // rays through earlier returns miss them.
  {
    const std::vector<Vector3> before = map.OccupiedVoxels();
    const std::vector<Eigen::Vector3f> moved = random_returns();
    for (int repeat = 0; repeat < 3; ++repeat) map.Insert(sensor + Vector3(0.3, -0.2, 0.05), moved);
    const std::vector<Vector3> after = map.OccupiedVoxels();
    const auto count_missing = [](const std::vector<Vector3>& from, const std::vector<Vector3>& in) {
      int missing = 0;
      for (const Vector3& v : from) {
        missing += std::none_of(in.begin(), in.end(), [&](const Vector3& w) { return (v - w).norm() < 1e-9; });
      }
      return missing;
    };
    ASSERT_GT(count_missing(before, after), 10) << "voxels freed";
    ASSERT_GT(count_missing(after, before), 10) << "voxels occupied";
  }
  check("after frames that freed and occupied voxels");
  const double h = GetParam();  // moves in z scaled to the window's height, so that part stays
  map.Recenter(sensor + Vector3(1.37, -0.82, 0.1 * h));
  check("after a small move");
  map.Recenter(sensor + Vector3(4.9, 3.1, -0.15 * h));
  check("after a larger move");
  map.MarkOccupied(sensor + Vector3(4.9, 3.1, -0.1 * h));
  check("after a voxel marked occupied");
  // A move of exactly one window along x: nothing stays, and every voxel takes the address of
  // one that was there before, whose remembered answers must be gone.
  std::vector<Vector3> inflated_before;
  for (const Vector3& v : map.OccupiedVoxels()) {
    if (map.IsInflated(v)) inflated_before.push_back(v);  // queried: in the memo
  }
  ASSERT_FALSE(inflated_before.empty());
  const double window_x = map.window_max_W().x() - map.window_min_W().x();
  // The centre voxel's centre (the window's centre is a voxel corner, which rounding may tip).
  const Vector3 centre = 0.5 * (map.window_min_W() + map.window_max_W()) + Vector3::Constant(0.05);
  map.Recenter(centre + Vector3(window_x, 0.0, 0.0));
  EXPECT_EQ(map.occupied_count(), 0) << "everything left";
  EXPECT_TRUE(map.OccupiedVoxels().empty());
  for (const Vector3& v : inflated_before) {
    const Vector3 same_address = v + Vector3(window_x, 0.0, 0.0);
    ASSERT_TRUE(map.InWindow(same_address));
    ASSERT_FALSE(map.IsInflated(same_address)) << same_address.transpose();
  }
}

INSTANTIATE_TEST_SUITE_P(WindowHeights, VoxelMapInflation, ::testing::Values(0.8, 4.0, 25.6));

// Hand-made cases for the queries' column runs (a word's end, the ring's wrap): one occupied voxel
// at each height of the window in turn, so at every position of its bit in a word and around the
// ring, and every voxel of the columns around it checked against the radius (2.5 voxels).
TEST_P(VoxelMapInflation, OneOccupiedVoxelAtEveryHeight) {
  VoxelMapOptions o;
  o.window_size_m = Vector3(1.6, 1.6, GetParam());
  o.recenter_hysteresis_m = 0.0;  // (at most a quarter of the window)
  o.inflation_radius_m = 0.25;
  const auto centre = [](const Vector3& lo, const Eigen::Vector3i& i) {
    return Vector3(lo + (i.cast<double>() + Vector3::Constant(0.5)) * 0.1);
  };
  const int height = VoxelMap(o).size_voxels().z();
  for (int oz = 0; oz < height; ++oz) {
    VoxelMap map(o);
    const Vector3 lo = map.window_min_W();
    const Eigen::Vector3i occupied(8, 8, oz);
    map.MarkOccupied(centre(lo, occupied));
    ASSERT_EQ(map.occupied_count(), 1);
    for (int x = 5; x <= 11; ++x) {
      for (int y = 5; y <= 11; ++y) {
        for (int z = 0; z < height; ++z) {
          const Eigen::Vector3i q(x, y, z);
          const bool truth = (q - occupied).cast<double>().norm() <= 2.5 + 1e-9;
          ASSERT_EQ(map.IsInflated(centre(lo, q)), truth) << "occupied z " << oz << ", query " << q.transpose();
        }
      }
    }
  }
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

// Whether the segment a-b meets the axis-aligned box [lo, hi] (slab clipping, Kay and Kajiya).
bool SegmentMeetsBox(const Vector3& a, const Vector3& b, const Vector3& lo, const Vector3& hi) {
  double s0 = 0.0, s1 = 1.0;
  for (int k = 0; k < 3; ++k) {
    const double d = b[k] - a[k];
    if (std::abs(d) < 1e-15) {
      if (a[k] < lo[k] || a[k] > hi[k]) return false;
      continue;
    }
    double u = (lo[k] - a[k]) / d, v = (hi[k] - a[k]) / d;
    if (u > v) std::swap(u, v);
    s0 = std::max(s0, u);
    s1 = std::min(s1, v);
  }
  return s0 <= s1;
}

/// The oracle's verdict on the voxel of centre c: +1 the segment surely crosses it, -1 surely not,
/// 0 within 1e-6 m of its boundary (either answer is right there).
int Crosses(const Vector3& a, const Vector3& b, const Vector3& c, double res) {
  const Vector3 half = Vector3::Constant(0.5 * res), eps = Vector3::Constant(1e-6);
  if (SegmentMeetsBox(a, b, c - half + eps, c + half - eps)) return 1;
  return SegmentMeetsBox(a, b, c - half - eps, c + half + eps) ? 0 : -1;
}

// The two tests below hold the ray walks to exact oracles, once per walk kernel.
class VoxelMapWalk : public ::testing::TestWithParam<VoxelMapOptions::WalkKernel> {};
INSTANTIATE_TEST_SUITE_P(Kernels, VoxelMapWalk,
                         ::testing::Values(VoxelMapOptions::WalkKernel::kAuto, VoxelMapOptions::WalkKernel::kPortable),
                         [](const ::testing::TestParamInfo<VoxelMapOptions::WalkKernel>& kernel) {
                           return kernel.param == VoxelMapOptions::WalkKernel::kAuto ? "Auto" : "Portable";
                         });

// The ray walk against an exact oracle: one ray into an empty map makes known exactly the voxels
// its segment crosses (clipped to the window, which sits off the origin so that its ring buffer
// wraps), for rays that end inside the window and rays that leave it.
TEST_P(VoxelMapWalk, ARayMarksExactlyTheVoxelsItsSegmentCrosses) {
  VoxelMapOptions o;
  o.walk_kernel = GetParam();
  o.window_size_m = Vector3(1.6, 1.6, 0.8);
  o.recenter_hysteresis_m = 0.0;
  Rng rng(7);
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    VoxelMap map(o);
    const Vector3 center(0.73, -0.41, 0.26);
    map.Recenter(center);
    const Vector3 from = center + Vector3(rng.Uniform(-0.7, 0.7), rng.Uniform(-0.7, 0.7), rng.Uniform(-0.3, 0.3));
    const Vector3 to = center + Vector3(rng.Uniform(-1.5, 1.5), rng.Uniform(-1.5, 1.5), rng.Uniform(-0.8, 0.8));
    const Eigen::Vector3f to_f = to.cast<float>();
    map.Insert(from, {to_f});
    const Vector3 end = to_f.cast<double>();
    for (double x = center.x() - 1.0; x < center.x() + 1.0; x += 0.1) {
      for (double y = center.y() - 1.0; y < center.y() + 1.0; y += 0.1) {
        for (double z = center.z() - 0.6; z < center.z() + 0.6; z += 0.1) {
          const Vector3 c = (Vector3(x, y, z) / 0.1).array().floor().matrix() * 0.1 + Vector3::Constant(0.05);
          if (!map.InWindow(c)) continue;
          const int verdict = Crosses(from, end, c, 0.1);
          if (verdict == 0) continue;
          ++checked;
          ASSERT_EQ(map.IsKnown(c), verdict > 0) << "trial " << trial << ", voxel at " << c.transpose();
        }
      }
    }
  }
  EXPECT_GT(checked, 300 * 1000);
}

// The collision query's walk, against the same oracle: segments that start and end anywhere,
// also outside the window and across its faces, collide exactly when they cross an occupied voxel
// (no inflation), and never through a voxel on the window's far side (the ring buffer's wrap).
TEST(VoxelMap, SegmentCollidesExactlyWhenItCrossesAnOccupiedVoxel) {
  VoxelMapOptions o;
  o.window_size_m = Vector3(1.6, 1.6, 0.8);
  o.recenter_hysteresis_m = 0.0;
  o.inflation_radius_m = 0.0;
  VoxelMap map(o);
  const Vector3 center(0.73, -0.41, 0.26);
  map.Recenter(center);
  // Occupied voxels near the window's faces and corners, and one inside.
  // (The window spans -0.83..0.77, -0.89..0.71 and -0.46..0.34 m about the centre.)
  const std::vector<Vector3> targets = {center + Vector3(-0.78, 0.1, 0.0), center + Vector3(0.72, -0.75, 0.3),
                                        center + Vector3(0.2, 0.68, -0.4), center + Vector3(0.1, 0.1, 0.05)};
  std::vector<Eigen::Vector3f> points;
  for (const Vector3& t : targets) points.push_back(t.cast<float>());
  map.Insert(center, points);
  ASSERT_EQ(map.occupied_count(), static_cast<int>(targets.size()));
  std::vector<Vector3> boxes;
  for (const Vector3& c : map.OccupiedVoxels()) boxes.push_back(c);
  Rng rng(11);
  int hits = 0, misses = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Vector3 a = center + Vector3(rng.Uniform(-1.5, 1.5), rng.Uniform(-1.5, 1.5), rng.Uniform(-0.8, 0.8));
    const Vector3 b = center + Vector3(rng.Uniform(-1.5, 1.5), rng.Uniform(-1.5, 1.5), rng.Uniform(-0.8, 0.8));
    int verdict = -1;
    for (const Vector3& c : boxes) verdict = std::max(verdict, Crosses(a, b, c, 0.1));
    if (verdict == 0) continue;
    ASSERT_EQ(map.SegmentCollides(a, b), verdict > 0) << "trial " << trial;
    (verdict > 0 ? hits : misses) += 1;
  }
  EXPECT_GT(hits, 200);
  EXPECT_GT(misses, 10000);
}

// The whole update against a plain reference model over many frames while the window moves:
// a map from each voxel to its log-odds (doubles), updated by the rule the map documents (each
// in-window return's voxel hit once; one ray per hit voxel, from its frame's first return there,
// and one per return outside the window; every voxel a ray's segment crosses, by the exact
// slab-clipping oracle, missed once unless hit; clamped; forgotten when it leaves the window).
// The map's shortcuts (settled-free voxels skipped, two rays walked at a time, the ring buffer's
// wrap) must not change a voxel's known or occupied state. Most points crowd a small region so
// that voxels go back and forth between hit and missed; the others cross the window's faces,
// where slots are reused as it moves.
void ExpectManyFramesToMatchTheReference(VoxelMapOptions::WalkKernel kernel, int clearing_stride) {
  SCOPED_TRACE("clearing_stride " + std::to_string(clearing_stride));
  VoxelMapOptions o;
  o.walk_kernel = kernel;
  o.clearing_stride = clearing_stride;
  o.window_size_m = Vector3(1.6, 1.6, 0.8);
  o.recenter_hysteresis_m = 0.0;
  o.log_odds_min = -0.8;  // two misses settle a voxel free, so the walk skips many
  VoxelMap map(o);
  using Key = std::array<int, 3>;
  const auto key_of = [](const Vector3& p) {
    return Key{static_cast<int>(std::floor(p.x() / 0.1)), static_cast<int>(std::floor(p.y() / 0.1)),
               static_cast<int>(std::floor(p.z() / 0.1))};
  };
  const auto center_of = [](const Key& k) -> Vector3 { return Vector3(k[0] + 0.5, k[1] + 0.5, k[2] + 0.5) * 0.1; };
  std::map<Key, double> reference;  // log-odds of the known voxels in the window
  std::set<Key> undecided;          // voxels a segment grazed within 1e-6 m: either answer is right
  Rng rng(21);
  int compared = 0, occupied_seen = 0;
  for (int frame = 0; frame < 60; ++frame) {
    // The window moves by a few voxels most frames.
    const Vector3 center(0.6 * std::sin(0.2 * frame), 0.5 * std::cos(0.15 * frame), 0.2 * std::sin(0.3 * frame));
    map.Recenter(center);
    const Vector3 lo = map.window_min_W(), hi = map.window_max_W();
    const auto in_window = [&](const Vector3& p) { return (p.array() >= lo.array()).all() && (p.array() < hi.array()).all(); };
    for (auto it = reference.begin(); it != reference.end();) {
      it = in_window(center_of(it->first)) ? std::next(it) : reference.erase(it);
    }
    const Vector3 origin = center + Vector3(rng.Uniform(-0.5, 0.5), rng.Uniform(-0.5, 0.5), rng.Uniform(-0.2, 0.2));
    std::vector<Eigen::Vector3f> points;
    for (int k = 0; k < 40; ++k) {
      const bool far = k % 3 == 2;  // some leave the window
      const double r = far ? 1.5 : 0.3;
      points.push_back((center + Vector3(rng.Uniform(-r, r), rng.Uniform(-r, r), rng.Uniform(-r / 2, r / 2))).cast<float>());
    }
    const MapUpdateSummary summary = map.Insert(origin, points);
    // The reference update.
    std::set<Key> hit;
    std::vector<Vector3> rays;
    for (const Eigen::Vector3f& pf : points) {
      const Vector3 p = pf.cast<double>();
      if (!in_window(p)) {
        rays.push_back(p);
      } else if (hit.insert(key_of(p)).second) {
        rays.push_back(p);
      }
    }
    // clearing_stride: the frame walks the rays of index = frame (mod stride).
    std::vector<Vector3> walked;
    for (std::size_t i = static_cast<std::size_t>(frame % clearing_stride); i < rays.size();
         i += static_cast<std::size_t>(clearing_stride)) {
      walked.push_back(rays[i]);
    }
    std::set<Key> missed;
    for (const Vector3& end : walked) {
      const Key a = key_of(lo + Vector3::Constant(0.05)), b = key_of(hi - Vector3::Constant(0.05));
      for (int x = a[0]; x <= b[0]; ++x) {
        for (int y = a[1]; y <= b[1]; ++y) {
          for (int z = a[2]; z <= b[2]; ++z) {
            const Key v{x, y, z};
            const int verdict = Crosses(origin, end, center_of(v), 0.1);
            if (verdict == 0) undecided.insert(v);
            if (verdict > 0 && !hit.count(v)) missed.insert(v);
          }
        }
      }
    }
    ASSERT_EQ(summary.rays_walked, static_cast<int>(walked.size())) << "frame " << frame;
    for (const Key& v : hit) reference[v] = std::min(o.log_odds_max, reference[v] + o.log_odds_hit);
    for (const Key& v : missed) reference[v] = std::max(o.log_odds_min, reference[v] + o.log_odds_miss);
    // Every voxel of the window, against the reference.
    const Key a = key_of(lo + Vector3::Constant(0.05)), b = key_of(hi - Vector3::Constant(0.05));
    for (int x = a[0]; x <= b[0]; ++x) {
      for (int y = a[1]; y <= b[1]; ++y) {
        for (int z = a[2]; z <= b[2]; ++z) {
          const Key v{x, y, z};
          if (undecided.count(v)) continue;
          const auto it = reference.find(v);
          const Vector3 c = center_of(v);
          ASSERT_EQ(map.IsKnown(c), it != reference.end()) << "frame " << frame << " at " << c.transpose();
          const bool occupied = it != reference.end() && it->second > o.occupied_threshold + 1e-9;
          ASSERT_EQ(map.IsOccupied(c), occupied) << "frame " << frame << " at " << c.transpose();
          ++compared;
          occupied_seen += occupied;
        }
      }
    }
    // The list of occupied voxels (the report's snapshots, kept as bits beside the cells): each
    // once, exactly the reference's occupied voxels up to the undecided.
    const std::vector<Vector3> listed_centers = map.OccupiedVoxels();
    std::set<Key> listed;
    for (const Vector3& c : listed_centers) listed.insert(key_of(c));
    ASSERT_EQ(listed.size(), listed_centers.size()) << "frame " << frame;
    ASSERT_EQ(static_cast<int>(listed.size()), map.occupied_count()) << "frame " << frame;
    for (const auto& [v, log_odds] : reference) {
      if (undecided.count(v)) continue;
      ASSERT_EQ(listed.count(v) == 1, log_odds > o.occupied_threshold + 1e-9) << "frame " << frame;
    }
    for (const Key& v : listed) {
      const auto it = reference.find(v);
      ASSERT_TRUE(undecided.count(v) || (it != reference.end() && it->second > o.occupied_threshold))
          << "frame " << frame << " at " << center_of(v).transpose();
    }
  }
  EXPECT_GT(compared, 60 * 2000);  // of the window's 16 x 16 x 8, all but the undecided
  EXPECT_GT(occupied_seen, 2000);
  EXPECT_LT(undecided.size(), 50u);
}

TEST_P(VoxelMapWalk, ManyFramesWithAMovingWindowMatchAPlainReferenceModel) {
  ExpectManyFramesToMatchTheReference(GetParam(), 1);
  ExpectManyFramesToMatchTheReference(GetParam(), 3);
}

// Nearest against a brute-force search over the list of occupied voxels, for radii that take the
// sorted-column path (up to 1.1 m at 0.1 m) and the cube scan beyond it: the same distance and the
// same voxel, of equally near ones the lowest index (x, then y, then z). A quarter of the queries
// lie on voxel corners or centres.
TEST(VoxelMap, NearestEqualsABruteForceSearch) {
  // At 0.1 m, and at 0.25 m, where centres and corners are exact in binary, so that the voxels
  // about a corner or a centre are exactly as near.
  for (const double res : {0.1, 0.25}) {
    VoxelMapOptions o = Small();
    o.resolution_m = res;
    VoxelMap map(o);
    Rng rng(9);
    for (int k = 0; k < 200; ++k) map.MarkOccupied(Vector3(rng.Uniform(-3, 3), rng.Uniform(-3, 3), rng.Uniform(0.2, 1.8)));
    const std::vector<Vector3> occupied = map.OccupiedVoxels();
    ASSERT_GT(occupied.size(), 150u);
    const auto index_of = [&](const Vector3& centre) { return Eigen::Vector3i((centre / res).array().floor().cast<int>()); };
    const auto lower = [](const Eigen::Vector3i& a, const Eigen::Vector3i& b) {
      return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
    };
    int found = 0, tied = 0;
    for (int k = 0; k < 2000; ++k) {
      Vector3 p(rng.Uniform(-3.5, 3.5), rng.Uniform(-3.5, 3.5), rng.Uniform(0.0, 2.0));
      if (k % 8 == 1) p = (p / res).array().round() * res;          // a corner
      if (k % 8 == 5) p = ((p / res).array().floor() + 0.5) * res;  // a centre
      const double radius = k % 4 == 3 ? 1.6 : rng.Uniform(0.0, 1.0);
      double truth = std::numeric_limits<double>::infinity();
      Eigen::Vector3i truth_index;
      int as_near = 0;
      for (const Vector3& c : occupied) {
        const double d = (c - p).norm();
        if (d > truth) continue;
        as_near = d < truth ? 1 : as_near + 1;
        if (d < truth || lower(index_of(c), truth_index)) truth_index = index_of(c);
        truth = d;
      }
      const auto n = map.Nearest(p, radius);
      if (truth > radius) {
        EXPECT_FALSE(n) << "nothing within " << radius << " of " << p.transpose();
        continue;
      }
      ASSERT_TRUE(n) << p.transpose();
      EXPECT_EQ(n->distance_m, truth);
      EXPECT_EQ(index_of(n->point_W), truth_index) << "at " << p.transpose() << ", " << as_near << " as near";
      EXPECT_NEAR((n->point_W - p).norm(), truth, 1e-12);
      ++found;
      tied += as_near > 1;
    }
    EXPECT_GT(found, 500) << res;
    if (res == 0.25) {
      EXPECT_GT(tied, 20) << "the queries on corners and centres meet ties";
    }
  }
}

// The AVX2 walk kernel against the portable one, which the tests above hold to exact oracles:
// the same frames into two maps, one per kernel, leave the same counts every frame, including the
// voxels each skipped as settled, and the same map (every voxel's known, occupied and inflated
// state) at a hand-made frame and every 8th LiDAR frame. The hand-made frame pins what random rays
// seldom meet: rays through voxel corners and edges from a voxel's centre (exact ties between the
// axes' boundaries, which the oracles leave undecided), and returns in the sensor's own voxel
// (walks of no step). The LiDAR's frames are a spinning sensor's in a forest, flown along a lane
// (some 8000 rays a frame, from a few voxels to beyond the window, which moves), so that the
// vector kernel's lanes finish and take rays in many orders, and go idle at the end of each batch.
TEST(VoxelMap, TheVectorWalkLeavesTheSameMapAsThePortableWalk) {
#if !defined(__AVX2__)
  GTEST_SKIP() << "this build has no AVX2 kernel (it targets no x86-64-v3)";
#endif
  VoxelMapOptions o = Small();
  VoxelMap vector_map(o);
  o.walk_kernel = VoxelMapOptions::WalkKernel::kPortable;
  VoxelMap portable_map(o);
  const auto compare_maps = [&](const std::string& when) {
    const Vector3 lo = vector_map.window_min_W();
    const Eigen::Vector3i n = vector_map.size_voxels();
    int differing = 0, known = 0;
    for (int x = 0; x < n.x(); ++x) {
      for (int y = 0; y < n.y(); ++y) {
        for (int z = 0; z < n.z(); ++z) {
          const Vector3 c = lo + (Vector3(x, y, z) + Vector3::Constant(0.5)) * 0.1;
          known += vector_map.IsKnown(c);
          differing += vector_map.IsKnown(c) != portable_map.IsKnown(c) ||
                       vector_map.IsOccupied(c) != portable_map.IsOccupied(c) ||
                       vector_map.IsInflated(c) != portable_map.IsInflated(c);
        }
      }
    }
    EXPECT_EQ(differing, 0) << when;
    return known;
  };
  const auto insert_both = [&](const Vector3& origin, const std::vector<Eigen::Vector3f>& points,
                               const std::string& when) {
    vector_map.Recenter(origin);
    portable_map.Recenter(origin);
    const MapUpdateSummary a = vector_map.Insert(origin, points), b = portable_map.Insert(origin, points);
    EXPECT_EQ(a.points_used, b.points_used) << when;
    EXPECT_EQ(a.voxels_traversed, b.voxels_traversed) << when;
    EXPECT_EQ(a.voxels_skipped, b.voxels_skipped) << when;
    EXPECT_EQ(a.voxels_updated, b.voxels_updated) << when;
    EXPECT_EQ(vector_map.occupied_count(), portable_map.occupied_count()) << when;
    return a;
  };
  // Hand-made frames from voxel centres whose coordinates, and the returns', are exact in float
  // and in voxel units (multiples of 0.25 m): a return at (2, 2, 0) quarter-metres crosses an x
  // and a y boundary at the same parameter, to the bit, at each corner, (2, 2, 2) all three; some
  // returns lie on voxel faces. Returns in the neighbouring voxels make walks of a few steps, one
  // in the sensor's own voxel a walk of none.
  const std::vector<Vector3> origins = {Vector3(0.25, -0.75, 1.25), Vector3(-0.25, 0.25, 0.75),
                                        Vector3(0.75, 0.75, 1.75), Vector3(-1.25, -0.25, 1.25)};
  for (std::size_t f = 0; f < origins.size(); ++f) {
    const Vector3& origin = origins[f];
    std::vector<Eigen::Vector3f> points{(origin + Vector3(0.01, -0.02, 0.03)).cast<float>()};
    for (int i = -6; i <= 6; ++i) {
      for (int j = -6; j <= 6; ++j) {
        for (int k = -4; k <= 4; ++k) points.push_back((origin + 0.25 * Vector3(i, j, k)).cast<float>());
      }
    }
    for (int i = -1; i <= 1; ++i) {
      for (int j = -1; j <= 1; ++j) {
        for (int k = -1; k <= 1; ++k) points.push_back((origin + 0.1 * Vector3(i, j, k)).cast<float>());
      }
    }
    const std::string when = "hand-made frame " + std::to_string(f);
    EXPECT_GT(insert_both(origin, points, when).voxels_traversed, 10000) << when;
    EXPECT_GT(compare_maps(when), 2000) << when;
  }
  Rng rng(17);
  sim::World forest;
  while (forest.cylinders.size() < 150) {
    const sim::Cylinder c{Eigen::Vector2d(rng.Uniform(-8, 8), rng.Uniform(-6, 6)), rng.Uniform(0.05, 0.3),
                          rng.Uniform(1, 6)};
    if (std::abs(c.center_m.y()) - c.radius_m > 1.0) forest.cylinders.push_back(c);
  }
  sim::LidarOptions lidar_options;
  lidar_options.enabled = true;
  sim::LidarSimulator lidar(lidar_options, forest, 3);
  const auto pose_at = [](TimeNs t) {
    const double s = ToSeconds(t);
    sim::BodyPose p;
    p.p_W = Vector3(-6.0 + 1.5 * s, 0.3 * std::sin(s), 1.2 + 0.2 * std::sin(0.7 * s));
    p.q_WB = Quaternion(Eigen::AngleAxisd(11.0 * s, Vector3::UnitZ()) * Eigen::AngleAxisd(0.2, Vector3::UnitX()));
    return p;
  };
  TimeNs t = 0;
  long steps = 0, skipped = 0;
  for (int frame = 0; frame < 40; ++frame) {
    std::optional<LidarFrame> f;
    while (!f) {
      f = lidar.Step(t, pose_at(t), t + 1'000'000, pose_at(t + 1'000'000));
      t += 1'000'000;
    }
    std::vector<Eigen::Vector3f> points;
    for (std::size_t i = 0; i < f->points_S.size(); ++i) {
      const sim::BodyPose p = pose_at(f->t_start_ns + f->offset_ns[i]);
      points.push_back((p.p_W + p.q_WB * (lidar_options.position_m + f->points_S[i].cast<double>())).cast<float>());
    }
    const sim::BodyPose end = pose_at(f->t_end_ns);
    const std::string when = "frame " + std::to_string(frame);
    const MapUpdateSummary s = insert_both(end.p_W + end.q_WB * lidar_options.position_m, points, when);
    steps += s.voxels_traversed;
    skipped += s.voxels_skipped;
    if (frame % 8 == 7) {
      EXPECT_GT(compare_maps(when), 100000) << when;
    }
  }
  EXPECT_GT(steps, 40L * 100000);
  EXPECT_GT(skipped, steps / 2);  // settled voxels were skipped, by both
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

// The window (12.8 m along x: [-6.4, 6.4) m) follows its centre along an axis only beyond the
// hysteresis (0.5 m), and then onto the centre.
TEST(VoxelMap, TheWindowFollowsAnAxisOnlyBeyondTheHysteresis) {
  VoxelMap map(Small());
  map.Recenter(Vector3(0.45, -0.45, 0.45));  // within 0.5 m on every axis: no move
  EXPECT_TRUE(map.InWindow(Vector3(-6.35, -6.35, 0.0)));
  EXPECT_FALSE(map.InWindow(Vector3(6.45, 0.0, 0.0)));
  map.Recenter(Vector3(0.65, -0.45, 0.0));  // x moves onto 0.6 (origin -5.8 m), y stays
  EXPECT_FALSE(map.InWindow(Vector3(-5.85, 0.0, 0.0)));
  EXPECT_TRUE(map.InWindow(Vector3(-5.75, 0.0, 0.0)));
  EXPECT_TRUE(map.InWindow(Vector3(6.95, 0.0, 0.0)));
  EXPECT_TRUE(map.InWindow(Vector3(0.0, -6.35, 0.0))) << "y within the hysteresis";
  map.Recenter(Vector3(0.2, 0.0, 0.0));  // back by 0.4 m along x: no move
  EXPECT_TRUE(map.InWindow(Vector3(6.95, 0.0, 0.0)));
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
  o = {};
  o.window_size_m = Vector3(1.6, 1.6, 0.8);  // the default hysteresis (0.5 m) exceeds 0.8 / 4
  try {
    o.Validate();
    ADD_FAILURE();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "recenter_hysteresis_m");
  }
  for (const int stride : {0, VoxelMapOptions::kMaxClearingStride + 1}) {
    o = {};
    o.clearing_stride = stride;
    RG_EXPECT_THROW_WITH(o.Validate(), ValidationError, "clearing_stride = " + std::to_string(stride));
  }
}

}  // namespace
}  // namespace rotorguard::perception
