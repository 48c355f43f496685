#include "rotorguard/control/dense_qp.h"

#include <cmath>
#include <limits>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "rotorguard/core/rng.h"

namespace rotorguard::control {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

DenseQp RandomQp(int n, int m, Rng& rng) {
  DenseQp qp(n, m);
  Eigen::MatrixXd M(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) M(i, j) = rng.Normal();
  qp.H = M * M.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n);
  for (int i = 0; i < n; ++i) {
    qp.g[i] = 3.0 * rng.Normal();
    // Some variables free, some one-sided, some boxed; the box always contains a point near 0.
    const double kind = rng.Uniform();
    if (kind < 0.75) qp.lb[i] = -rng.Uniform(0.1, 1.5);
    if (kind > 0.25) qp.ub[i] = rng.Uniform(0.1, 1.5);
  }
  for (int r = 0; r < m; ++r) {
    for (int j = 0; j < n; ++j) qp.C(r, j) = rng.Normal();
    qp.lc[r] = -rng.Uniform(0.2, 2.0);
    if (rng.Uniform() < 0.6) qp.uc[r] = rng.Uniform(0.2, 2.0);
  }
  return qp;
}

double Objective(const DenseQp& qp, const Eigen::VectorXd& z) { return 0.5 * z.dot(qp.H * z) + qp.g.dot(z); }

/// Brute-force oracle, independent of the solver: for every choice of active sides (each bound and
/// each general constraint inactive, at its lower or at its upper side), minimise the objective on
/// that face by a direct KKT solve; the optimum is the feasible candidate of least objective.
Eigen::VectorXd BruteForce(const DenseQp& qp) {
  const int n = qp.num_variables(), m = qp.num_constraints(), total = n + m;
  long combos = 1;
  for (int i = 0; i < total; ++i) combos *= 3;
  double best = kInf;
  Eigen::VectorXd best_z;
  for (long code = 0; code < combos; ++code) {
    std::vector<Eigen::VectorXd> rows;
    std::vector<double> rhs;
    long c = code;
    bool valid = true;
    for (int i = 0; i < total && valid; ++i) {
      const int side = static_cast<int>(c % 3);
      c /= 3;
      if (side == 0) continue;
      const double bound = i < n ? (side == 1 ? qp.lb[i] : qp.ub[i]) : (side == 1 ? qp.lc[i - n] : qp.uc[i - n]);
      if (!std::isfinite(bound)) valid = false;
      rows.push_back(i < n ? Eigen::VectorXd(Eigen::VectorXd::Unit(n, i)) : Eigen::VectorXd(qp.C.row(i - n).transpose()));
      rhs.push_back(bound);
    }
    if (!valid || static_cast<int>(rows.size()) > n) continue;
    const int a = static_cast<int>(rows.size());
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n + a, n + a);
    Eigen::VectorXd b(n + a);
    K.topLeftCorner(n, n) = qp.H;
    b.head(n) = -qp.g;
    for (int k = 0; k < a; ++k) {
      K.block(0, n + k, n, 1) = rows[k];
      K.block(n + k, 0, 1, n) = rows[k].transpose();
      b[n + k] = rhs[k];
    }
    Eigen::FullPivLU<Eigen::MatrixXd> lu(K);
    if (!lu.isInvertible()) continue;
    const Eigen::VectorXd z = lu.solve(b).head(n);
    const Eigen::VectorXd cz = qp.C * z;
    const double tol = 1e-9;
    bool feasible = true;
    for (int i = 0; i < n; ++i) feasible = feasible && z[i] >= qp.lb[i] - tol && z[i] <= qp.ub[i] + tol;
    for (int i = 0; i < m; ++i) feasible = feasible && cz[i] >= qp.lc[i] - tol && cz[i] <= qp.uc[i] + tol;
    if (feasible && Objective(qp, z) < best) {
      best = Objective(qp, z);
      best_z = z;
    }
  }
  return best_z;
}

TEST(DenseQp, MatchesBruteForceOnRandomSmallProblems) {
  Rng rng(2024);
  int with_active = 0;
  for (int trial = 0; trial < 150; ++trial) {
    const int n = 2 + trial % 4, m = trial % 3;
    const DenseQp qp = RandomQp(n, m, rng);
    DenseQpSolver solver(n, m);
    const DenseQpSummary& s = solver.Solve(qp);
    ASSERT_EQ(s.status, QpStatus::kSolved) << "trial " << trial << ": " << s.BriefReport();
    const Eigen::VectorXd oracle = BruteForce(qp);
    ASSERT_EQ(oracle.size(), n) << "trial " << trial;
    EXPECT_LT((solver.z() - oracle).cwiseAbs().maxCoeff(), 1e-8) << "trial " << trial;
    with_active += s.active_constraints > 0;
  }
  EXPECT_GT(with_active, 75);  // the cases exercise the active-set logic, not just the unconstrained minimum
}

