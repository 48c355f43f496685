// peer_lbfgs: the planner's L-BFGS beside GCOPTER's (lbfgs.hpp) on the same objective, the planner's
// eq. (22) in free space (TrajectoryOptimizer::Objective), in one process, problem by problem, the
// two turns alternated (docs/performance.md).
//
//   peer_lbfgs [--problems 200] [--seed 1] [--repetitions 3]
//
// Problem i of M pieces (M = 5 and 10): rest to rest from (0, 0, 1.5) to a point 2M-4M m away on a
// random heading at a height in [1, 3] m; the initial waypoints on the straight line, each moved by
// N(0, 0.3 m) per axis; each initial duration 1.5 times its piece's length at v_max; limits v 2 m/s,
// a 3 m/s^2, j 6 m/s^3. Both start from the same variables x = [q, tau].
//   rotorguard: the planner's own L-BFGS as the planner runs it (TrajectoryOptimizerOptions::lbfgs);
//   gcopter:    lbfgs::lbfgs_optimize with the parameters GCOPTER's planner sets (gcopter.hpp: 256
//               pairs, past 3, delta 1e-4 (its relative cost tolerance as rotorguard's), g_epsilon 0,
//               min_step 1e-32; no iteration limit).
// A non-finite cost (a trajectory that cannot be built) reaches GCOPTER's line search as +inf with a
// zero gradient, which it rejects as too high. Reported per size: each side's median time of the
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
#include "rotorguard/core/rng.h"
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

Problem MakeProblem(int pieces, std::uint64_t seed, const DynamicLimits& limits) {
  Rng rng(seed);
  const Vector3 a(0.0, 0.0, 1.5);
  const double heading = rng.Uniform(-M_PI, M_PI), distance = rng.Uniform(2.0 * pieces, 4.0 * pieces);
  const Vector3 b(distance * std::cos(heading), distance * std::sin(heading), rng.Uniform(1.0, 3.0));
  Eigen::Matrix3Xd q(3, pieces - 1);
  for (int i = 1; i < pieces; ++i) {
    q.col(i - 1) = a + (b - a) * i / pieces + Vector3(rng.Normal(0, 0.3), rng.Normal(0, 0.3), rng.Normal(0, 0.3));
  }
  Eigen::VectorXd t(pieces);
  for (int i = 0; i < pieces; ++i) {
    const Vector3 from = i == 0 ? a : Vector3(q.col(i - 1)), to = i == pieces - 1 ? b : Vector3(q.col(i));
    t[i] = 1.5 * (to - from).norm() / limits.v_max;
  }
  Problem p{PvaState::Zero(), PvaState::Zero(), TrajectoryOptimizer::Variables(q, t)};
  p.head.col(0) = a;
  p.tail.col(0) = b;
  return p;
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

int Usage(const char* why) {
  std::fprintf(stderr, "peer_lbfgs: %s\nusage: peer_lbfgs [--problems N >= 1] [--seed S] [--repetitions R >= 1]\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  long problems = 200, repetitions = 3;
  unsigned long long seed = 1;
  for (int i = 1; i < argc; ++i) {
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
  const TrajectoryOptimizer optimizer{TrajectoryOptimizerOptions{}};
  const DynamicLimits limits{.v_max = 2.0, .a_max = 3.0, .j_max = 6.0};
  lbfgs::lbfgs_parameter_t gcopter;  // as gcopter.hpp sets them
  gcopter.mem_size = 256;
  gcopter.past = 3;
  gcopter.min_step = 1.0e-32;
  gcopter.g_epsilon = 0.0;
  gcopter.delta = optimizer.options().lbfgs.relative_cost_tolerance;

  nlohmann::json sizes = nlohmann::json::array();
  for (const int pieces : {5, 10}) {
    std::vector<double> time_own, time_gc, cost_own, cost_gc, diff, iter_own, iter_gc, eval_own, eval_gc;
    int gc_errors = 0, own_failures = 0;
    for (long i = 0; i < problems; ++i) {
      const Problem p = MakeProblem(pieces, TrialSeed(seed, "peer_lbfgs", static_cast<std::uint64_t>(pieces * 100000 + i)),
                                    limits);
      double best_own = std::numeric_limits<double>::infinity(), best_gc = best_own, f_own = 0, f_gc = 0;
      for (long r = 0; r < repetitions; ++r) {
        for (int turn = 0; turn < 2; ++turn) {
          const bool own = (turn + i + r) % 2 == 0;  // each side first in half of the solves
          Eigen::VectorXd x = p.x0;
          Context c{&optimizer, &p, &limits};
          const auto t0 = Clock::now();
          if (own) {
            const GradientObjective f = [&](const Eigen::VectorXd& v, Eigen::VectorXd* g) {
              ++c.evaluations;
              return optimizer.Objective(p.head, p.tail, limits, {}, v, g);
            };
            const LbfgsSummary s = MinimizeLbfgs(f, optimizer.options().lbfgs, &x);
            const double ms = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
            best_own = std::min(best_own, ms);
            f_own = optimizer.Objective(p.head, p.tail, limits, {}, x, nullptr);
            if (r == 0) {
              own_failures += s.failed;
              iter_own.push_back(s.iterations);
              eval_own.push_back(c.evaluations);
            }
          } else {
            double f = 0.0;
            const int ret = lbfgs::lbfgs_optimize(x, f, &GcopterCost, nullptr, nullptr, &c, gcopter);
            const double ms = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
            best_gc = std::min(best_gc, ms);
            f_gc = optimizer.Objective(p.head, p.tail, limits, {}, x, nullptr);
            if (r == 0) {
              gc_errors += ret < 0;
              eval_gc.push_back(c.evaluations);
            }
          }
        }
      }
      time_own.push_back(best_own);
      time_gc.push_back(best_gc);
      cost_own.push_back(f_own);
      cost_gc.push_back(f_gc);
      diff.push_back(f_own - f_gc);
    }
    const auto mean = [](const std::vector<double>& v) {
      double s = 0;
      for (double e : v) s += e;
      return v.empty() ? 0.0 : s / static_cast<double>(v.size());
    };
    double var = 0;
    const double d_mean = mean(diff);
    for (double d : diff) var += (d - d_mean) * (d - d_mean);
    const double n = static_cast<double>(diff.size());
    const int lower = static_cast<int>(std::count_if(diff.begin(), diff.end(), [](double d) { return d < 0; }));
    sizes.push_back({{"pieces", pieces},
                     {"problems", problems},
                     {"rotorguard_us_median", Percentile(time_own, 0.5)},
                     {"gcopter_us_median", Percentile(time_gc, 0.5)},
                     {"rotorguard_cost_mean", mean(cost_own)},
                     {"gcopter_cost_mean", mean(cost_gc)},
                     {"cost_difference_mean", d_mean},
                     {"cost_difference_stderr", n > 1 ? std::sqrt(var / (n - 1) / n) : 0.0},
                     {"problems_rotorguard_lower", lower},
                     {"rotorguard_iterations_mean", mean(iter_own)},
                     {"rotorguard_evaluations_mean", mean(eval_own)},
                     {"gcopter_evaluations_mean", mean(eval_gc)},
                     {"rotorguard_failures", own_failures},
                     {"gcopter_errors", gc_errors}});
  }
  const nlohmann::json out = {{"benchmark", "peer_lbfgs"},
                              {"seed", seed},
                              {"repetitions", repetitions},
                              {"host", buildinfo::HostInfo()},
                              {"sizes", sizes}};
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
