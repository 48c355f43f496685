#include "rotorguard/planning/lbfgs.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include <ceres/first_order_function.h>
#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>
#include <glog/logging.h>

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

}  // namespace

LbfgsSummary MinimizeLbfgs(const GradientObjective& f, const LbfgsOptions& options, Eigen::VectorXd* x) {
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
