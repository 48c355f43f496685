#include "rotorguard/sim/raycast.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "rotorguard/core/rng.h"

namespace rotorguard::sim {
namespace {

/// The oracle of the indices: the nearest hit of the ground and of every obstacle of `w` (the
/// moving boxes where they are at time t), each tested in turn.
std::optional<RayHit> CastByTestingEverything(const World& w, const Vector3& o, const Vector3& d, double max_m,
                                              double t) {
  std::optional<RayHit> best = IntersectGround(o, d, max_m);
  const auto keep = [&](const std::optional<RayHit>& h) {
    if (h && (!best || h->distance_m < best->distance_m)) best = h;
  };
  for (const Box& b : w.boxes) keep(IntersectBox(b, o, d, max_m));
  for (const Cylinder& c : w.cylinders) keep(IntersectCylinder(c, o, d, max_m));
  for (const MovingBox& m : w.moving_boxes) keep(IntersectBox(m.At(t), o, d, max_m));
  return best;
}

// Closed forms.
TEST(Raycast, GroundBoxAndCylinderAgainstClosedForms) {
  const Vector3 diag = Vector3(1, 0, -1).normalized();
  ASSERT_TRUE(IntersectGround(Vector3(0, 0, 2), diag, 10.0));
  EXPECT_NEAR(IntersectGround(Vector3(0, 0, 2), diag, 10.0)->distance_m, 2.0 * std::sqrt(2.0), 1e-12);
  EXPECT_FALSE(IntersectGround(Vector3(0, 0, 2), diag, 2.0)) << "beyond the range";
  EXPECT_FALSE(IntersectGround(Vector3(0, 0, 2), Vector3::UnitX(), 10.0)) << "parallel";

  const Box box{Vector3(0, 0, 0.5), Vector3(2, 2, 1), 0.0};
  const auto hb = IntersectBox(box, Vector3(-5, 0, 0.5), Vector3::UnitX(), 10.0);
  ASSERT_TRUE(hb);
  EXPECT_NEAR(hb->distance_m, 4.0, 1e-12);
  EXPECT_NEAR((hb->normal_W - Vector3(-1, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_FALSE(IntersectBox(box, Vector3(0, 0, 0.5), Vector3::UnitX(), 10.0)) << "from inside";
  EXPECT_FALSE(IntersectBox(box, Vector3(-5, 0, 1.5), Vector3::UnitX(), 10.0)) << "above it";
  // A box yawed by 45 degrees, hit face-on along its rotated x axis: distance to the face.
  const Box yawed{Vector3::Zero(), Vector3(2, 2, 2), std::numbers::pi / 4};
  const Vector3 along = Vector3(1, 1, 0).normalized();
  const auto hy = IntersectBox(yawed, -5.0 * along, along, 10.0);
  ASSERT_TRUE(hy);
  EXPECT_NEAR(hy->distance_m, 4.0, 1e-12);
  EXPECT_NEAR((hy->normal_W + along).norm(), 0.0, 1e-12);

  const Cylinder tree{Eigen::Vector2d(0, 0), 0.5, 3.0};
  const auto hs = IntersectCylinder(tree, Vector3(-5, 0, 1), Vector3::UnitX(), 10.0);
  ASSERT_TRUE(hs);
  EXPECT_NEAR(hs->distance_m, 4.5, 1e-12);
  EXPECT_NEAR((hs->normal_W - Vector3(-1, 0, 0)).norm(), 0.0, 1e-12);
  // Off-centre: the chord's near end, sqrt(r^2 - y^2) before the axis.
  const auto ho = IntersectCylinder(tree, Vector3(-5, 0.3, 1), Vector3::UnitX(), 10.0);
  ASSERT_TRUE(ho);
  EXPECT_NEAR(ho->distance_m, 5.0 - std::sqrt(0.25 - 0.09), 1e-12);
  const auto hc = IntersectCylinder(tree, Vector3(0.1, 0, 5), -Vector3::UnitZ(), 10.0);
  ASSERT_TRUE(hc);
  EXPECT_NEAR(hc->distance_m, 2.0, 1e-12);
  EXPECT_NEAR((hc->normal_W - Vector3::UnitZ()).norm(), 0.0, 1e-12);
  EXPECT_FALSE(IntersectCylinder(tree, Vector3(-5, 0, 4), Vector3::UnitX(), 10.0)) << "over the top";
  EXPECT_FALSE(IntersectCylinder(tree, Vector3(0, 0, 1), Vector3::UnitX(), 10.0)) << "from inside";
}

TEST(Raycast, AWorldWhoseGroundLiesBelowZeroIsCastAgainstThatGround) {
  // The vehicle's frame: z = 0 where its centre of gravity rests, the ground 5 cm below; a trunk
  // stands on that ground, a box where its file puts it.
  World w;
  w.ground_z_m = -0.05;
  w.cylinders.push_back(Cylinder{Eigen::Vector2d(3, 0), 0.5, 3.0});
  w.boxes.push_back(Box{Vector3(0, 3, 1.0), Vector3(1, 1, 1), 0.0});
  RayCaster caster(w);
  const auto down = caster.Cast(Vector3(0, 0, 1), -Vector3::UnitZ(), 10.0, 0.0);
  ASSERT_TRUE(down);
  EXPECT_NEAR(down->distance_m, 1.05, 1e-12);
  // The trunk's foot, below z = 0: hit 2.5 m away.
  const auto foot = caster.Cast(Vector3(0, 0, -0.03), Vector3::UnitX(), 10.0, 0.0);
  ASSERT_TRUE(foot);
  EXPECT_NEAR(foot->distance_m, 2.5, 1e-12);
  // Its top at z = 3, as written: a ray over it at 3.01 goes on to nothing.
  EXPECT_FALSE(caster.Cast(Vector3(0, 0, 3.01), Vector3::UnitX(), 10.0, 0.0));
  // The box, from z = 0.5 to 1.5 as written.
  const auto box = caster.Cast(Vector3(0, 0, 1.4), Vector3::UnitY(), 10.0, 0.0);
  ASSERT_TRUE(box);
  EXPECT_NEAR(box->distance_m, 2.5, 1e-12);
  EXPECT_FALSE(caster.Cast(Vector3(0, 0, 1.6), Vector3::UnitY(), 10.0, 0.0));
  // The distance functions agree: the ground 0.05 below z = 0, the trunk's foot 2.5 m away.
  EXPECT_NEAR(w.DistanceToSurface(Vector3(0, 0, 0), 0.0), 0.05, 1e-12);
  EXPECT_NEAR(w.DistanceToObstacles(Vector3(0, 0, -0.03), 0.0), 2.5, 1e-12);  // the box: hypot(2.5, 0.53)
}

// Against an independent truth: marching along the ray with the obstacles' distance functions
// (world.h), then bisecting the first step that enters one. Random boxes, cylinders and rays.
TEST(Raycast, HitsAgreeWithDistanceFunctionMarching) {
  Rng rng(5);
  int hits = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Box box{Vector3(rng.Uniform(-2, 2), rng.Uniform(-2, 2), rng.Uniform(0.5, 2)),
                  Vector3(rng.Uniform(0.2, 2), rng.Uniform(0.2, 2), rng.Uniform(0.2, 2)), rng.Uniform(-3, 3)};
    const Cylinder cyl{Eigen::Vector2d(rng.Uniform(-2, 2), rng.Uniform(-2, 2)), rng.Uniform(0.05, 1), rng.Uniform(0.5, 4)};
    const Vector3 o(rng.Uniform(-6, 6), rng.Uniform(-6, 6), rng.Uniform(0.1, 5));
    for (int which = 0; which < 2; ++which) {
      // Aimed near the obstacle's centre: hits, grazes and misses.
      const Vector3 centre = which == 0 ? box.center_m : Vector3(cyl.center_m.x(), cyl.center_m.y(), 0.5 * cyl.height_m);
      const Vector3 target = centre + Vector3(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1));
      const Vector3 d = (target - o).normalized();
      // Above the ground only (the world's solids stand on it).
      const double range = d.z() < 0.0 ? std::min(20.0, -o.z() / d.z()) : 20.0;
      const auto dist = [&](const Vector3& p) { return which == 0 ? box.Distance(p) : cyl.Distance(p); };
      if (dist(o) == 0.0) continue;  // starts inside
      const auto hit = which == 0 ? IntersectBox(box, o, d, range) : IntersectCylinder(cyl, o, d, range);
      // Sphere tracing: steps of the distance itself never skip a surface.
      double t = 0.0;
      bool entered = false;
      while (t < range) {
        const double s = dist(o + t * d);
        if (s < 1e-9) {
          entered = true;
          break;
        }
        t += s;
      }
      ASSERT_EQ(hit.has_value(), entered) << "trial " << trial << " obstacle " << which;
      if (!hit) continue;
      ++hits;
      EXPECT_NEAR(hit->distance_m, t, 1e-6) << "trial " << trial << " obstacle " << which;
      EXPECT_LT(hit->normal_W.dot(d), 1e-12) << "the normal faces the ray";
      EXPECT_NEAR(hit->normal_W.norm(), 1.0, 1e-12);
    }
  }
  EXPECT_GT(hits, 250) << "most rays aim at the obstacles";
}

// The boxes' grid and the trees' azimuth index (rebuilt for each ray's new origin) find exactly
// what testing every obstacle finds, in a 500-tree forest with boxes.
// The indices' cast equals the oracle to the bit, distance and normal, with either cylinder kernel
// (the AVX2 one tests four trunks at once, in the same operations as IntersectCylinder).
class RaycastKernels : public ::testing::TestWithParam<RayCasterOptions::CylinderKernel> {
 protected:
  RayCasterOptions Options(double cell_m) const {
    RayCasterOptions o;
    o.cell_size_m = cell_m;
    o.cylinder_kernel = GetParam();
    return o;
  }
};

void ExpectSameHit(const std::optional<RayHit>& got, const std::optional<RayHit>& expected, int k) {
  ASSERT_EQ(got.has_value(), expected.has_value()) << k;
  if (!got) return;
  ASSERT_EQ(got->distance_m, expected->distance_m) << k;
  ASSERT_EQ(got->normal_W, expected->normal_W) << k;
}

TEST_P(RaycastKernels, IndicesMatchBruteForceInAForest) {
  Rng rng(9);
  World w;
  for (int i = 0; i < 500; ++i) {
    w.cylinders.push_back({Eigen::Vector2d(rng.Uniform(-15, 15), rng.Uniform(-10, 10)), rng.Uniform(0.05, 0.4),
                           rng.Uniform(2, 8)});
  }
  for (int i = 0; i < 20; ++i) {
    w.boxes.push_back({Vector3(rng.Uniform(-15, 15), rng.Uniform(-10, 10), rng.Uniform(0, 2)),
                       Vector3(rng.Uniform(0.3, 3), rng.Uniform(0.3, 3), rng.Uniform(0.3, 3)), rng.Uniform(-3, 3)});
  }
  MovingBox mover;
  mover.size_m = Vector3(1, 1, 1);
  mover.waypoints_m = {Vector3(-5, 0, 1), Vector3(5, 0, 1)};
  mover.speed_m_s = 1.0;
  w.moving_boxes.push_back(mover);
  RayCaster caster(w, Options(0.7));
  int hits = 0;
  for (int k = 0; k < 20000; ++k) {
    const Vector3 o(rng.Uniform(-20, 20), rng.Uniform(-14, 14), rng.Uniform(0.2, 3));
    const double az = rng.Uniform(-std::numbers::pi, std::numbers::pi), el = rng.Uniform(-0.5, 1.0);
    const Vector3 d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const double t = rng.Uniform(0, 20);
    const std::optional<RayHit> brute = CastByTestingEverything(w, o, d, 40.0, t);
    const auto grid = caster.Cast(o, d, 40.0, t);
    ExpectSameHit(grid, brute, k);
    if (grid) ++hits;
  }
  EXPECT_GT(hits, 10000);
}

// The same truth for a LiDAR's rays: origins that drift along a lane and circle a spinning mount
// (the azimuth index reused within its margin and rebuilt beyond it), rays in every direction
// including straight up and down and ones that graze a trunk's edge, and origins inside a trunk's
// padded disc, over the top of a trunk and inside a trunk.
TEST_P(RaycastKernels, AzimuthIndexMatchesBruteForceAlongAFlight) {
  Rng rng(21);
  World w;
  for (int i = 0; i < 300; ++i) {
    w.cylinders.push_back(
        {Eigen::Vector2d(rng.Uniform(-15, 15), rng.Uniform(-10, 10)), rng.Uniform(0.05, 0.4), rng.Uniform(1, 6)});
  }
  w.cylinders.push_back({Eigen::Vector2d(0.3, 0.1), 0.2, 1.0});  // the lane passes over and through it
  w.boxes.push_back({Vector3(3, -2, 1), Vector3(1, 2, 2), 0.4});
  RayCasterOptions options = Options(1.0);
  options.azimuth_bins = 64;  // coarse bins: many trunks per bin, the nearest-first cut-off matters
  RayCaster caster(w, options);
  int hits = 0, grazing = 0;
  for (int k = 0; k < 40000; ++k) {
    const double s = 1e-3 * k;  // 40 m of lane, a ray every millimetre
    const Vector3 centre(-20.0 + s, 0.1 + 0.3 * std::sin(0.2 * s), 0.5 + 0.01 * s);
    const Vector3 o = centre + 0.1 * Vector3(std::cos(11.0 * s), std::sin(11.0 * s), 0.0);
    Vector3 d;
    if (k % 97 == 0) {
      d = (k % 194 == 0 ? 1.0 : -1.0) * Vector3::UnitZ();
    } else if (k % 5 == 0) {
      // Aimed at a trunk's silhouette edge: the tangent from o, turned by a hair either way.
      const Cylinder& c = w.cylinders[static_cast<std::size_t>(rng.NextU64() % 301)];
      const Eigen::Vector2d v = c.center_m - o.head<2>();
      if (v.norm() <= c.radius_m) continue;
      const double a = std::asin(c.radius_m / v.norm()) * (1.0 + rng.Uniform(-1e-9, 1e-9));
      const double phi = std::atan2(v.y(), v.x()) + (rng.Uniform() < 0.5 ? a : -a);
      d = Vector3(std::cos(phi), std::sin(phi), rng.Uniform(-0.1, 0.3)).normalized();
      ++grazing;
    } else {
      const double az = rng.Uniform(-std::numbers::pi, std::numbers::pi), el = rng.Uniform(-0.6, 1.2);
      d = Vector3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    }
    const auto expected = CastByTestingEverything(w, o, d, 40.0, 0.0);
    const auto got = caster.Cast(o, d, 40.0, 0.0);
    ExpectSameHit(got, expected, k);
    if (got) ++hits;
  }
  EXPECT_GT(hits, 20000);
  EXPECT_GT(grazing, 7000);
  // Rebuilt about once per margin of travel (40 m of lane, 0.25 m margin, the mount's circle on top).
  EXPECT_GT(caster.index_rebuilds(), 40);
  EXPECT_LT(caster.index_rebuilds(), 1000);
}

// Hand-made edges of the bin walk, closed forms exact in binary: a trunk at (10, 0) of radius 0.5
// meets the ray from x = -5 along +x at 14.5 (b = -30, disc = 1). Its bin holds one trunk, so
// three lanes of its quad are padding, one of them a zero-size trunk at the origin on the ray.
TEST_P(RaycastKernels, ExactEdgesOfTheBinWalk) {
  World w;
  w.cylinders.push_back({Eigen::Vector2d(10, 0), 0.5, 5.0});
  RayCaster caster(w, Options(1.0));
#if defined(__AVX2__) && defined(__FMA__)
  EXPECT_EQ(caster.vector_kernel(), GetParam() == RayCasterOptions::CylinderKernel::kAuto);
#else
  EXPECT_FALSE(caster.vector_kernel());
#endif
  const Vector3 along_x = Vector3::UnitX();
  // An unbounded range: the padding lanes lie within every reach limit and must still miss.
  const auto unbounded = caster.Cast(Vector3(-5, 0, 0), along_x, std::numeric_limits<double>::infinity(), 0.0);
  ASSERT_TRUE(unbounded);
  EXPECT_EQ(unbounded->distance_m, 14.5);
  EXPECT_EQ(unbounded->normal_W, Vector3(-1, 0, 0));
  // A hit at exactly the range counts when nothing nearer was hit (IntersectCylinder's t <= max).
  const auto at_range = caster.Cast(Vector3(-5, 0, 1), along_x, 14.5, 0.0);
  ASSERT_TRUE(at_range);
  EXPECT_EQ(at_range->distance_m, 14.5);
  EXPECT_FALSE(caster.Cast(Vector3(-5, 0, 1), along_x, std::nextafter(14.5, 0.0), 0.0));
  // Each ray tested the one trunk (its travel bound, 15 - 0.5 - 0.25 m, lies within every range
  // above), and no padding.
  EXPECT_EQ(caster.cylinder_tests(), 3);
}

INSTANTIATE_TEST_SUITE_P(Kernels, RaycastKernels,
                         ::testing::Values(RayCasterOptions::CylinderKernel::kAuto,
                                           RayCasterOptions::CylinderKernel::kPortable),
                         [](const ::testing::TestParamInfo<RayCasterOptions::CylinderKernel>& kernel) {
                           return kernel.param == RayCasterOptions::CylinderKernel::kAuto ? "Auto" : "Portable";
                         });

// Two trunks mirrored across the ray meet it at the same distance with mirrored normals: the
// kernels keep the same one (the first in the bin), as the one-at-a-time loop does.
TEST(Raycast, KernelsBreakTiesAlike) {
  World w;
  for (const double y : {0.3, -0.3}) w.cylinders.push_back({Eigen::Vector2d(10, y), 0.5, 5.0});
  RayCasterOptions portable;
  portable.cylinder_kernel = RayCasterOptions::CylinderKernel::kPortable;
  RayCaster loop(w, portable), vector(w, RayCasterOptions{});
  const Vector3 o(-5, 0, 1);
  const auto expected = loop.Cast(o, Vector3::UnitX(), 40.0, 0.0);
  const auto got = vector.Cast(o, Vector3::UnitX(), 40.0, 0.0);
  ASSERT_TRUE(expected);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->distance_m, expected->distance_m);
  EXPECT_EQ(got->normal_W, expected->normal_W);
  EXPECT_NE(expected->normal_W.y(), 0.0);  // a real tie: either trunk's normal leans its own way
  // Both trunks give this distance: the tie is exact.
  EXPECT_EQ(IntersectCylinder(w.cylinders[0], o, Vector3::UnitX(), 40.0)->distance_m,
            IntersectCylinder(w.cylinders[1], o, Vector3::UnitX(), 40.0)->distance_m);
}

// The walk stops once a rising ray is above the tallest obstacle, box or cylinder alike: rays that
// rise to just below the top of the tallest still hit it (closed form: the face's distance along
// the ray), and rays just above it pass.
TEST(Raycast, RisingRaysHitTheTallestObstacleNearItsTop) {
  for (const bool box_tallest : {true, false}) {
    SCOPED_TRACE(box_tallest ? "a box is the tallest" : "a cylinder is the tallest");
    World w;
    w.cylinders.push_back({Eigen::Vector2d(-6, 3), 0.2, box_tallest ? 2.0 : 9.0});  // to the left, out of the way
    w.boxes.push_back({Vector3(-6, -3, 1), Vector3(1, 1, 2), 0.0});
    // The target: its near face at x = 9.5, top at z = 9.
    if (box_tallest) {
      w.boxes.push_back({Vector3(10, 0, 4.5), Vector3(1, 4, 9), 0.0});
    } else {
      w.cylinders.push_back({Eigen::Vector2d(10, 0), 0.5, 9.0});
    }
    RayCaster caster(w, RayCasterOptions{1.0});
    const Vector3 o(0, 0, 1);
    for (const double z_at_face : {8.99, 9.01}) {
      const Vector3 d = Vector3(9.5, 0, z_at_face - 1.0).normalized();
      const auto hit = caster.Cast(o, d, 40.0, 0.0);
      if (z_at_face < 9.0) {
        ASSERT_TRUE(hit);
        EXPECT_NEAR(hit->distance_m, std::hypot(9.5, z_at_face - 1.0), 1e-9);
      } else {
        EXPECT_FALSE(hit) << "over the top";
      }
    }
  }
}

TEST(Raycast, RejectsBadOptions) {
  EXPECT_THROW(RayCaster(World{}, RayCasterOptions{0.0}), std::invalid_argument);
  RayCasterOptions bins;
  bins.azimuth_bins = 4;
  EXPECT_THROW(RayCaster(World{}, bins), std::invalid_argument);
  RayCasterOptions margin;
  margin.azimuth_margin_m = 0.0;
  EXPECT_THROW(RayCaster(World{}, margin), std::invalid_argument);
}

}  // namespace
}  // namespace rotorguard::sim
