#include "rotorguard/control/ocp_qp.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "rotorguard/control/riccati_qp.h"
#include "ocp_qp_oracle.h"
#include "rotorguard/core/rng.h"
#include "test_util.h"

namespace rotorguard::control {
namespace {

using rotorguard::testing::MatricesNear;

/// The solver's condensed problem equals the naive construction, to rounding.
void ExpectCondensedEqualsNaive(const OcpQp& qp) {
  CondensingQpSolver solver(qp.dims);
  solver.Solve(qp);
  Eigen::MatrixXd H, C;
  Eigen::VectorXd g, lc, uc;
  NaiveCondense(qp, &H, &g, &C, &lc, &uc);
  EXPECT_TRUE(MatricesNear(solver.condensed().H, H, 1e-9 * H.cwiseAbs().maxCoeff()));
  EXPECT_TRUE(MatricesNear(solver.condensed().g, g, 1e-9 * g.cwiseAbs().maxCoeff()));
  EXPECT_TRUE(MatricesNear(solver.condensed().C, C, 1e-12 * C.cwiseAbs().maxCoeff()));
  EXPECT_TRUE(MatricesNear(solver.condensed().lc, lc, 1e-9));
  EXPECT_TRUE(MatricesNear(solver.condensed().uc, uc, 1e-9));
}

TEST(CondensingQp, CondensedProblemEqualsTheNaiveConstruction) {
  Rng rng(11);
  ExpectCondensedEqualsNaive(RandomOcp(7, 5, 2, {1, 3}, rng));
}

TEST(CondensingQp, TheNmpcSizedInstantiationEqualsTheNaiveConstruction) {
  // nx = 17, nu = 4 takes the compile-time-sized code path.
  Rng rng(12);
  ExpectCondensedEqualsNaive(RandomOcp(6, 17, 4, {10, 11, 12}, rng));
}

TEST(CondensingQp, UnconstrainedSolutionSolvesTheFullSpaceKktSystem) {
  // Without binding bounds the optimum solves the equality-constrained KKT system in all
  // variables [u_0..u_{N-1}, x_1..x_N] with the dynamics as constraints: an independent solve.
  Rng rng(5);
  const int N = 6, nx = 4, nu = 2;
  OcpQp qp = RandomOcp(N, nx, nu, {}, rng);
  for (auto& b : qp.u_lower) b.setConstant(-1e9);
  for (auto& b : qp.u_upper) b.setConstant(1e9);
  CondensingQpSolver solver(qp.dims);
  ASSERT_TRUE(solver.Solve(qp).IsSolutionUsable());
  const int nv = N * nu + N * nx, ne = N * nx;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nv + ne, nv + ne);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nv + ne);
  const auto ui = [&](int k) { return k * nu; };
  const auto xi = [&](int k) { return N * nu + (k - 1) * nx; };  // k = 1..N
  for (int k = 0; k < N; ++k) {
    K.block(ui(k), ui(k), nu, nu) = qp.R[k];
    rhs.segment(ui(k), nu) = -qp.r[k];
    K.block(xi(k + 1), xi(k + 1), nx, nx) = qp.Q[k + 1];
    rhs.segment(xi(k + 1), nx) = -qp.q[k + 1];
    // x_{k+1} - A_k x_k - B_k u_k = c_k (x_0 is data).
    const int row = nv + k * nx;
    K.block(row, xi(k + 1), nx, nx) = Eigen::MatrixXd::Identity(nx, nx);
    K.block(row, ui(k), nx, nu) = -qp.B[k];
    rhs.segment(row, nx) = qp.c[k];
    if (k == 0) {
      rhs.segment(row, nx) += qp.A[0] * qp.x0;
    } else {
      K.block(row, xi(k), nx, nx) = -qp.A[k];
    }
  }
  K.topRightCorner(nv, ne) = K.bottomLeftCorner(ne, nv).transpose();
  const Eigen::VectorXd sol = K.fullPivLu().solve(rhs);
  for (int k = 0; k < N; ++k) {
    EXPECT_TRUE(MatricesNear(solver.u()[k], sol.segment(ui(k), nu), 1e-8)) << "u_" << k;
    EXPECT_TRUE(MatricesNear(solver.x()[k + 1], sol.segment(xi(k + 1), nx), 1e-8)) << "x_" << k + 1;
  }
}

