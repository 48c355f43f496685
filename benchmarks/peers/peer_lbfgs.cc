// peer_lbfgs: the planner's L-BFGS beside GCOPTER's (lbfgs.hpp) on the same objective, the planner's
// eq. (22) in free space (TrajectoryOptimizer::Objective), in one process, problem by problem, the
// two turns alternated (docs/performance.md).
//
//   peer_lbfgs [--problems 200] [--seed 1] [--repetitions 3]
//
// The problems are the free-space definition MINCO optimisers are compared on (free_space_bench.h,
// `rotorguard bench planner --free-space`: DrawFreeSpaceProblem, its limits and cost), 5 and 10
// pieces; both L-BFGS start from the same variables x = [q, tau].
//   rotorguard: the planner's own L-BFGS as the planner runs it (TrajectoryOptimizerOptions::lbfgs);
//   gcopter:    lbfgs::lbfgs_optimize with the parameters GCOPTER's planner sets (gcopter.hpp: 256
//               pairs, past 3, delta 1e-4 (its relative cost tolerance as rotorguard's), g_epsilon 0,
//               min_step 1e-32; no iteration limit).
// A non-finite cost (a trajectory that cannot be built) reaches GCOPTER as +inf with a zero gradient:
// lbfgs.hpp then returns LBFGSERR_INVALID_FUNCVAL with the last good point, counted in gcopter_*_errors
// (stopping at the iteration limit is counted apart, as *_at_limit). Reported per size: each side's median time of the
// optimisation alone (the fastest of its repetitions per problem), its mean final cost, and the
// per-problem cost difference (rotorguard - gcopter) with its standard error. Prints one JSON object.
#include <gcopter/lbfgs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/benchmarks/free_space_bench.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/planning/trajectory_optimizer.h"

