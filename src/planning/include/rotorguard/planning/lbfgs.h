#pragma once
/// Unconstrained minimisation for the penalty formulations of the trajectory optimisers (paper
/// 000, eq. 22; paper 002, eq. 11): Ceres' L-BFGS (GradientProblemSolver) behind a wrapper that
/// treats any non-finite cost or gradient as a failed evaluation, which the line search backs away
/// from (Ceres alone can accept a NaN cost and declare convergence).
#include <functional>
#include <string>

#include <Eigen/Core>

namespace rotorguard::planning {

/// max(x, 0)^3 and its derivative: the penalty of the sampled constraints, cubed so that the
/// objective is twice differentiable where a constraint becomes active.
inline double CubicPenalty(double x, double* slope) {
  if (x <= 0.0) {
    *slope = 0.0;
    return 0.0;
  }
  *slope = 3.0 * x * x;
  return x * x * x;
}

/// f(x) and, when `gradient` is not null, its gradient; NaN when x has no value.
using GradientObjective = std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd* gradient)>;

struct LbfgsOptions {
  int max_iterations = 200;               ///< >= 1
  double relative_cost_tolerance = 1e-4;  ///< stop once an iteration lowers f by less than this fraction
};

struct LbfgsSummary {
  bool failed = false;  ///< Ceres reported a failure (x may still be the best point it reached)
  int iterations = 0;
  int evaluations = 0;
  std::string message;
};

/// Minimises f from *x in place. Ceres' glog warnings (its line search's harmless ones) are kept
/// to errors: a library does not print.
LbfgsSummary MinimizeLbfgs(const GradientObjective& f, const LbfgsOptions& options, Eigen::VectorXd* x);

}  // namespace rotorguard::planning