TEST(CondensingQp, RespectsInputAndStateBoundsWhenTheyBind) {
  Rng rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    OcpQp qp = RandomOcp(10, 6, 3, {0, 2, 5}, rng);
    // Feasible by construction (mild dynamics from a small start, where zero input stays inside
    // the bounds), and a cost that pulls the bounded states to +-4, beyond their +-1.5 bounds.
    qp.x0 *= 0.1;
    Eigen::VectorXd target = Eigen::VectorXd::Zero(6);
    target << 4.0, 0.0, -4.0, 0.0, 0.0, 4.0;
    for (int k = 0; k < 10; ++k) {
      qp.A[k] = Eigen::MatrixXd::Identity(6, 6) + 0.02 * (qp.A[k] - Eigen::MatrixXd::Identity(6, 6));
      qp.c[k].setZero();
    }
    for (int k = 0; k <= 10; ++k) qp.q[k] = -qp.Q[k] * target;
    CondensingQpSolver solver(qp.dims);
    const OcpQpSummary& s = solver.Solve(qp);
    ASSERT_TRUE(s.IsSolutionUsable()) << s.BriefReport();
    EXPECT_GT(s.active_constraints, 0);
    for (int k = 0; k < 10; ++k) {
      EXPECT_LE(solver.u()[k].cwiseAbs().maxCoeff(), 0.6 + 1e-9);
      for (int b : {0, 2, 5}) EXPECT_LE(std::abs(solver.x()[k + 1][b]), 1.5 + 1e-8);
    }
    // The dynamics hold exactly along the returned trajectory.
    for (int k = 0; k < 10; ++k) {
      EXPECT_TRUE(MatricesNear(solver.x()[k + 1], qp.A[k] * solver.x()[k] + qp.B[k] * solver.u()[k] + qp.c[k], 1e-12));
    }
  }
}

TEST(CondensingQp, FeedbackOnAPreparedProblemEqualsAFreshSolveAtTheMeasuredState) {
  // The real-time iteration's split: prepare around a predicted x0, feed back the measured one.
  // The feedback shifts the condensed gradient and state-bound rows by the measured state's free
  // response; the oracle is the QP condensed afresh at the measured state. The cost pulls the
  // bounded states beyond their +-1.5 so that state bounds bind; a one-stage horizon and a
  // problem without state bounds are the edge cases. Each split solver feeds back twice before
  // the compared call (nothing may carry over between feedbacks).
  Rng rng(21);
  struct Case {
    int N, nx, nu;
    std::vector<int> bounded;
  };
  for (const Case& c : {Case{8, 6, 2, {0, 3}}, Case{8, 17, 4, {0, 3}}, Case{1, 6, 2, {0, 3}}, Case{8, 6, 2, {}}}) {
    const OcpQp qp = OcpPulledAgainstItsStateBounds(c.N, c.nx, c.nu, c.bounded, rng);
    const std::string name = fmt::format("N {} nx {} bounds {}", c.N, c.nx, c.bounded.size());
    CondensingQpSolver split(qp.dims), fresh(qp.dims);
    split.Prepare(qp);
    for (int i = 0; i < 2; ++i) split.Feedback(qp.x0 + 0.3 * RandomMatrix(c.nx, 1, rng));
    const Eigen::VectorXd measured = qp.x0 + 0.05 * RandomMatrix(c.nx, 1, rng);
    const OcpQpSummary& s = split.Feedback(measured);
    ASSERT_TRUE(s.IsSolutionUsable()) << name << ": " << s.BriefReport();
    OcpQp measured_qp = qp;
    measured_qp.x0 = measured;
    ASSERT_TRUE(fresh.Solve(measured_qp).IsSolutionUsable()) << name;
    const DenseQp &shifted = split.condensed(), &condensed = fresh.condensed();
    EXPECT_TRUE(MatricesNear(shifted.g, condensed.g, 1e-10)) << name;
    if (!c.bounded.empty()) {
      EXPECT_TRUE(MatricesNear(shifted.lc, condensed.lc, 1e-10)) << name;
      EXPECT_TRUE(MatricesNear(shifted.uc, condensed.uc, 1e-10)) << name;
      if (c.N > 1) {  // the state bounds are part of the compared solution
        EXPECT_GT(StateBoundsAtTheirLimit(fresh.x(), c.bounded), 0) << name;
      }
    }
    for (int k = 0; k < c.N; ++k) EXPECT_TRUE(MatricesNear(split.u()[k], fresh.u()[k], 1e-9)) << name << " u_" << k;
    EXPECT_TRUE(MatricesNear(split.x()[c.N], fresh.x()[c.N], 1e-9)) << name;
  }
}

