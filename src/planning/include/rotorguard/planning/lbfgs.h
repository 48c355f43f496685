#pragma once
/// Unconstrained minimisation for the penalty formulations of the trajectory optimisers (paper
/// 000, eq. 22; paper 002, eq. 11): Ceres' L-BFGS (GradientProblemSolver) behind a wrapper that
/// treats any non-finite cost or gradient as a failed evaluation, which the line search backs away
/// from (Ceres alone can accept a NaN cost and declare convergence).
#include <Eigen/Core>
#include <functional>
#include <span>
#include <string>

#include "rotorguard/core/config_schema.h"

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

/// Which L-BFGS minimises.
enum class LbfgsMethod {
  /// Ceres' GradientProblemSolver: Wolfe line search (bracketing and zoom), the initial inverse
  /// Hessian scaled by its approximate-eigenvalue estimate; stops once one iteration lowers f by
  /// less than relative_cost_tolerance.
  kCeres,
  /// This library's own: the two-loop recursion over `memory` pairs, a weak-Wolfe line search by
  /// bisection and doubling (Lewis & Overton, "Nonsmooth optimization via quasi-Newton methods",
  /// Math. Prog. 2013), and a stop once f fell by less than relative_cost_tolerance over the last
  /// `past` iterations (liblbfgs' delta test), which one short step does not trigger.
  kLewisOverton,
};

/// As config files write them (stack.planner.lbfgs) and bench planner's --lbfgs.
inline constexpr EnumName<LbfgsMethod> kLbfgsMethodNames[] = {{LbfgsMethod::kCeres, "ceres"},
                                                              {LbfgsMethod::kLewisOverton, "lewis_overton"}};
constexpr std::span<const EnumName<LbfgsMethod>> NamesOf(const LbfgsMethod*) { return kLbfgsMethodNames; }

struct LbfgsOptions {
  int max_iterations = 200;               ///< >= 1
  double relative_cost_tolerance = 1e-4;  ///< stop once f falls by less than this fraction (see LbfgsMethod)
  LbfgsMethod method = LbfgsMethod::kCeres;
  /// kLewisOverton: correction pairs kept, >= 1 (chosen by measurement: CHANGELOG.md, "Choosing the
  /// L-BFGS").
  int memory = 128;
  int past = 3;     ///< kLewisOverton: iterations the decrease test spans, >= 1
  /// Throws ValidationError naming the field (the tolerance in (0, 0.1]).
  void Validate() const;
};

struct LbfgsSummary {
  bool failed = false;  ///< the solver failed (x may still be the best point it reached)
  int iterations = 0;
  int evaluations = 0;
  std::string message;
};

/// Minimises f from *x in place. Ceres' glog warnings (its line search's harmless ones) are kept
/// to errors: a library does not print.
LbfgsSummary MinimizeLbfgs(const GradientObjective& f, const LbfgsOptions& options, Eigen::VectorXd* x);

}  // namespace rotorguard::planning