namespace {

using namespace rotorguard;
using namespace rotorguard::planning;
using Clock = std::chrono::steady_clock;

struct Problem {
  PvaState head, tail;
  Eigen::VectorXd x0;
};

Problem MakeProblem(int pieces, std::uint64_t seed, int index) {
  const benchmarks::FreeSpaceProblem p = benchmarks::DrawFreeSpaceProblem(pieces, seed, index);
  Problem out{PvaState::Zero(), PvaState::Zero(),
              TrajectoryOptimizer::Variables(p.points.middleCols(1, pieces - 1), p.durations)};
  out.head.col(0) = p.points.col(0);
  out.tail.col(0) = p.points.col(pieces);
  return out;
}

struct Context {
  const TrajectoryOptimizer* optimizer;
  const Problem* problem;
  const DynamicLimits* limits;
  int evaluations = 0;
};

double GcopterCost(void* instance, const Eigen::VectorXd& x, Eigen::VectorXd& g) {
  auto* c = static_cast<Context*>(instance);
  ++c->evaluations;
  const double f = c->optimizer->Objective(c->problem->head, c->problem->tail, *c->limits, {}, x, &g);
  if (!std::isfinite(f) || !g.allFinite()) {
    g.setZero();
    return std::numeric_limits<double>::infinity();
  }
  return f;
}

constexpr const char* kUsage = "peer_lbfgs [--problems N >= 1] [--seed S] [--repetitions R >= 1]";

int Usage(const char* why) {
  std::fprintf(stderr, "peer_lbfgs: %s\nusage: %s\n", why, kUsage);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  long problems = 200, repetitions = 3;
  unsigned long long seed = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      std::printf("usage: %s\n", kUsage);
      return 0;
    }
    const std::string a = argv[i];
    if ((a == "--problems" || a == "--seed" || a == "--repetitions") && i + 1 < argc) {
      char* end = nullptr;
      const unsigned long long v = std::strtoull(argv[++i], &end, 10);
      if (*end != '\0' || argv[i][0] == '-' || (a != "--seed" && (v < 1 || v > 100000))) {
        return Usage((a + ": expected an integer" + (a == "--seed" ? "" : " in [1, 100000]") + ", got '" + argv[i] +
                      "'")
                         .c_str());
      }
      if (a == "--problems") problems = static_cast<long>(v);
      if (a == "--seed") seed = v;
      if (a == "--repetitions") repetitions = static_cast<long>(v);
    } else {
      return Usage(("unknown argument '" + a + "'").c_str());
    }
  }
  const TrajectoryOptimizer optimizer{benchmarks::FreeSpaceOptimizerOptions(LbfgsMethod::kLewisOverton)};
  const DynamicLimits limits = benchmarks::FreeSpaceLimits();
  // GCOPTER's parameters as gcopter.hpp sets them; its relative cost tolerance rotorguard's.
  lbfgs::lbfgs_parameter_t gcopter;
  gcopter.mem_size = 256;
  gcopter.past = 3;
  gcopter.min_step = 1.0e-32;
  gcopter.g_epsilon = 0.0;
  gcopter.delta = optimizer.options().lbfgs.relative_cost_tolerance;
  // Two budgets: the planner's 200 iterations for both, and none (GCOPTER's planner sets none;
  // rotorguard's then gets kUnlimited), where each runs until its own decrease test stops it.
  constexpr int kUnlimited = 100000;
  struct Side {
    const char* name;
    bool own;
    int max_iterations;  // 0: none (GCOPTER's convention)
  };
  const Side sides[] = {{"rotorguard_200", true, optimizer.options().lbfgs.max_iterations},
                        {"gcopter_200", false, optimizer.options().lbfgs.max_iterations},
                        {"rotorguard_unlimited", true, kUnlimited},
                        {"gcopter_unlimited", false, 0}};
  constexpr int kSides = 4;

  nlohmann::json sizes = nlohmann::json::array();
  for (const int pieces : {5, 10}) {
    std::vector<double> time[kSides], cost[kSides], iterations[kSides], evaluations[kSides];
    int failures[kSides] = {}, limits_hit[kSides] = {};
    for (long i = 0; i < problems; ++i) {
      const Problem p = MakeProblem(pieces, seed, static_cast<int>(i));
      double best[kSides], final_cost[kSides];
      std::fill(best, best + kSides, std::numeric_limits<double>::infinity());
      for (long r = 0; r < repetitions; ++r) {
        for (int turn = 0; turn < kSides; ++turn) {
          const int k = static_cast<int>((turn + i + r) % kSides);  // each side first in a quarter of the solves
          const Side& side = sides[k];
          Eigen::VectorXd x = p.x0;
          Context c{&optimizer, &p, &limits};
          bool failed = false, at_limit = false;
          int iters = 0;
          const auto t0 = Clock::now();
          if (side.own) {
            LbfgsOptions o = optimizer.options().lbfgs;
            o.max_iterations = side.max_iterations;
            const GradientObjective f = [&](const Eigen::VectorXd& v, Eigen::VectorXd* g) {
              ++c.evaluations;
              return optimizer.Objective(p.head, p.tail, limits, {}, v, g);
            };
            const LbfgsSummary summary = MinimizeLbfgs(f, o, &x);
            failed = summary.failed;
            iters = summary.iterations;
            at_limit = !failed && iters >= o.max_iterations;
          } else {
            lbfgs::lbfgs_parameter_t o = gcopter;
            o.max_iterations = side.max_iterations;
            double f = 0.0;
            const int code = lbfgs::lbfgs_optimize(x, f, &GcopterCost, nullptr, nullptr, &c, o);
            at_limit = code == lbfgs::LBFGSERR_MAXIMUMITERATION;
            failed = code < 0 && !at_limit;
            iters = -1;  // lbfgs.hpp does not return its count
          }
          best[k] = std::min(best[k], std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
          final_cost[k] = optimizer.Objective(p.head, p.tail, limits, {}, x, nullptr);
          if (r == 0) {
            failures[k] += failed;
            limits_hit[k] += at_limit;
            if (iters >= 0) iterations[k].push_back(iters);
            evaluations[k].push_back(c.evaluations);
          }
        }
      }
      for (int k = 0; k < kSides; ++k) {
        time[k].push_back(best[k]);
        cost[k].push_back(final_cost[k]);
      }
    }
    nlohmann::json size = {{"pieces", pieces}, {"problems", problems}};
    for (int k = 0; k < kSides; ++k) {
      const std::string n = sides[k].name;
      size[n + "_us_median"] = Percentile(time[k], 0.5);
      size[n + "_cost_mean"] = Mean(cost[k]);
      size[n + "_evaluations_mean"] = Mean(evaluations[k]);
      if (!iterations[k].empty()) size[n + "_iterations_mean"] = Mean(iterations[k]);
      size[n + "_errors"] = failures[k];
      size[n + "_at_limit"] = limits_hit[k];
    }
    // Per problem, rotorguard's final cost minus GCOPTER's at the same budget.
    for (const std::string budget : {"200", "unlimited"}) {
      const int own = budget == "200" ? 0 : 2, peer = own + 1;
      std::vector<double> diff;
      for (std::size_t j = 0; j < cost[own].size(); ++j) diff.push_back(cost[own][j] - cost[peer][j]);
      const double d = Mean(diff), n = static_cast<double>(diff.size());
      double var = 0.0;
      for (double e : diff) var += (e - d) * (e - d);
      size["cost_difference_" + budget + "_mean"] = d;
      size["cost_difference_" + budget + "_stderr"] = n > 1 ? std::sqrt(var / (n - 1) / n) : 0.0;
      size["problems_rotorguard_lower_" + budget] =
          std::count_if(diff.begin(), diff.end(), [](double e) { return e < 0.0; });
    }
    sizes.push_back(size);
  }
  const nlohmann::json out = {{"benchmark", "peer_lbfgs"},
                              {"seed", seed},
                              {"repetitions", repetitions},
                              {"host", buildinfo::HostInfo()},
                              {"sizes", sizes}};
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