// Inputs fixed by equal bounds (a failed rotor: u_bar_i = 0) are eliminated before the dense
// solve. The oracle: the naively condensed QP with those bounds, solved whole by the dense
// active-set solver. One solver object runs through patterns in turn (a rotor, then another
// stage pattern, then none, then the first again), with the feedback at a measured state.
TEST(CondensingQp, InputsFixedByEqualBoundsGiveTheSolutionOfTheWholeQp) {
  Rng rng(33);
  // State bounds bind too: their rows carry the fixed inputs' share.
  const OcpQp base = OcpPulledAgainstItsStateBounds(8, 6, 3, {0, 3}, rng);
  CondensingQpSolver solver(base.dims);
  int compared = 0;
  for (int pattern : {0, 1, 2, 0}) {
    OcpQp qp = base;
    for (int k = 0; k < 8; ++k) {
      if (pattern == 0) qp.u_lower[k][1] = qp.u_upper[k][1] = 0.25;                // input 1 held at every stage
      if (pattern == 1 && k % 3 == 0) qp.u_lower[k][2] = qp.u_upper[k][2] = -0.1;  // input 2 at some
    }
    const Eigen::VectorXd measured = qp.x0 + 0.05 * RandomMatrix(6, 1, rng);
    solver.Prepare(qp);
    const OcpQpSummary& s = solver.Feedback(measured);
    ASSERT_TRUE(s.IsSolutionUsable()) << s.BriefReport();
    OcpQp measured_qp = qp;
    measured_qp.x0 = measured;
    DenseQp whole(8 * 3, 8 * 2);
    NaiveCondense(measured_qp, &whole.H, &whole.g, &whole.C, &whole.lc, &whole.uc);
    for (int k = 0; k < 8; ++k) {
      whole.lb.segment(3 * k, 3) = qp.u_lower[k];
      whole.ub.segment(3 * k, 3) = qp.u_upper[k];
    }
    DenseQpSolver oracle(8 * 3, 8 * 2);
    ASSERT_TRUE(oracle.Solve(whole).IsSolutionUsable());
    for (int k = 0; k < 8; ++k) {
      EXPECT_TRUE(MatricesNear(solver.u()[k], oracle.z().segment(3 * k, 3), 1e-8))
          << "pattern " << pattern << " u_" << k;
      if (pattern == 0) {
        EXPECT_EQ(solver.u()[k][1], 0.25);  // exactly, not to a tolerance
      }
      ++compared;
    }
    EXPECT_GE(s.active_constraints, pattern == 0 ? 8 : (pattern == 1 ? 3 : 0)) << "the fixed inputs count as active";
    EXPECT_GT(StateBoundsAtTheirLimit(solver.x(), {0, 3}), 0) << "pattern " << pattern;
  }
  EXPECT_EQ(compared, 32);
}

