#include "rotorguard/planning/lbfgs.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "rotorguard/core/rng.h"

namespace rotorguard::planning {
namespace {

LbfgsOptions LewisOverton(double tolerance) {
  LbfgsOptions o;
  o.method = LbfgsMethod::kLewisOverton;
  o.max_iterations = 500;
  o.relative_cost_tolerance = tolerance;
  return o;
}

// A strictly convex quadratic, f = ½ xᵀA x − bᵀx + 10, whose minimiser solves A x = b: both
// methods reach it from a random start.
TEST(Lbfgs, BothMethodsReachTheMinimiserOfAQuadratic) {
  Rng rng(11);
  const int n = 12;
  Eigen::MatrixXd m(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) m(i, j) = rng.Uniform(-1.0, 1.0);
  }
  const Eigen::MatrixXd a = m * m.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b(i) = rng.Uniform(-2.0, 2.0);
  const Eigen::VectorXd minimiser = a.ldlt().solve(b);
  const GradientObjective f = [&](const Eigen::VectorXd& x, Eigen::VectorXd* g) {
    if (g) *g = a * x - b;
    return 0.5 * x.dot(a * x) - b.dot(x) + 10.0;
  };
  for (const LbfgsMethod method : {LbfgsMethod::kCeres, LbfgsMethod::kLewisOverton}) {
    LbfgsOptions o = LewisOverton(1e-14);
    o.method = method;
    Eigen::VectorXd x = Eigen::VectorXd::Constant(n, 3.0);
    const LbfgsSummary s = MinimizeLbfgs(f, o, &x);
    EXPECT_FALSE(s.failed) << s.message;
    EXPECT_LT((x - minimiser).norm(), 1e-5 * minimiser.norm()) << static_cast<int>(method) << ": " << s.message;
  }
}

// Rosenbrock's valley from the classic start (−1.2, 1): the minimum is (1, 1).
TEST(Lbfgs, LewisOvertonFollowsRosenbrocksValleyToItsMinimum) {
  const GradientObjective f = [](const Eigen::VectorXd& x, Eigen::VectorXd* g) {
    const double u = 1.0 - x(0), v = x(1) - x(0) * x(0);
    if (g) {
      g->resize(2);
      (*g)(0) = -2.0 * u - 400.0 * x(0) * v;
      (*g)(1) = 200.0 * v;
    }
    return u * u + 100.0 * v * v + 1.0;  // + 1: the relative test then measures against 1 at the end
  };
  Eigen::VectorXd x(2);
  x << -1.2, 1.0;
  const LbfgsSummary s = MinimizeLbfgs(f, LewisOverton(1e-15), &x);
  EXPECT_FALSE(s.failed) << s.message;
  EXPECT_LT(std::hypot(x(0) - 1.0, x(1) - 1.0), 1e-5) << x.transpose() << ": " << s.message;
  EXPECT_GT(s.iterations, 10);
  EXPECT_GE(s.evaluations, s.iterations);
}

// Where the cost has no value (NaN beyond x = 4) the line search backs off, as it does from a
// cost that rises: the minimum at 3 is found from 0 although doubling steps overshoot into NaN.
TEST(Lbfgs, LewisOvertonBacksAwayFromNonFiniteCosts) {
  const GradientObjective f = [](const Eigen::VectorXd& x, Eigen::VectorXd* g) {
    if (x(0) > 4.0) return std::numeric_limits<double>::quiet_NaN();
    if (g) *g = Eigen::VectorXd::Constant(1, 2.0 * (x(0) - 3.0));
    return (x(0) - 3.0) * (x(0) - 3.0) + 1.0;
  };
  Eigen::VectorXd x = Eigen::VectorXd::Zero(1);
  const LbfgsSummary s = MinimizeLbfgs(f, LewisOverton(1e-14), &x);
  EXPECT_FALSE(s.failed) << s.message;
  EXPECT_NEAR(x(0), 3.0, 1e-5) << s.message;
  Eigen::VectorXd nowhere = Eigen::VectorXd::Constant(1, 5.0);
  EXPECT_TRUE(MinimizeLbfgs(f, LewisOverton(1e-6), &nowhere).failed) << "a start without a cost";
}

TEST(Lbfgs, InvalidOptionsAreNamed) {
  const GradientObjective f = [](const Eigen::VectorXd& x, Eigen::VectorXd* g) {
    if (g) *g = 2.0 * x;
    return x.squaredNorm();
  };
  Eigen::VectorXd x = Eigen::VectorXd::Ones(2);
  LbfgsOptions o;
  o.memory = 0;
  try {
    MinimizeLbfgs(f, o, &x);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("LbfgsOptions::memory"), std::string::npos) << e.what();
  }
  o = LbfgsOptions{};
  o.past = 0;
  EXPECT_THROW(MinimizeLbfgs(f, o, &x), std::invalid_argument);
}

}  // namespace
}  // namespace rotorguard::planning
