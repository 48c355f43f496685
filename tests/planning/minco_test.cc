#include "rotorguard/planning/minco.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "rotorguard/core/rng.h"

namespace rotorguard::planning {
namespace {

// The banded LU against Eigen's dense LU with partial pivoting, for A X = B and A^T X = B, on
// random diagonally dominant matrices with the MINCO bandwidths and others.
TEST(BandedMatrix, SolvesMatchADenseSolve) {
  Rng rng(1);
  for (const auto& [n, lower, upper] : {std::tuple{1, 0, 0}, std::tuple{12, 4, 2}, std::tuple{30, 2, 5}, std::tuple{7, 6, 6}, std::tuple{40, 4, 3}}) {
    BandedMatrix a(n, lower, upper);
    for (int i = 0; i < n; ++i) {
      for (int j = std::max(0, i - lower); j <= std::min(n - 1, i + upper); ++j) a(i, j) = rng.Uniform(-1, 1);
      a(i, i) += (i % 2 ? -1.0 : 1.0) * (lower + upper + 2);
    }
    const Eigen::MatrixXd dense = a.ToDense();
    ASSERT_TRUE(a.Factorize());
    const Eigen::MatrixXd rhs = Eigen::MatrixXd::Random(n, 3);
    Eigen::MatrixXd x = rhs, xt = rhs;
    a.Solve(x);
    a.SolveTransposed(xt);
    EXPECT_LT((x - dense.partialPivLu().solve(rhs)).cwiseAbs().maxCoeff(), 1e-12) << n;
    EXPECT_LT((xt - dense.transpose().partialPivLu().solve(rhs)).cwiseAbs().maxCoeff(), 1e-12) << n;
  }
  BandedMatrix singular(3, 1, 1);
  EXPECT_FALSE(singular.Factorize()) << "a zero pivot is reported";
}

PvaState RandomState(Rng& rng) {
  PvaState s;
  for (int k = 0; k < 3; ++k) s.col(k) = Vector3(rng.Uniform(-2, 2), rng.Uniform(-2, 2), rng.Uniform(-2, 2));
  return s;
}

struct Problem {
  PvaState head, tail;
  Eigen::Matrix3Xd q;
  Eigen::VectorXd t;
};

Problem RandomProblem(Rng& rng, int pieces, double t_lo, double t_hi) {
  Problem p{RandomState(rng), RandomState(rng), Eigen::Matrix3Xd(3, pieces - 1), Eigen::VectorXd(pieces)};
  for (int i = 0; i + 1 < pieces; ++i) p.q.col(i) = Vector3(rng.Uniform(-5, 5), rng.Uniform(-5, 5), rng.Uniform(0, 3));
  for (int i = 0; i < pieces; ++i) p.t(i) = std::exp(rng.Uniform(std::log(t_lo), std::log(t_hi)));
  return p;
}

// The 6M conditions that define the coefficients (head and tail states, the waypoints, continuity
// of derivatives 0..4 at each junction) hold, for 1 to 12 pieces and durations from 0.02 s to
// 50 s: the banded solve without pivoting finds the one solution of the system.
TEST(MinimumJerkTrajectory, MeetsBoundaryWaypointAndContinuityConditions) {
  Rng rng(2);
  for (int trial = 0; trial < 200; ++trial) {
    const int m = 1 + trial % 12;
    const Problem p = RandomProblem(rng, m, trial % 2 ? 0.02 : 0.5, trial % 2 ? 2.0 : 50.0);
    MinimumJerkTrajectory traj;
    ASSERT_TRUE(traj.Build(p.head, p.tail, p.q, p.t));
    const auto near = [](const Vector3& a, const Vector3& b) {
      return (a - b).norm() <= 1e-8 * std::max({1.0, a.norm(), b.norm()});
    };
    for (int d = 0; d < 3; ++d) {
      EXPECT_TRUE(near(traj.PieceDerivative(0, 0.0, d), p.head.col(d))) << "head, derivative " << d;
      EXPECT_TRUE(near(traj.PieceDerivative(m - 1, p.t(m - 1), d), p.tail.col(d))) << "tail, derivative " << d;
    }
    for (int i = 0; i + 1 < m; ++i) {
      EXPECT_TRUE(near(traj.PieceDerivative(i, p.t(i), 0), p.q.col(i))) << "waypoint " << i;
      for (int d = 0; d < 5; ++d) {
        EXPECT_TRUE(near(traj.PieceDerivative(i, p.t(i), d), traj.PieceDerivative(i + 1, 0.0, d)))
            << "trial " << trial << ", junction " << i << ", derivative " << d;
      }
    }
  }
}

// One piece from rest to rest is the classic minimum-jerk polynomial
// p0 + (p1 - p0)(10 s^3 - 15 s^4 + 6 s^5), s = t / T, with energy 720 |p1 - p0|^2 / T^5.
TEST(MinimumJerkTrajectory, RestToRestIsTheClosedForm) {
  PvaState head = PvaState::Zero(), tail = PvaState::Zero();
  head.col(0) = Vector3(1, 2, 3);
  tail.col(0) = Vector3(4, -2, 3.5);
  const double T = 2.5;
  MinimumJerkTrajectory traj;
  ASSERT_TRUE(traj.Build(head, tail, Eigen::Matrix3Xd(3, 0), Eigen::VectorXd::Constant(1, T)));
  for (double t = 0.0; t <= T; t += 0.1) {
    const double s = t / T;
    const Vector3 expected = head.col(0) + (tail.col(0) - head.col(0)) * (10 * std::pow(s, 3) - 15 * std::pow(s, 4) + 6 * std::pow(s, 5));
    EXPECT_LT((traj.Evaluate(t).p_W - expected).norm(), 1e-12);
  }
  EXPECT_NEAR(traj.Energy(), 720.0 * (tail.col(0) - head.col(0)).squaredNorm() / std::pow(T, 5), 1e-9);
}

// A chain from rest to rest: each piece is the one-piece Build between its corners at rest (the
// closed form above), so the chain stops at every corner, stays on the segments, peaks at 1.875
// L / T in speed, and its energy is the pieces' 720 L^2 / T^5. It has no adjoint system.
TEST(MinimumJerkTrajectory, ARestToRestChainIsOneRestToRestPiecePerSegment) {
  Eigen::Matrix3Xd points(3, 4);
  points << 0.0, 2.0, 2.0, -1.0,  //
      0.0, 0.0, 1.5, 3.0,         //
      1.0, 1.2, 1.2, 0.8;
  const Eigen::Vector3d durations(2.0, 1.5, 3.0);
  MinimumJerkTrajectory chain;
  ASSERT_TRUE(chain.BuildRestToRest(points, durations));
  ASSERT_EQ(chain.pieces(), 3);
  double start = 0.0, energy = 0.0;
  for (int i = 0; i < 3; ++i) {
    PvaState head = PvaState::Zero(), tail = PvaState::Zero();
    head.col(0) = points.col(i);
    tail.col(0) = points.col(i + 1);
    MinimumJerkTrajectory one;
    ASSERT_TRUE(one.Build(head, tail, Eigen::Matrix3Xd(3, 0), Eigen::VectorXd::Constant(1, durations(i))));
    const double length = (points.col(i + 1) - points.col(i)).norm();
    for (double t = 0.0; t <= durations(i); t += 0.05) {
      const ReferencePoint a = chain.Evaluate(start + t), b = one.Evaluate(t);
      EXPECT_LT((a.p_W - b.p_W).norm(), 1e-12) << "piece " << i << " t " << t;
      EXPECT_LT((a.v_W - b.v_W).norm(), 1e-12) << "piece " << i << " t " << t;
      EXPECT_LT((a.a_W - b.a_W).norm(), 1e-12) << "piece " << i << " t " << t;
      // On the segment: the offset from its start is parallel to it.
      EXPECT_LT((a.p_W - points.col(i)).cross(points.col(i + 1) - points.col(i)).norm(), 1e-12);
    }
    EXPECT_LT(chain.Evaluate(start).v_W.norm(), 1e-12) << "at rest at corner " << i;
    EXPECT_NEAR(chain.PieceDerivative(i, 0.5 * durations(i), 1).norm(), 1.875 * length / durations(i), 1e-12);
    energy += 720.0 * length * length / std::pow(durations(i), 5);
    start += durations(i);
  }
  EXPECT_NEAR(chain.Energy(), energy, 1e-9 * energy);
  EXPECT_LT((chain.Evaluate(1e9).p_W - points.col(3)).norm(), 1e-12);
  Eigen::Matrix3Xd dq;
  Eigen::VectorXd dt;
  Eigen::MatrixX3d partials = Eigen::MatrixX3d::Zero(18, 3);
  EXPECT_THROW(chain.PropagateGradient(&partials, Eigen::VectorXd::Zero(3), &dq, &dt), std::logic_error);
  EXPECT_FALSE(chain.BuildRestToRest(points, Eigen::Vector3d(1.0, 0.0, 1.0))) << "a zero duration";
  EXPECT_TRUE(chain.empty());
  EXPECT_FALSE(chain.BuildRestToRest(points, Eigen::Vector2d(1.0, 1.0))) << "sizes";
  EXPECT_FALSE(chain.BuildRestToRest(points.leftCols(1), Eigen::VectorXd(0))) << "one point";
  Eigen::Matrix3Xd bad = points;
  bad(1, 2) = std::nan("");
  EXPECT_FALSE(chain.BuildRestToRest(bad, durations)) << "a NaN point";
}

// The energy's total gradient with respect to waypoints and durations (partials propagated
// through the adjoint) against central differences of the rebuilt trajectory's energy.
TEST(MinimumJerkTrajectory, EnergyGradientMatchesFiniteDifferences) {
  Rng rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Problem p = RandomProblem(rng, 1 + trial % 8, 0.4, 3.0);
    MinimumJerkTrajectory traj;
    ASSERT_TRUE(traj.Build(p.head, p.tail, p.q, p.t));
    Eigen::MatrixX3d dc;
    Eigen::VectorXd dt_partial, dt;
    Eigen::Matrix3Xd dq;
    traj.EnergyPartials(&dc, &dt_partial);
    traj.PropagateGradient(&dc, dt_partial, &dq, &dt);
    const auto energy = [&](const Eigen::Matrix3Xd& q, const Eigen::VectorXd& t) {
      MinimumJerkTrajectory other;
      EXPECT_TRUE(other.Build(p.head, p.tail, q, t));
      return other.Energy();
    };
    const double scale = std::max(1.0, traj.Energy());
    for (int i = 0; i < p.q.cols(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const double h = 1e-6;
        Eigen::Matrix3Xd plus = p.q, minus = p.q;
        plus(k, i) += h;
        minus(k, i) -= h;
        EXPECT_NEAR(dq(k, i), (energy(plus, p.t) - energy(minus, p.t)) / (2 * h), 1e-6 * scale) << "q " << i << "," << k;
      }
    }
    for (int i = 0; i < p.t.size(); ++i) {
      const double h = 1e-6 * p.t(i);
      Eigen::VectorXd plus = p.t, minus = p.t;
      plus(i) += h;
      minus(i) -= h;
      EXPECT_NEAR(dt(i), (energy(p.q, plus) - energy(p.q, minus)) / (2 * h), 1e-6 * scale) << "T " << i;
    }
  }
}

// The polynomial basis' derivatives against the power rule applied by hand, for every order.
TEST(MinimumJerkTrajectory, BasisRowsAreThePolynomialDerivatives) {
  for (const double t : {0.0, 0.3, 1.0, 2.7}) {
    const Eigen::Matrix<double, 5, 6> rows = MinimumJerkTrajectory::BasisRows(t);
    for (int order = 0; order < 5; ++order) {
      for (int k = 0; k < 6; ++k) {
        // d^order/dt^order t^k = k (k - 1) ... (k - order + 1) t^(k - order)
        double expected = k >= order ? std::pow(t, k - order) : 0.0;
        for (int m = 0; m < order; ++m) expected *= k - m;
        EXPECT_NEAR(rows(order, k), expected, 1e-12) << "t " << t << ", order " << order << ", k " << k;
        EXPECT_EQ(MinimumJerkTrajectory::Basis(t, order)(k), rows(order, k));
      }
    }
  }
}

TEST(MinimumJerkTrajectory, RejectsBadInputs) {
  MinimumJerkTrajectory traj;
  const PvaState z = PvaState::Zero();
  EXPECT_FALSE(traj.Build(z, z, Eigen::Matrix3Xd(3, 0), Eigen::VectorXd::Constant(1, 0.0)));
  EXPECT_FALSE(traj.Build(z, z, Eigen::Matrix3Xd(3, 0), Eigen::VectorXd::Constant(1, std::nan(""))));
  EXPECT_FALSE(traj.Build(z, z, Eigen::Matrix3Xd(3, 1), Eigen::VectorXd::Constant(1, 1.0))) << "sizes";
  EXPECT_TRUE(traj.empty());
  EXPECT_TRUE(traj.Evaluate(1.0).p_W.allFinite());
}

}  // namespace
}  // namespace rotorguard::planning