// The mixed-level iteration's cheap preparation: a QP whose matrices are the last prepared ones and
// whose vectors (x0, c, q, r, input and state bounds) are new. The oracle is a fresh solver that
// condenses and factorises the new QP whole. One solver runs through the steps below, each fed
// back at a measured state: updates of the whole QP and of the reduced one (fixed inputs at new
// values: their shares of the gradient and constraint rows change), and the pattern changes in
// between (an input fixed, another fixed, one freed), which take a whole preparation.
TEST(CondensingQp, PreparingOnlyTheVectorsEqualsAWholePreparation) {
  Rng rng(47);
  const OcpQp base = OcpPulledAgainstItsStateBounds(8, 17, 4, {0, 3}, rng);
  struct Step {
    double held1, held3;  // input 1 at every stage and input 3 at even ones, NaN: free
  };
  const double kFree = std::nan("");
  const Step steps[] = {{kFree, kFree}, {0.2, kFree}, {0.35, kFree}, {0.35, -0.1},
                        {0.2, -0.25},   {0.2, kFree}, {0.3, kFree}};
  CondensingQpSolver reusing(base.dims);
  ASSERT_NE(reusing.Prepare(base).status, QpStatus::kNumericalFailure);
  OcpQp qp = base;
  int step = 0;
  for (const Step& st : steps) {
    qp.x0 = base.x0 + 0.05 * RandomMatrix(17, 1, rng);
    for (int k = 0; k < 8; ++k) {
      qp.c[k] = RandomMatrix(17, 1, rng, 0.05);
      qp.r[k] = RandomMatrix(4, 1, rng, 0.3);
      qp.u_lower[k].setConstant(-0.6 + 0.1 * rng.Uniform());
      qp.u_upper[k].setConstant(0.6 - 0.1 * rng.Uniform());
      if (!std::isnan(st.held1)) qp.u_lower[k][1] = qp.u_upper[k][1] = st.held1;
      if (!std::isnan(st.held3) && k % 2 == 0) qp.u_lower[k][3] = qp.u_upper[k][3] = st.held3;
    }
    const bool last = step + 1 == static_cast<int>(std::size(steps));
    for (int k = 0; k <= 8; ++k) {
      qp.q[k] = base.q[k] + RandomMatrix(17, 1, rng, 0.3);
      qp.x_lower[k].setConstant(last ? -1.5 : -1.5 - 0.2 * rng.Uniform());  // the last: back at +-1.5
      qp.x_upper[k].setConstant(last ? 1.5 : 1.5 + 0.2 * rng.Uniform());
    }
    ASSERT_NE(reusing.PrepareVectors(qp).status, QpStatus::kNumericalFailure) << "step " << step;
    const Eigen::VectorXd measured = qp.x0 + 0.02 * RandomMatrix(17, 1, rng);
    const OcpQpSummary& s = reusing.Feedback(measured);
    ASSERT_TRUE(s.IsSolutionUsable()) << "step " << step << ": " << s.BriefReport();
    // The steps that keep the last one's fixed inputs keep its factorisation, and the dense
    // solver starts from its last active set with that set's factorisation; a new pattern is a
    // new reduced solver, which starts cold.
    EXPECT_EQ(s.start, step == 2 || step == 4 || step == 6 ? QpStart::kHot : QpStart::kCold) << "step " << step;
    OcpQp measured_qp = qp;
    measured_qp.x0 = measured;
    CondensingQpSolver fresh(qp.dims);
    ASSERT_TRUE(fresh.Solve(measured_qp).IsSolutionUsable()) << "step " << step;
    EXPECT_TRUE(MatricesNear(reusing.condensed().g, fresh.condensed().g, 1e-9)) << "step " << step;
    EXPECT_TRUE(MatricesNear(reusing.condensed().lc, fresh.condensed().lc, 1e-10)) << "step " << step;
    for (int k = 0; k < 8; ++k) {
      EXPECT_TRUE(MatricesNear(reusing.u()[k], fresh.u()[k], 1e-9)) << "step " << step << " u_" << k;
      if (!std::isnan(st.held1)) {
        EXPECT_EQ(reusing.u()[k][1], st.held1) << "step " << step;
      }
    }
    EXPECT_TRUE(MatricesNear(reusing.x()[8], fresh.x()[8], 1e-9)) << "step " << step;
    if (last) {
      EXPECT_GT(StateBoundsAtTheirLimit(fresh.x(), {0, 3}), 0) << "the state bounds take part";
    }
    ++step;
  }
}

// What the cheap preparation keeps: handed other matrices (against its contract), it leaves the
// condensed Hessian bit for bit as prepared, where a whole preparation changes it; a change of the
// fixed inputs makes it prepare whole.
TEST(CondensingQp, PreparingOnlyTheVectorsKeepsTheCondensedHessian) {
  Rng rng(49);
  const OcpQp qp = OcpPulledAgainstItsStateBounds(6, 6, 2, {0}, rng);
  CondensingQpSolver solver(qp.dims);
  solver.Prepare(qp);
  const Eigen::MatrixXd prepared = solver.condensed().H;
  OcpQp other = qp;
  other.A[2] += 0.1 * RandomMatrix(6, 6, rng);
  solver.PrepareVectors(other);
  EXPECT_TRUE(MatricesNear(solver.condensed().H, prepared, 0.0)) << "the Hessian was not condensed again";
  other.u_lower[0][1] = other.u_upper[0][1] = 0.1;  // an input fixed: a whole preparation
  solver.PrepareVectors(other);
  EXPECT_FALSE(MatricesNear(solver.condensed().H, prepared, 1e-6)) << "condensed with the new matrices";
}

