#include "rotorguard/planning/lbfgs.h"

#include <ceres/first_order_function.h>
#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "rotorguard/core/error.h"

namespace rotorguard::planning {

namespace {

class CeresObjective final : public ceres::FirstOrderFunction {
 public:
  CeresObjective(const GradientObjective& f, int size, int* evaluations)
      : f_(f), size_(size), evaluations_(evaluations) {}
  bool Evaluate(const double* parameters, double* cost, double* gradient) const override {
    ++*evaluations_;
    const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(parameters, size_);
    Eigen::VectorXd g;
    *cost = f_(x, gradient ? &g : nullptr);
    if (!std::isfinite(*cost)) return false;
    if (gradient) {
      if (g.size() != size_ || !g.allFinite()) return false;
      Eigen::Map<Eigen::VectorXd>(gradient, size_) = g;
    }
    return true;
  }
  int NumParameters() const override { return size_; }

 private:
  const GradientObjective& f_;
  int size_;
  int* evaluations_;
};

/// LbfgsMethod::kLewisOverton.
LbfgsSummary MinimizeLewisOverton(const GradientObjective& f, const LbfgsOptions& options, Eigen::VectorXd* x) {
  // Armijo's sufficient decrease and the weak Wolfe curvature condition (Nocedal & Wright, eq. 3.6).
  constexpr double kArmijo = 1e-4, kCurvature = 0.9;
  constexpr int kMaxLineSearch = 60;
  LbfgsSummary summary;
  const auto n = x->size();
  Eigen::VectorXd g(n), x_trial(n), g_trial(n), d(n), s_new(n), y_new(n);
  double fx = f(*x, &g);
  ++summary.evaluations;
  if (!std::isfinite(fx) || g.size() != n || !g.allFinite()) {
    summary.failed = true;
    summary.message = "the starting point has no finite cost and gradient";
    return summary;
  }
  const int m = options.memory;
  Eigen::MatrixXd s_pairs(n, m), y_pairs(n, m);
  Eigen::VectorXd rho(m), alpha(m);
  int stored = 0, newest = -1;  // a ring of the last `stored` pairs, newest at `newest`
  std::vector<double> history(static_cast<std::size_t>(options.past), fx);  // f of the last `past` iterates
  d = -g;
  double step = 1.0 / std::max(d.norm(), 1e-300);  // the first step moves x by one unit
  for (int k = 1; k <= options.max_iterations; ++k) {
    double g_dot_d = g.dot(d);
    if (!(g_dot_d < 0.0)) {  // not a descent direction (rounding at a flat point): steepest descent
      d = -g;
      stored = 0;
      g_dot_d = -g.squaredNorm();
      if (!(g_dot_d < 0.0)) {
        summary.message = "the gradient vanished";
        break;
      }
    }
    double low = 0.0, high = std::numeric_limits<double>::infinity(), t = step, f_trial = fx;
    bool accepted = false;
    for (int ls = 0; ls < kMaxLineSearch; ++ls) {
      x_trial = *x + t * d;
      f_trial = f(x_trial, &g_trial);
      ++summary.evaluations;
      const bool finite = std::isfinite(f_trial) && g_trial.size() == n && g_trial.allFinite();
      if (!finite || f_trial > fx + kArmijo * t * g_dot_d) {
        high = t;
      } else if (g_trial.dot(d) < kCurvature * g_dot_d) {
        low = t;
      } else {
        accepted = true;
        break;
      }
      t = std::isinf(high) ? 2.0 * t : 0.5 * (low + high);
    }
    summary.iterations = k;
    if (!accepted) {
      summary.message = "the line search found no step that satisfies the Wolfe conditions";
      break;
    }
    // The new pair, kept when its curvature is positive (always, under the Wolfe conditions, but for
    // rounding).
    s_new = x_trial - *x;
    y_new = g_trial - g;
    const double sy = s_new.dot(y_new);
    *x = x_trial;
    g = g_trial;
    const double f_before = history.front();
    std::rotate(history.begin(), history.begin() + 1, history.end());
    history.back() = f_trial;
    fx = f_trial;
    if (sy > 1e-12 * s_new.norm() * y_new.norm()) {
      newest = (newest + 1) % m;
      s_pairs.col(newest) = s_new;
      y_pairs.col(newest) = y_new;
      rho(newest) = 1.0 / sy;
      stored = std::min(stored + 1, m);
    }
    // The decrease test over the last `past` iterations.
    if (k >= options.past && f_before - fx < options.relative_cost_tolerance * std::max(std::abs(fx), 1e-300)) {
      summary.message = "the cost fell by less than the tolerance over the last iterations";
      break;
    }
    // d = -H g by the two-loop recursion, H0 = (s'y / y'y) I of the newest pair.
    d = -g;
    for (int j = 0, i = newest; j < stored; ++j, i = (i - 1 + m) % m) {
      alpha(i) = rho(i) * s_pairs.col(i).dot(d);
      d.noalias() -= alpha(i) * y_pairs.col(i);
    }
    if (stored > 0) d *= 1.0 / (rho(newest) * y_pairs.col(newest).squaredNorm());
    for (int j = 0, i = (newest - stored + 1 + m) % m; j < stored; ++j, i = (i + 1) % m) {
      const double beta = rho(i) * y_pairs.col(i).dot(d);
      d.noalias() += (alpha(i) - beta) * s_pairs.col(i);
    }
    step = 1.0;
  }
  if (summary.message.empty()) summary.message = "the iteration limit";
  return summary;
}

}  // namespace

void LbfgsOptions::Validate() const {
  const auto require = [](bool ok, const char* field, double value, const char* rule) {
    if (!ok) ThrowValidation("LbfgsOptions", field, value, rule);
  };
  require(max_iterations >= 1, "max_iterations", max_iterations, ">= 1");
  require(relative_cost_tolerance > 0.0 && relative_cost_tolerance <= 0.1, "relative_cost_tolerance",
          relative_cost_tolerance, "in (0, 0.1]");
  require(memory >= 1, "memory", memory, ">= 1");
  require(past >= 1, "past", past, ">= 1");
}

LbfgsSummary MinimizeLbfgs(const GradientObjective& f, const LbfgsOptions& options, Eigen::VectorXd* x) {
  options.Validate();
  if (options.method == LbfgsMethod::kLewisOverton) return MinimizeLewisOverton(f, options, x);
  static std::once_flag quiet;
  std::call_once(quiet, [] { FLAGS_minloglevel = std::max(FLAGS_minloglevel, static_cast<int>(google::GLOG_ERROR)); });
  LbfgsSummary summary;
  ceres::GradientProblemSolver::Options solver_options;
  solver_options.line_search_direction_type = ceres::LBFGS;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.logging_type = ceres::SILENT;
  solver_options.use_approximate_eigenvalue_bfgs_scaling = true;
  solver_options.function_tolerance = options.relative_cost_tolerance;
  solver_options.gradient_tolerance = 1e-8;
  ceres::GradientProblem problem(new CeresObjective(f, static_cast<int>(x->size()), &summary.evaluations));
  ceres::GradientProblemSolver::Summary ceres_summary;
  ceres::Solve(solver_options, problem, x->data(), &ceres_summary);
  summary.iterations = static_cast<int>(ceres_summary.iterations.size());
  summary.failed = ceres_summary.termination_type == ceres::FAILURE;
  summary.message = ceres_summary.message;
  return summary;
}

}  // namespace rotorguard::planning
