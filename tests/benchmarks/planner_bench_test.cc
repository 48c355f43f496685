#include "rotorguard/campaign_kinds/planner_bench.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "rotorguard/benchmarks/free_space_bench.h"
#include "rotorguard/harness/world_raster.h"

namespace rotorguard::benchmarks {
namespace {

// The rasterised map against the world: every occupied voxel's centre lies within half a voxel
// diagonal of an obstacle, and every voxel centre deeper than that inside one is occupied.
TEST(PlannerBench, RasterizedMapMatchesTheWorld) {
  const sim::World world = PlannerRoom(3);
  perception::VoxelMapOptions o;
  o.window_size_m = Vector3(12, 12, 6);
  perception::VoxelMap map(o);
  harness::RasterizeWorld(world, &map);
  const double half_diagonal = 0.5 * std::sqrt(3.0) * 0.1;
  const std::vector<Vector3> occupied = map.OccupiedVoxels();
  ASSERT_GT(occupied.size(), 10000u);
  for (const Vector3& c : occupied) ASSERT_LE(world.DistanceToObstacles(c, 0.0), half_diagonal + 1e-9) << c.transpose();
  // Inside: 0.05 m into the walls' and furniture's interior along a grid of probes.
  int inside = 0;
  for (double x = -5.45; x < 5.5; x += 0.1) {
    for (double y = -4.45; y < 4.5; y += 0.1) {
      for (double z = 0.05; z < 3.0; z += 0.3) {
        const Vector3 p(x, y, z);
        bool deep = false;
        for (const sim::Box& b : world.boxes) {
          // Inside the box shrunk by a voxel along each axis (its own frame).
          const Eigen::Vector2d r = Eigen::Rotation2Dd(-b.yaw_rad) * (p - b.center_m).head<2>();
          deep |= std::abs(r.x()) < 0.5 * b.size_m.x() - 0.1 && std::abs(r.y()) < 0.5 * b.size_m.y() - 0.1 &&
                  std::abs(p.z() - b.center_m.z()) < 0.5 * b.size_m.z() - 0.1;
        }
        if (!deep) continue;
        ++inside;
        ASSERT_TRUE(map.IsOccupied(p)) << p.transpose();
      }
    }
  }
  EXPECT_GT(inside, 500);
}

// A small run: every group is there with its figures, the limits are eq. (33)'s, and plans in the
// room succeed.
TEST(PlannerBench, SmallRunReportsEveryGroup) {
  PlannerBenchOptions o;
  o.pairs = 3;
  o.worlds = 1;
  const nlohmann::json r = RunPlannerBenchmark(o);
  for (const char* g : {"forest_nominal", "forest_post_failure", "room_nominal", "room_post_failure"}) {
    ASSERT_TRUE(r["groups"].contains(g)) << g;
    const nlohmann::json& x = r["groups"][g];
    EXPECT_EQ(x["pairs"].get<int>(), 3) << g;
    for (const char* k : {"plan_ms_mean", "plan_ms_p99", "success_rate", "mean_traj_duration_s", "max_limit_violation"}) {
      EXPECT_TRUE(x.contains(k)) << g << "." << k;
      EXPECT_TRUE(std::isfinite(x[k].get<double>())) << g << "." << k;
    }
  }
  EXPECT_EQ(r["pairs"].get<int>(), 12);
  EXPECT_LT(r["limits_post_failure"]["a_max"].get<double>(), r["limits_nominal"]["a_max"].get<double>());
  EXPECT_GE(r["groups"]["room_nominal"]["success_rate"].get<double>(), 2.0 / 3.0);
  EXPECT_NE(PlannerMarkdown(r).find("room_post_failure"), std::string::npos);
  // The fallbacks are counted among the successes, never beyond them.
  for (const char* k : {"plans_fine_search", "plans_rest_to_rest"}) {
    ASSERT_TRUE(r.contains(k)) << k;
    EXPECT_GE(r[k].get<int>(), 0) << k;
    EXPECT_LE(r[k].get<double>(), r["success_rate"].get<double>() * r["pairs"].get<int>() + 1e-9) << k;
  }
}

TEST(PlannerBench, BadOptionsAreNamed) {
  PlannerBenchOptions o;
  o.worlds = 0;
  try {
    RunPlannerBenchmark(o);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("worlds"), std::string::npos) << e.what();
  }
}

// The free-space problems as defined: every point in the 20 x 20 x 2 m box, each step 1.5-4 m,
// each initial duration the step's length at v_max = 1 m/s; the same problem for the same
// arguments and another for another index; and a small run reports one record per size.
TEST(FreeSpaceBench, ProblemsFollowTheirDefinition) {
  for (const int pieces : {1, 5, 10}) {
    for (int index = 0; index < 50; ++index) {
      const FreeSpaceProblem p = DrawFreeSpaceProblem(pieces, 7, index);
      ASSERT_EQ(p.points.cols(), pieces + 1);
      ASSERT_EQ(p.durations.size(), pieces);
      for (int i = 0; i <= pieces; ++i) {
        const Vector3 q = p.points.col(i);
        EXPECT_TRUE(q.x() >= -10 && q.x() <= 10 && q.y() >= -10 && q.y() <= 10 && q.z() >= 0 && q.z() <= 2)
            << q.transpose();
      }
      for (int i = 0; i < pieces; ++i) {
        const double step = (p.points.col(i + 1) - p.points.col(i)).norm();
        EXPECT_GE(step, 1.5 - 1e-12);
        EXPECT_LE(step, 4.0 + 1e-12);
        EXPECT_NEAR(p.durations(i), step / FreeSpaceLimits().v_max, 1e-12);
      }
    }
    EXPECT_EQ(DrawFreeSpaceProblem(pieces, 7, 3).points, DrawFreeSpaceProblem(pieces, 7, 3).points);
    EXPECT_NE(DrawFreeSpaceProblem(pieces, 7, 3).points, DrawFreeSpaceProblem(pieces, 7, 4).points);
  }
  FreeSpaceBenchOptions o;
  o.pieces = {2, 3};
  o.problems = 3;
  o.evaluations = 2;
  const nlohmann::json r = RunFreeSpaceBenchmark(o);
  ASSERT_EQ(r["free_space"].size(), 2u);
  for (const nlohmann::json& size : r["free_space"]) {
    EXPECT_EQ(size["failed"].get<int>(), 0);
    // The time weight is 10: the cost holds 10 T, T the optimised duration, which the dense check
    // stretches by a few percent at most.
    EXPECT_GT(size["cost_mean"].get<double>(), 0.9 * 10.0 * size["duration_s_mean"].get<double>());
  }
  o.pieces = {0};
  EXPECT_THROW(RunFreeSpaceBenchmark(o), std::invalid_argument);
}

}  // namespace
}  // namespace rotorguard::benchmarks
