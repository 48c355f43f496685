#include "rotorguard/benchmarks/free_space_bench.h"

#include <fmt/format.h>

#include <cmath>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/core/stopwatch.h"

namespace rotorguard::benchmarks {

namespace {

// The box the waypoints are drawn in [m], and a step's length between two of them.
const Vector3 kBoxLow(-10.0, -10.0, 0.0), kBoxHigh(10.0, 10.0, 2.0);
constexpr double kStepMin = 1.5, kStepMax = 4.0;

bool InBox(const Vector3& p) { return (p.array() >= kBoxLow.array()).all() && (p.array() <= kBoxHigh.array()).all(); }

}  // namespace

void FreeSpaceBenchOptions::Validate() const {
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowInvalidArgument("RunFreeSpaceBenchmark", std::string("FreeSpaceBenchOptions::") + field, v, rule);
  };
  require(!pieces.empty(), "pieces", static_cast<double>(pieces.size()), "at least one size");
  for (int m : pieces) require(m >= 1 && m <= 100, "pieces", m, "sizes in [1, 100]");
  require(problems >= 1 && problems <= 100000, "problems", problems, "in [1, 100000]");
  require(evaluations >= 1 && evaluations <= 100000, "evaluations", evaluations, "in [1, 100000]");
}

planning::DynamicLimits FreeSpaceLimits() {
  planning::DynamicLimits limits;
  limits.v_max = 1.0;
  limits.a_max = 2.0;
  limits.j_max = planning::DynamicLimits::kNoLimit;
  return limits;
}

planning::TrajectoryOptimizerOptions FreeSpaceOptimizerOptions(planning::LbfgsMethod lbfgs) {
  planning::TrajectoryOptimizerOptions o;
  o.lbfgs.method = lbfgs;
  o.weights = {.time = 10.0, .smoothness = 1.0, .feasibility = 1e4, .collision = 0.0};
  o.samples_per_piece = 16;  // 17 samples, both ends included
  o.lbfgs.max_iterations = 200;
  o.lbfgs.relative_cost_tolerance = 1e-4;
  return o;
}

FreeSpaceProblem DrawFreeSpaceProblem(int pieces, std::uint64_t seed, int index) {
  Rng rng(DeriveSeed(DeriveSeed(seed, static_cast<std::uint64_t>(pieces)), static_cast<std::uint64_t>(index)));
  FreeSpaceProblem p;
  p.points.resize(3, pieces + 1);
  p.durations.resize(pieces);
  p.points.col(0) = Vector3(rng.Uniform(kBoxLow.x(), kBoxHigh.x()), rng.Uniform(kBoxLow.y(), kBoxHigh.y()),
                            rng.Uniform(kBoxLow.z(), kBoxHigh.z()));
  const double v_max = FreeSpaceLimits().v_max;
  for (int i = 1; i <= pieces; ++i) {
    Vector3 next;
    do {  // a direction uniform on the sphere: a normal vector's
      Vector3 direction(rng.Normal(), rng.Normal(), rng.Normal());
      next = p.points.col(i - 1) + rng.Uniform(kStepMin, kStepMax) * direction.normalized();
    } while (!InBox(next));
    p.points.col(i) = next;
    p.durations(i - 1) = (p.points.col(i) - p.points.col(i - 1)).norm() / v_max;
  }
  return p;
}