TEST(CondensingQp, PreparingOnlyTheVectorsWithoutAPreparationPreparesWhole) {
  Rng rng(48);
  const OcpQp qp = OcpPulledAgainstItsStateBounds(6, 6, 2, {0}, rng);
  CondensingQpSolver first(qp.dims), whole(qp.dims);
  ASSERT_NE(first.PrepareVectors(qp).status, QpStatus::kNumericalFailure);
  whole.Prepare(qp);
  EXPECT_TRUE(MatricesNear(first.condensed().H, whole.condensed().H, 0.0));
  ASSERT_TRUE(first.Feedback(qp.x0).IsSolutionUsable());
  ASSERT_TRUE(whole.Feedback(qp.x0).IsSolutionUsable());
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(MatricesNear(first.u()[k], whole.u()[k], 0.0)) << "u_" << k;
}

TEST(CondensingQp, RejectsMismatchedDimensionsAndBadDims) {
  Rng rng(1);
  const OcpQp qp = RandomOcp(4, 3, 1, {}, rng);
  CondensingQpSolver solver(OcpQpDims{5, 3, 1, {}});
  EXPECT_THROW(solver.Solve(qp), std::invalid_argument);
  EXPECT_THROW(OcpQp(OcpQpDims{0, 3, 1, {}}), std::invalid_argument);
  EXPECT_THROW(OcpQp(OcpQpDims{4, 3, 1, {3}}), std::invalid_argument);
}

// ---- RiccatiQpSolver: the stage form, against oracles independent of its recursions.

/// ExpectKktOfTheNaiveCondensing at the Riccati solver's inputs and multipliers, and its states the
/// inputs' trajectory, exactly. Returns the number of bounds active at the point.
int ExpectKktOfTheNaiveCondensing(const OcpQp& qp, const RiccatiQpSolver& solver) {
  const int N = qp.dims.horizon, nu = qp.dims.nu, nbx = static_cast<int>(qp.dims.state_bound_index.size());
  Eigen::VectorXd u(N * nu), yu(N * nu), yx(N * nbx);
  for (int k = 0; k < N; ++k) {
    u.segment(k * nu, nu) = solver.u()[k];
    yu.segment(k * nu, nu) = solver.input_multipliers()[k];
    yx.segment(k * nbx, nbx) = solver.state_multipliers()[k + 1];
  }
  for (int k = 0; k < N; ++k) {
    EXPECT_TRUE(MatricesNear(solver.x()[k + 1], qp.A[k] * solver.x()[k] + qp.B[k] * solver.u()[k] + qp.c[k], 1e-12));
  }
  return ExpectKktOfTheNaiveCondensing(qp, u, yu, yx);
}

TEST(RiccatiQp, UnconstrainedSolutionEqualsTheCondensingSolvers) {
  // No bound binds: the minimum of the dynamics-constrained quadratic, which both solvers compute
  // by different factorisations (Riccati; condensing and Cholesky).
  Rng rng(43);
  for (int trial = 0; trial < 5; ++trial) {
    OcpQp qp = RandomOcp(15, 17, 4, {2, 7}, rng);
    for (int k = 0; k < 15; ++k) {
      qp.u_lower[k].setConstant(-1e9);
      qp.u_upper[k].setConstant(1e9);
      qp.x_lower[k + 1].setConstant(-1e12);
      qp.x_upper[k + 1].setConstant(1e12);
    }
    RiccatiQpSolver riccati(qp.dims);
    CondensingQpSolver condensing(qp.dims);
    ASSERT_TRUE(riccati.Solve(qp).IsSolutionUsable());
    ASSERT_TRUE(condensing.Solve(qp).IsSolutionUsable());
    EXPECT_EQ(riccati.summary().active_constraints, 0);
    for (int k = 0; k < 15; ++k) {
      EXPECT_TRUE(MatricesNear(riccati.u()[k], condensing.u()[k], 1e-8 * (1.0 + condensing.u()[k].norm())));
    }
  }
}