/// KKT conditions checked independently of the solver's internals.
void ExpectKkt(const DenseQp& qp, const DenseQpSolver& solver, double tol) {
  const Eigen::VectorXd& z = solver.z();
  const Eigen::VectorXd& yb = solver.bound_multipliers();
  const Eigen::VectorXd& yc = solver.constraint_multipliers();
  const Eigen::VectorXd stationarity = qp.H * z + qp.g - yb - qp.C.transpose() * yc;
  EXPECT_LT(stationarity.cwiseAbs().maxCoeff(), tol);
  const Eigen::VectorXd cz = qp.C * z;
  for (int i = 0; i < qp.num_variables(); ++i) {
    EXPECT_GE(z[i], qp.lb[i] - tol);
    EXPECT_LE(z[i], qp.ub[i] + tol);
    if (yb[i] > tol) {
      EXPECT_NEAR(z[i], qp.lb[i], tol);  // positive multiplier: at the lower bound
    }
    if (yb[i] < -tol) {
      EXPECT_NEAR(z[i], qp.ub[i], tol);  // negative: at the upper bound
    }
  }
  for (int i = 0; i < qp.num_constraints(); ++i) {
    EXPECT_GE(cz[i], qp.lc[i] - tol);
    EXPECT_LE(cz[i], qp.uc[i] + tol);
    if (yc[i] > tol) {
      EXPECT_NEAR(cz[i], qp.lc[i], tol);
    }
    if (yc[i] < -tol) {
      EXPECT_NEAR(cz[i], qp.uc[i], tol);
    }
  }
}

TEST(DenseQp, SatisfiesKktOnLargeProblemsWithManyActiveConstraints) {
  Rng rng(7);
  for (int trial = 0; trial < 10; ++trial) {
    const DenseQp qp = RandomQp(80, 60, rng);
    DenseQpSolver solver(80, 60);
    const DenseQpSummary& s = solver.Solve(qp);
    ASSERT_EQ(s.status, QpStatus::kSolved) << s.BriefReport();
    EXPECT_GT(s.active_constraints, 5);
    ExpectKkt(qp, solver, 1e-7);
  }
}

TEST(DenseQp, UnconstrainedMinimumWhenNothingBinds) {
  DenseQp qp(3, 0);
  qp.H.setZero();
  qp.H.diagonal() << 2.0, 4.0, 8.0;
  qp.g << -2.0, 4.0, 0.0;
  DenseQpSolver solver(3, 0);
  ASSERT_TRUE(solver.Solve(qp).IsSolutionUsable());
  EXPECT_LT((solver.z() - Eigen::Vector3d(1.0, -1.0, 0.0)).norm(), 1e-14);
  EXPECT_EQ(solver.summary().active_constraints, 0);
}

TEST(DenseQp, ReportsInfeasibleConstraints) {
  DenseQp qp(2, 2);
  qp.C << 1.0, 1.0, 1.0, 1.0;
  qp.lc << 1.0, -kInf;  // x + y >= 1
  qp.uc << kInf, 0.0;   // x + y <= 0
  DenseQpSolver solver(2, 2);
  EXPECT_EQ(solver.Solve(qp).status, QpStatus::kInfeasible);
  DenseQp crossed(1, 0);
  crossed.lb << 1.0;
  crossed.ub << 0.0;
  DenseQpSolver one(1, 0);
  EXPECT_EQ(one.Solve(crossed).status, QpStatus::kInfeasible);
}

TEST(DenseQp, NonFiniteOrIndefiniteDataIsANumericalFailureNotACrash) {
  DenseQp qp(2, 0);
  qp.g << std::nan(""), 1.0;
  DenseQpSolver solver(2, 0);
  EXPECT_EQ(solver.Solve(qp).status, QpStatus::kNumericalFailure);
  EXPECT_TRUE(solver.z().allFinite());
  qp.g << 0.0, 1.0;
  qp.H << 1.0, 0.0, 0.0, -1.0;
  EXPECT_EQ(solver.Solve(qp).status, QpStatus::kNumericalFailure);
  qp.H.setIdentity();
  qp.ub[1] = std::nan("");  // a NaN bound is an error, not a missing bound
  EXPECT_EQ(solver.Solve(qp).status, QpStatus::kNumericalFailure);
}

TEST(DenseQp, SummaryExplainsAnUnsolvedSolver) {
  const DenseQpSolver solver(2, 0);
  EXPECT_EQ(solver.summary().status, QpStatus::kNotSolved);
  EXPECT_NE(solver.summary().BriefReport().find("Solve() was not called"), std::string::npos);
}

}  // namespace
}  // namespace rotorguard::control