nlohmann::json RunFreeSpaceBenchmark(const FreeSpaceBenchOptions& options) {
  options.Validate();
  const planning::DynamicLimits limits = FreeSpaceLimits();
  const planning::TrajectoryOptimizer optimizer(FreeSpaceOptimizerOptions(options.lbfgs));
  const int total = static_cast<int>(options.pieces.size()) * options.problems;
  int done = 0;
  nlohmann::json sizes = nlohmann::json::array();
  for (const int m : options.pieces) {
    std::vector<double> solve_us, eval_us, check_us, cost, duration, iterations, evaluations;
    int failed = 0, stretched = 0;
    for (int k = 0; k < options.problems; ++k) {
      const FreeSpaceProblem p = DrawFreeSpaceProblem(m, options.seed, k);
      planning::PvaState head = planning::PvaState::Zero(), tail = planning::PvaState::Zero();
      head.col(0) = p.points.col(0);
      tail.col(0) = p.points.col(m);
      const Eigen::Matrix3Xd waypoints = p.points.middleCols(1, m - 1);
      // One evaluation of the cost and its gradient at the initial guess, averaged over many.
      const Eigen::VectorXd x = planning::TrajectoryOptimizer::Variables(waypoints, p.durations);
      Eigen::VectorXd gradient;
      double sink = 0.0;
      const Stopwatch eval_clock;
      for (int e = 0; e < options.evaluations; ++e) sink += optimizer.Objective(head, tail, limits, {}, x, &gradient);
      eval_us.push_back(1e6 * eval_clock.seconds() / options.evaluations);

      planning::MinimumJerkTrajectory traj;
      const planning::TrajectoryOptimizerSummary s =
          optimizer.Optimize(head, tail, waypoints, p.durations, limits, {}, &traj);
      solve_us.push_back(1e3 * s.solve_ms);
      // (The sum's check also keeps the timed evaluations from being optimised away.)
      if (!std::isfinite(sink) || !s.ok()) {
        ++failed;
      } else {
        check_us.push_back(1e3 * s.check_ms);
        cost.push_back(s.final_cost);
        duration.push_back(traj.total_duration());
        iterations.push_back(s.iterations);
        evaluations.push_back(s.evaluations);
        stretched += s.slowdowns > 0;
      }
      if (options.progress) options.progress(++done, total);
    }
    sizes.push_back({{"pieces", m},
                     {"problems", options.problems},
                     {"failed", failed},
                     {"solve_us_median", Percentile(solve_us, 0.5)},
                     {"solve_us_p90", Percentile(solve_us, 0.9)},
                     {"eval_us_median", Percentile(eval_us, 0.5)},
                     {"check_us_median", Percentile(check_us, 0.5)},
                     {"cost_mean", Mean(cost)},
                     {"duration_s_mean", Mean(duration)},
                     {"iterations_mean", Mean(iterations)},
                     {"evaluations_mean", Mean(evaluations)},
                     {"stretched_by_check", stretched}});
  }
  const planning::TrajectoryOptimizerOptions& o = optimizer.options();
  const Vector3 box = kBoxHigh - kBoxLow;
  return {{"benchmark", "planner_free_space"},
          {"seed", options.seed},
          {"problem",
           {{"box_m", {box.x(), box.y(), box.z()}},
            {"step_m", {kStepMin, kStepMax}},
            {"v_max", limits.v_max},
            {"a_max", limits.a_max},
            {"j_max", nullptr},
            {"weights", {o.weights.time, o.weights.smoothness, o.weights.feasibility}},
            {"samples_per_piece", o.samples_per_piece + 1},
            {"max_iterations", o.lbfgs.max_iterations},
            {"relative_cost_tolerance", o.lbfgs.relative_cost_tolerance},
            {"lbfgs", ToName(options.lbfgs)}}},
          {"free_space", sizes},
          {"host", buildinfo::HostInfo()}};
}

std::string FreeSpaceMarkdown(const nlohmann::json& r) {
  std::string md = fmt::format(
      "The trajectory optimiser on {} random free-space problems per size, seed {} (rest to rest, v_max 1 m/s, "
      "a_max 2 m/s², no jerk limit), L-BFGS: {}.\n\n",
      r["free_space"][0]["problems"].get<int>(), r["seed"].get<std::uint64_t>(),
      r["problem"]["lbfgs"].get<std::string>());
  md +=
      "| pieces | solve µs (median / p90) | one evaluation µs | check µs | cost (mean) | duration s (mean) | "
      "iterations | evaluations | stretched | failed |\n";
  md += "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const nlohmann::json& s : r["free_space"]) {
    md +=
        fmt::format("| {} | {:.0f} / {:.0f} | {:.2f} | {:.1f} | {:.2f} | {:.2f} | {:.1f} | {:.1f} | {} | {} |\n",
                    s["pieces"].get<int>(), s["solve_us_median"].get<double>(), s["solve_us_p90"].get<double>(),
                    s["eval_us_median"].get<double>(), s["check_us_median"].get<double>(), s["cost_mean"].get<double>(),
                    s["duration_s_mean"].get<double>(), s["iterations_mean"].get<double>(),
                    s["evaluations_mean"].get<double>(), s["stretched_by_check"].get<int>(), s["failed"].get<int>());
  }
  return md;
}

}  // namespace rotorguard::benchmarks
