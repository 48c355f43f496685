#pragma once
/// `rotorguard bench planner --free-space`: the trajectory optimiser alone (planning::
/// TrajectoryOptimizer) on random free-space problems, the definition under which it is compared
/// with other MINCO optimisers (docs/planning.md, "The optimiser in free space"):
///   - a start uniform in a 20 x 20 x 2 m box, each next waypoint 1.5-4 m from the last in a
///     uniformly random direction, redrawn until it lies in the box; rest to rest;
///   - the intermediate waypoints and durations length / v_max as the initial guess;
///   - v_max 1 m/s, a_max 2 m/s², no jerk limit; cost 10 T + jerk energy + 1e4 Σ max(|v|² − 1, 0)³
///     + 1e4 Σ max(|a|² − 4, 0)³ over 17 samples per piece (both ends included);
///   - 200 iterations at most, relative cost tolerance 1e-4, then the optimiser's dense limit check.
/// Per size it reports the median solve time, the median time of one cost and gradient evaluation
/// (at the initial guess), and the mean final cost and trajectory duration.
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "rotorguard/planning/trajectory_optimizer.h"

namespace rotorguard::benchmarks {

struct FreeSpaceBenchOptions {
  std::vector<int> pieces = {5, 10};  ///< problem sizes, each in [1, 100]
  int problems = 200;                 ///< problems per size, in [1, 100000]
  std::uint64_t seed = 1;
  int evaluations = 200;  ///< timed evaluations per problem for eval_us, in [1, 100000]
  planning::LbfgsMethod lbfgs = planning::LbfgsMethod::kLewisOverton;  ///< the optimiser's L-BFGS
  /// Called after each problem with (done, total).
  std::function<void(int, int)> progress;
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// One problem: its M + 1 points (start, M − 1 intermediate waypoints, end) and M durations.
struct FreeSpaceProblem {
  Eigen::Matrix3Xd points;
  Eigen::VectorXd durations;
};

/// The limits and optimiser options of the definition above.
planning::DynamicLimits FreeSpaceLimits();
planning::TrajectoryOptimizerOptions FreeSpaceOptimizerOptions(planning::LbfgsMethod lbfgs);
/// Problem `index` of size `pieces` for `seed`: the same for every run and build.
FreeSpaceProblem DrawFreeSpaceProblem(int pieces, std::uint64_t seed, int index);

/// {"benchmark": "planner_free_space", "free_space": [{pieces, solve_us_median, eval_us_median,
/// cost_mean, duration_s_mean, ...}, ...], ...}.
nlohmann::json RunFreeSpaceBenchmark(const FreeSpaceBenchOptions& options);
std::string FreeSpaceMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks
