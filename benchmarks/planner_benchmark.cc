// The trajectory optimiser of the planner (MINCO s = 3 + the planner's L-BFGS) on 10-piece problems.
// BM_OptimizeFreeSpace: 20 m rest to rest, waypoints and durations optimised under v/a/j limits.
// BM_OptimizeAmongPillars: the same through a row of pillars across the straight line (the
// nearest pillar's surface within 1 m of each sample of the initial guess as its plane). Target: <= 5 ms for about 10 pieces.
// Run: build/bin/planner_benchmark
#include <benchmark/benchmark.h>

#include <vector>

#include "rotorguard/planning/trajectory_optimizer.h"

namespace {

using namespace rotorguard;
using namespace rotorguard::planning;

PvaState Rest(const Vector3& p) {
  PvaState s = PvaState::Zero();
  s.col(0) = p;
  return s;
}

void Run(benchmark::State& state, const NearestPlane& nearest) {
  const TrajectoryOptimizer optimizer{TrajectoryOptimizerOptions{}};
  const Vector3 a(0, 0, 1.5), b(20, 0, 1.5);
  const int pieces = 10;
  Eigen::Matrix3Xd q(3, pieces - 1);
  for (int i = 1; i < pieces; ++i) q.col(i - 1) = a + (b - a) * i / pieces + Vector3(0, 0.3 * (i % 2 ? 1 : -1), 0);
  const Eigen::VectorXd t = Eigen::VectorXd::Constant(pieces, 2.0);
  MinimumJerkTrajectory initial;
  initial.Build(Rest(a), Rest(b), q, t);
  const PlaneSet obstacles =
      nearest ? BuildSamplePlanes(initial, optimizer.options().samples_per_piece, nearest) : PlaneSet{};
  double iterations = 0, evaluations = 0, ok = 0, duration = 0;
  for (auto _ : state) {
    MinimumJerkTrajectory traj;
    const TrajectoryOptimizerSummary s = optimizer.Optimize(Rest(a), Rest(b), q, t, DynamicLimits{}, obstacles, &traj);
    iterations += s.iterations;
    evaluations += s.evaluations;
    ok += s.ok();
    duration += traj.total_duration();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["lbfgs_iterations"] = iterations / n;
  state.counters["evaluations"] = evaluations / n;
  state.counters["success"] = ok / n;
  state.counters["traj_duration_s"] = duration / n;
}

void BM_OptimizeFreeSpace(benchmark::State& state) { Run(state, {}); }
BENCHMARK(BM_OptimizeFreeSpace)->Unit(benchmark::kMillisecond);

void BM_OptimizeAmongPillars(benchmark::State& state) {
  std::vector<Eigen::Vector2d> pillars;
  for (int k = 0; k < 6; ++k) pillars.emplace_back(3.0 + 2.5 * k, k % 2 ? 0.4 : -0.4);
  const double radius = 0.2;
  const NearestPlane nearest = [&](const Vector3& p) -> std::optional<ObstaclePlane> {
    std::optional<ObstaclePlane> best;
    double best_d = 1.0;
    for (const Eigen::Vector2d& c : pillars) {
      const Eigen::Vector2d d = p.head<2>() - c;
      const double r = d.norm(), dist = r - radius;
      if (r < 1e-9 || dist > best_d) continue;
      best_d = dist;
      const Vector3 n(d.x() / r, d.y() / r, 0.0);
      best = ObstaclePlane{Vector3(c.x(), c.y(), p.z()) + radius * n, n};
    }
    return best;
  };
  Run(state, nearest);
}
BENCHMARK(BM_OptimizeAmongPillars)->Unit(benchmark::kMillisecond);

}  // namespace
