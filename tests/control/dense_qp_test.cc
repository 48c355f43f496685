#include "rotorguard/control/dense_qp.h"

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

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

/// A problem near `qp`: its gradient and bounds moved by up to `scale` (what changes between two
/// NMPC calls that share a factorisation).
DenseQp Perturbed(const DenseQp& qp, double scale, Rng& rng) {
  DenseQp next = qp;
  for (int i = 0; i < qp.num_variables(); ++i) {
    next.g[i] += scale * rng.Normal();
    const double shift = 0.1 * scale * rng.Normal();
    next.lb[i] += shift;  // an infinite side stays infinite
    next.ub[i] += shift;
  }
  for (int r = 0; r < qp.num_constraints(); ++r) {
    const double shift = 0.1 * scale * rng.Normal();
    next.lc[r] += shift;
    next.uc[r] += shift;
  }
  return next;
}

/// Options of a solver that starts every solve from the unconstrained minimum: the comparison.
ActiveSetOptions ColdStarts() {
  ActiveSetOptions options;
  options.warm_start = false;
  return options;
}

// Sequences of nearby problems, solved by one solver that starts from its previous active set and
// checked against the brute-force oracle; every few problems a new Hessian is factorised, so both
// the hot start (kept factorisation) and the warm start (rebuilt on the new one) are exercised.
TEST(DenseQp, WarmAndHotStartsMatchBruteForceOnSequencesOfNearbyProblems) {
  Rng rng(99);
  int hot = 0, warm = 0, hot_with_drops = 0;
  for (int sequence = 0; sequence < 40; ++sequence) {
    const int n = 2 + sequence % 4, m = sequence % 3;
    DenseQp qp = RandomQp(n, m, rng);
    DenseQpSolver solver(n, m);
    ASSERT_TRUE(solver.Factorize(qp.H));
    int previous_active = 0;
    for (int step = 0; step < 8; ++step) {
      if (step == 4) {
        const DenseQp other = RandomQp(n, m, rng);
        qp.H = 0.8 * qp.H + 0.2 * other.H;
        ASSERT_TRUE(solver.Factorize(qp.H));
      }
      const DenseQpSummary& s = solver.SolveFactorized(qp);
      ASSERT_EQ(s.status, QpStatus::kSolved) << "sequence " << sequence << " step " << step << ": " << s.BriefReport();
      const Eigen::VectorXd oracle = BruteForce(qp);
      ASSERT_EQ(oracle.size(), n);
      EXPECT_LT((solver.z() - oracle).cwiseAbs().maxCoeff(), 1e-8) << "sequence " << sequence << " step " << step;
      // The first solve has no previous set, and one from an empty set is cold.
      QpStart expected = QpStart::kHot;
      if (step == 0 || (step == 4 && previous_active == 0)) expected = QpStart::kCold;
      if (step == 4 && previous_active > 0) expected = QpStart::kWarm;
      EXPECT_EQ(s.start, expected) << "sequence " << sequence << " step " << step;
      hot += s.start == QpStart::kHot;
      warm += s.start == QpStart::kWarm;
      hot_with_drops += s.start == QpStart::kHot && s.start_active_constraints < previous_active;
      previous_active = s.active_constraints;
      qp = Perturbed(qp, 1.0, rng);
    }
  }
  EXPECT_EQ(hot, 40 * 6);
  EXPECT_GT(warm, 30);
  EXPECT_GT(hot_with_drops, 10);  // the start dropped constraints whose multipliers turned negative
}

// The NMPC's size: 80 variables, 60 general constraints, many active. Warm and hot starts give the
// cold solver's solution and satisfy the KKT conditions, in fewer active-set changes.
TEST(DenseQp, WarmAndHotStartsMatchColdStartsOnLargeProblemsInFewerIterations) {
  Rng rng(11);
  DenseQp qp = RandomQp(80, 60, rng);
  DenseQpSolver warm(80, 60), cold(80, 60, ColdStarts());
  ASSERT_TRUE(warm.Factorize(qp.H) && cold.Factorize(qp.H));
  int warm_iterations = 0, cold_iterations = 0;
  for (int step = 0; step < 30; ++step) {
    if (step % 10 == 5) {  // a new Hessian: the warm start rebuilds the active set on it
      qp.H += 0.1 * RandomQp(80, 60, rng).H;
      ASSERT_TRUE(warm.Factorize(qp.H));
      ASSERT_TRUE(cold.Factorize(qp.H));
    }
    const DenseQpSummary& w = warm.SolveFactorized(qp);
    const DenseQpSummary& c = cold.SolveFactorized(qp);
    ASSERT_EQ(w.status, QpStatus::kSolved) << w.BriefReport();
    ASSERT_EQ(c.status, QpStatus::kSolved) << c.BriefReport();
    EXPECT_EQ(c.start, QpStart::kCold);
    EXPECT_GT(c.active_constraints, 3);
    EXPECT_LT((warm.z() - cold.z()).cwiseAbs().maxCoeff(), 1e-8) << "step " << step << ": " << w.BriefReport();
    ExpectKkt(qp, warm, 1e-7);
    if (step > 0) {
      warm_iterations += w.iterations;
      cold_iterations += c.iterations;
    }
    qp = Perturbed(qp, 0.05, rng);
  }
  EXPECT_LT(warm_iterations, cold_iterations / 3) << warm_iterations << " against " << cold_iterations;
}