TEST(RiccatiQp, BoundsWhoseNormalsAreDependentAreHandled) {
  // x_{k+1}[0] = u_k[0] exactly, and both are bounded by the same +-0.6: the two bounds of a pair
  // are the same constraint, so at most one can enter the active set. A cost pulling x[0] to 4
  // makes them bind. Oracle: the KKT conditions and the condensing solver.
  Rng rng(53);
  OcpQp qp = OcpPulledAgainstItsStateBounds(6, 4, 2, {0}, rng);
  for (int k = 0; k < 6; ++k) {
    qp.A[k].row(0).setZero();
    qp.B[k].row(0) << 1.0, 0.0;
    qp.c[k][0] = 0.0;
    qp.x_lower[k + 1][0] = -0.6;
    qp.x_upper[k + 1][0] = 0.6;
  }
  RiccatiQpSolver solver(qp.dims);
  const OcpQpSummary& s = solver.Solve(qp);
  ASSERT_TRUE(s.IsSolutionUsable()) << s.BriefReport();
  ExpectKktOfTheNaiveCondensing(qp, solver);
  CondensingQpSolver condensing(qp.dims);
  ASSERT_TRUE(condensing.Solve(qp).IsSolutionUsable());
  int at_bound = 0;
  for (int k = 0; k < 6; ++k) {
    EXPECT_TRUE(MatricesNear(solver.u()[k], condensing.u()[k], 1e-8)) << "u_" << k;
    at_bound += std::abs(solver.u()[k][0] - 0.6) < 1e-9;
  }
  EXPECT_GT(at_bound, 0) << "the pair must bind";
}

TEST(RiccatiQp, InputsFixedByEqualBoundsAreHeldExactlyAndTheKktConditionsHold) {
  // A failed rotor's inputs: bounds equal at every stage (pattern 0) or some (pattern 1), with state
  // bounds binding. The fixed inputs leave the recursion and must come out exactly at their value,
  // with the multipliers that make the whole QP's KKT conditions hold. Then a preparation of the
  // vectors alone with the fixed values moved, and one whose fixed inputs changed (a whole one),
  // against fresh solves.
  Rng rng(61);
  const OcpQp base = OcpPulledAgainstItsStateBounds(8, 6, 3, {0, 3}, rng);
  RiccatiQpSolver solver(base.dims);
  int compared = 0;
  for (int pattern : {0, 1, 1, 2, 0}) {
    OcpQp qp = base;
    for (int k = 0; k < 8; ++k) {
      if (pattern == 0) qp.u_lower[k][1] = qp.u_upper[k][1] = 0.25;                                  // every stage
      if (pattern == 1 && k % 3 == 0) qp.u_lower[k][2] = qp.u_upper[k][2] = -0.1 + 0.01 * compared;  // some
    }
    const OcpQpSummary& s = solver.PrepareVectors(qp);  // whole when the fixed inputs changed
    ASSERT_NE(s.status, QpStatus::kNumericalFailure);
    ASSERT_TRUE(solver.Feedback(qp.x0).IsSolutionUsable()) << solver.summary().BriefReport();
    SCOPED_TRACE(fmt::format("pattern {} ({})", pattern, compared));
    ExpectKktOfTheNaiveCondensing(qp, solver);
    RiccatiQpSolver fresh(qp.dims);
    ASSERT_TRUE(fresh.Solve(qp).IsSolutionUsable());
    for (int k = 0; k < 8; ++k) {
      EXPECT_TRUE(MatricesNear(solver.u()[k], fresh.u()[k], 1e-9)) << "u_" << k;
      if (pattern == 0) {
        EXPECT_EQ(solver.u()[k][1], 0.25);  // exactly, not to a tolerance
      }
      if (pattern == 1 && k % 3 == 0) {
        EXPECT_EQ(solver.u()[k][2], qp.u_lower[k][2]);
      }
    }
    EXPECT_GE(solver.summary().active_constraints, pattern == 0 ? 8 : (pattern == 1 ? 3 : 0));
    EXPECT_GT(StateBoundsAtTheirLimit(solver.x(), {0, 3}), 0);
    ++compared;
  }
  EXPECT_EQ(compared, 5);
}

TEST(RiccatiQp, RejectsMismatchedDimensions) {
  // The solvers' shared contract (KKT against Ipopt, warm starts, infeasibility, bad data):
  // qp_contract_test.cc.
  Rng rng(59);
  const OcpQp qp = OcpPulledAgainstItsStateBounds(5, 4, 2, {0}, rng);
  RiccatiQpSolver other(OcpQpDims{6, 4, 2, {0}});
  EXPECT_THROW(other.Solve(qp), std::invalid_argument);
}

}  // namespace
}  // namespace rotorguard::control