// Hot starts on one factorisation are rebuilt from J0 every 50 solves, so that the rotations'
// rounding cannot pile up; a failed solve leaves only the bounds the factorisation placed as the
// next start. Every solve is checked against a cold solver.
TEST(DenseQp, HotStartsAreRebuiltEveryFiftySolvesAndAFailureLeavesThePlacedBounds) {
  Rng rng(23);
  DenseQp qp = RandomQp(30, 10, rng);
  DenseQpSolver solver(30, 10), cold(30, 10, ColdStarts());
  ASSERT_TRUE(solver.Factorize(qp.H) && cold.Factorize(qp.H));
  std::vector<int> warm_steps;
  for (int step = 0; step < 120; ++step) {
    const DenseQpSummary& s = solver.SolveFactorized(qp);
    ASSERT_TRUE(s.IsSolutionUsable()) << s.BriefReport();
    ASSERT_TRUE(cold.SolveFactorized(qp).IsSolutionUsable());
    EXPECT_LT((solver.z() - cold.z()).cwiseAbs().maxCoeff(), 1e-8) << "step " << step;
    if (s.start == QpStart::kWarm) warm_steps.push_back(step);
    EXPECT_EQ(s.start == QpStart::kCold, step == 0) << "step " << step;
    qp = Perturbed(qp, 0.05, rng);
  }
  EXPECT_EQ(warm_steps, (std::vector<int>{51, 102}));
  ASSERT_TRUE(solver.Factorize(qp.H));  // places the active bounds last
  ASSERT_TRUE(cold.Factorize(qp.H));
  ASSERT_TRUE(solver.SolveFactorized(qp).IsSolutionUsable());
  ASSERT_GT(solver.summary().start_active_constraints, 0);
  DenseQp crossed = qp;
  crossed.lb[0] = 1.0;  // above its upper bound
  crossed.ub[0] = 0.0;
  EXPECT_EQ(solver.SolveFactorized(crossed).status, QpStatus::kInfeasible);
  EXPECT_EQ(solver.summary().active_constraints, 0);
  EXPECT_EQ(solver.bound_multipliers().cwiseAbs().maxCoeff(), 0.0);
  const DenseQpSummary& after = solver.SolveFactorized(qp);
  ASSERT_TRUE(after.IsSolutionUsable());
  EXPECT_EQ(after.start, QpStart::kWarm);
  ASSERT_TRUE(cold.SolveFactorized(qp).IsSolutionUsable());
  EXPECT_LT((solver.z() - cold.z()).cwiseAbs().maxCoeff(), 1e-8);
  // A factorisation that fails leaves no active set and no multipliers behind.
  DenseQp indefinite = qp;
  indefinite.H(0, 0) = -1.0;
  EXPECT_EQ(solver.Solve(indefinite).status, QpStatus::kNumericalFailure);
  EXPECT_EQ(solver.bound_multipliers().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(solver.z().cwiseAbs().maxCoeff(), 0.0);
}

// min 1/2 |z|^2 + g'z subject to z >= 0 has z = max(0, -g) (a closed form), and the multipliers
// of the bounds are max(0, g).
TEST(DenseQp, AHotStartDropsTheConstraintsWhoseMultipliersTurnNegative) {
  DenseQp qp(3, 0);
  qp.lb.setZero();
  qp.g << 1.0, 2.0, 3.0;
  DenseQpSolver solver(3, 0);
  ASSERT_TRUE(solver.Solve(qp).IsSolutionUsable());
  EXPECT_EQ(solver.summary().active_constraints, 3);
  EXPECT_LT(solver.z().norm(), 1e-15);
  qp.g << 1.0, -2.0, -4.0;
  const DenseQpSummary& s = solver.SolveFactorized(qp);
  ASSERT_TRUE(s.IsSolutionUsable());
  EXPECT_EQ(s.start, QpStart::kHot);
  EXPECT_EQ(s.start_active_constraints, 1);  // variables 1 and 2 left their bounds
  EXPECT_EQ(s.iterations, 0);                // and the start was the solution
  EXPECT_LT((solver.z() - Eigen::Vector3d(0.0, 2.0, 4.0)).norm(), 1e-14);
  EXPECT_LT((solver.bound_multipliers() - Eigen::Vector3d(1.0, 0.0, 0.0)).norm(), 1e-14);
  // A bound that became infinite binds no more.
  qp.lb[0] = -kInf;
  ASSERT_TRUE(solver.SolveFactorized(qp).IsSolutionUsable());
  EXPECT_EQ(solver.summary().start_active_constraints, 0);
  EXPECT_LT((solver.z() - Eigen::Vector3d(-1.0, 2.0, 4.0)).norm(), 1e-14);
}

TEST(DenseQp, TheSameProblemAgainHotStartsAtItsSolution) {
  Rng rng(5);
  int lower = 0, upper = 0;  // active bounds of either side, placed by the warm start
  for (const auto& [n, m] : {std::pair{80, 60}, std::pair{60, 0}}) {
    const DenseQp qp = RandomQp(n, m, rng);
    DenseQpSolver solver(n, m);
    ASSERT_TRUE(solver.Solve(qp).IsSolutionUsable());
    const Eigen::VectorXd first = solver.z();
    const int active = solver.summary().active_constraints;
    ASSERT_GT(active, 5);
    // Solved again, the problem starts at its solution: all its constraints, no iteration.
    const auto expect_start_at_solution = [&](QpStart start, double tolerance) {
      const DenseQpSummary& s = solver.SolveFactorized(qp);
      ASSERT_TRUE(s.IsSolutionUsable());
      EXPECT_EQ(s.start, start);
      EXPECT_EQ(s.start_active_constraints, active);
      EXPECT_EQ(s.iterations, 0);
      EXPECT_LT((solver.z() - first).cwiseAbs().maxCoeff(), tolerance);
    };
    expect_start_at_solution(QpStart::kHot, 1e-12);
    // Factorised anew, with the active bounds ordered last: the warm start is the solution too.
    ASSERT_TRUE(solver.Factorize(qp.H));
    expect_start_at_solution(QpStart::kWarm, 1e-10);
    lower += (solver.bound_multipliers().array() > 0.0).count();
    upper += (solver.bound_multipliers().array() < 0.0).count();
  }
  EXPECT_GT(lower, 0);
  EXPECT_GT(upper, 0);
}

// A hot start needs the factorisation of the same normals in the same metric: a changed row of an
// active constraint, or a new factorisation, rebuilds the set (a warm start); a failed solve (with
// no bound placed by the factorisation), or warm_start off, starts cold.
TEST(DenseQp, AChangedActiveRowANewFactorisationOrAFailureEndsTheHotStarts) {
  DenseQp qp(2, 1);
  qp.g << -1.0, -1.0;
  qp.C << 1.0, 1.0;
  qp.uc << 1.0;  // z1 + z2 <= 1 binds: z = (0.5, 0.5)
  DenseQpSolver solver(2, 1);
  ASSERT_TRUE(solver.Solve(qp).IsSolutionUsable());
  EXPECT_EQ(solver.summary().start, QpStart::kCold);
  ASSERT_EQ(solver.summary().active_constraints, 1);
  // z1 + 3 z2 <= 1: z = (1, 1) - mu (1, 3) with 4 - 10 mu = 1, so mu = 0.3 and z = (0.7, 0.1).
  qp.C << 1.0, 3.0;
  ASSERT_TRUE(solver.SolveFactorized(qp).IsSolutionUsable());
  EXPECT_EQ(solver.summary().start, QpStart::kWarm);
  EXPECT_EQ(solver.summary().iterations, 0);
  EXPECT_LT((solver.z() - Eigen::Vector2d(0.7, 0.1)).norm(), 1e-14);
  ASSERT_TRUE(solver.SolveFactorized(qp).IsSolutionUsable());
  EXPECT_EQ(solver.summary().start, QpStart::kHot);
  ASSERT_TRUE(solver.Factorize(qp.H));
  ASSERT_TRUE(solver.SolveFactorized(qp).IsSolutionUsable());
  EXPECT_EQ(solver.summary().start, QpStart::kWarm);
  DenseQp crossed = qp;
  crossed.lc << 2.0;  // lc > uc
  EXPECT_EQ(solver.SolveFactorized(crossed).status, QpStatus::kInfeasible);
  EXPECT_EQ(solver.summary().active_constraints, 0);
  ASSERT_TRUE(solver.SolveFactorized(qp).IsSolutionUsable());
  EXPECT_EQ(solver.summary().start, QpStart::kCold);
  DenseQpSolver cold(2, 1, ColdStarts());
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(cold.Solve(qp).IsSolutionUsable());
    EXPECT_EQ(cold.summary().start, QpStart::kCold);
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
  EXPECT_EQ(solver.summary().objective, 0.0);  // not a product with the NaN data
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
