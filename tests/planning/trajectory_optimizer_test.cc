#include "rotorguard/planning/trajectory_optimizer.h"

#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"

namespace rotorguard::planning {
namespace {

/// A vertical cylinder's surface as an obstacle query: the nearest surface point and the outward
/// normal (the gradient of the exact distance, so the plane-based gradient is exact too).
ObstacleQuery Cylinder(const Eigen::Vector2d& center, double radius) {
  return [=](const Vector3& p, double search) -> std::optional<ObstaclePlane> {
    const Eigen::Vector2d d = p.head<2>() - center;
    const double r = d.norm();
    if (r < 1e-9 || r - radius > search) return std::nullopt;
    const Vector3 n(d.x() / r, d.y() / r, 0.0);
    return ObstaclePlane{Vector3(center.x(), center.y(), p.z()) + radius * n, n};
  };
}

PvaState Rest(const Vector3& p) {
  PvaState s = PvaState::Zero();
  s.col(0) = p;
  return s;
}

/// Straight-line waypoints between a and b, and durations at a given speed.
void StraightGuess(const Vector3& a, const Vector3& b, int pieces, double speed, Eigen::Matrix3Xd* q,
                   Eigen::VectorXd* t) {
  q->resize(3, pieces - 1);
  for (int i = 1; i < pieces; ++i) q->col(i - 1) = a + (b - a) * i / pieces;
  *t = Eigen::VectorXd::Constant(pieces, (b - a).norm() / pieces / speed);
}

/// The largest |derivative| over a trajectory, sampled 2000 times per piece.
double MaxNorm(const MinimumJerkTrajectory& traj, int order) {
  double m = 0.0;
  for (int i = 0; i < traj.pieces(); ++i) {
    for (int j = 0; j <= 2000; ++j) m = std::max(m, traj.PieceDerivative(i, traj.durations()(i) * j / 2000.0, order).norm());
  }
  return m;
}

// The objective's gradient (time, energy, the three limits and the clearance all active) against
// central differences, in waypoints and in the duration parameters.
TEST(TrajectoryOptimizer, ObjectiveGradientMatchesFiniteDifferences) {
  TrajectoryOptimizerOptions o;
  o.weight_feasibility = 10.0;
  o.weight_collision = 10.0;
  o.clearance_m = 0.5;
  const TrajectoryOptimizer optimizer(o);
  DynamicLimits limits{0.5, 0.4, 0.6};  // tight: every penalty active somewhere
  const PvaState head = Rest(Vector3(0, 0, 1)), tail = Rest(Vector3(6, 1, 1.5));
  const ObstacleQuery obstacles = Cylinder(Eigen::Vector2d(3.0, 0.7), 0.3);
  Rng rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    const int pieces = 2 + trial;
    Eigen::Matrix3Xd q;
    Eigen::VectorXd t;
    StraightGuess(head.col(0), tail.col(0), pieces, 1.0, &q, &t);
    Eigen::VectorXd x(4 * pieces - 3);
    for (int i = 0; i < q.cols(); ++i) x.segment<3>(3 * i) = q.col(i) + Vector3(rng.Uniform(-0.3, 0.3), rng.Uniform(-0.3, 0.3), 0.0);
    for (int i = 0; i < pieces; ++i) x(3 * (pieces - 1) + i) = TrajectoryOptimizer::TauOf(t(i) * rng.Uniform(0.7, 1.3));
    Eigen::VectorXd g;
    const double f = optimizer.Objective(head, tail, limits, obstacles, x, &g);
    ASSERT_TRUE(std::isfinite(f));
    for (int k = 0; k < x.size(); ++k) {
      const double h = 1e-6;
      Eigen::VectorXd plus = x, minus = x;
      plus(k) += h;
      minus(k) -= h;
      const double fd = (optimizer.Objective(head, tail, limits, obstacles, plus, nullptr) -
                         optimizer.Objective(head, tail, limits, obstacles, minus, nullptr)) / (2 * h);
      EXPECT_NEAR(g(k), fd, 1e-5 * std::max(1.0, std::abs(fd))) << "trial " << trial << ", variable " << k;
    }
  }
}

// Eq. (33) with the reference vehicle: two rotors of 11.5 N lift 1.15 kg with
// sqrt(23^2 - (1.15 g)^2) = 20.04 N to spare horizontally, less 0.65 kg/s x 1 m/s of drag.
TEST(TrajectoryOptimizer, PostFailureAccelerationLimitIsEquation33) {
  const double w = 1.15 * 9.81;
  EXPECT_NEAR(PostFailureAccelerationLimit(1.15, 11.5, 0.65, 1.0, 0.5), 0.5 * (std::sqrt(23.0 * 23.0 - w * w) - 0.65) / 1.15,
              1e-12);
  EXPECT_EQ(PostFailureAccelerationLimit(1.15, 5.0, 0.65, 1.0, 0.5), 0.0) << "two rotors cannot hold the weight";
}

// Free space, rest to rest over 8 m: the result respects v, a and j limits on a sampling 30 times
// denser than the optimiser's own check, for nominal limits and for a lower post-failure
// acceleration limit, which makes the flight longer.
TEST(TrajectoryOptimizer, OutputRespectsItsLimitsAndALowerAccelerationLimitSlowsIt) {
  const TrajectoryOptimizer optimizer{TrajectoryOptimizerOptions{}};
  const PvaState head = Rest(Vector3(0, 0, 1)), tail = Rest(Vector3(8, 2, 1));
  Eigen::Matrix3Xd q;
  Eigen::VectorXd t;
  StraightGuess(head.col(0), tail.col(0), 5, 2.0, &q, &t);
  double durations[2];
  int run = 0;
  for (const double a_max : {2.0, 0.3}) {
    const DynamicLimits limits{1.0, a_max, 2.0};
    MinimumJerkTrajectory traj;
    const TrajectoryOptimizerSummary s = optimizer.Optimize(head, tail, q, t, limits, {}, &traj);
    ASSERT_TRUE(s.ok()) << s.message;
    EXPECT_GE(s.limit_margin, 0.0);
    EXPECT_LE(MaxNorm(traj, 1), limits.v_max * 1.001);
    EXPECT_LE(MaxNorm(traj, 2), limits.a_max * 1.001);
    EXPECT_LE(MaxNorm(traj, 3), limits.j_max * 1.001);
    EXPECT_LT((traj.Evaluate(traj.total_duration()).p_W - tail.col(0)).norm(), 1e-9);
    durations[run++] = traj.total_duration();
  }
  EXPECT_GT(durations[1], durations[0] * 1.2) << "a_max,f = 0.3 m/s² takes longer than 2 m/s²";
}

// A pillar on the straight line: the optimised trajectory keeps the clearance from its surface
// (checked densely against the true geometry).
TEST(TrajectoryOptimizer, KeepsClearOfAnObstacleOnTheStraightLine) {
  TrajectoryOptimizerOptions o;
  o.clearance_m = 0.3;
  const TrajectoryOptimizer optimizer(o);
  const PvaState head = Rest(Vector3(0, 0, 1)), tail = Rest(Vector3(8, 0, 1));
  const Eigen::Vector2d pillar(4.0, 0.05);
  Eigen::Matrix3Xd q;
  Eigen::VectorXd t;
  StraightGuess(head.col(0), tail.col(0), 6, 1.0, &q, &t);
  MinimumJerkTrajectory traj;
  const TrajectoryOptimizerSummary s = optimizer.Optimize(head, tail, q, t, DynamicLimits{}, Cylinder(pillar, 0.25), &traj);
  ASSERT_TRUE(s.ok()) << s.message;
  double closest = 1e9;
  for (double tt = 0.0; tt <= traj.total_duration(); tt += 0.005) {
    closest = std::min(closest, (traj.Evaluate(tt).p_W.head<2>() - pillar).norm() - 0.25);
  }
  EXPECT_GT(closest, 0.25) << "within a few cm of the 0.3 m clearance";
  EXPECT_NEAR(s.min_clearance_m, closest, 0.02);
}

// A query that answers NaN makes the objective non-finite: a clear failure, never a trajectory.
TEST(TrajectoryOptimizer, NonFiniteObstacleAnswersAreAFailureNotAConvergence) {
  const TrajectoryOptimizer optimizer{TrajectoryOptimizerOptions{}};
  const ObstacleQuery nan = [](const Vector3& p, double) -> std::optional<ObstaclePlane> {
    return ObstaclePlane{p + Vector3(0.1, 0, 0), Vector3::Constant(std::nan(""))};
  };
  Eigen::Matrix3Xd q;
  Eigen::VectorXd t;
  StraightGuess(Vector3(0, 0, 1), Vector3(4, 0, 1), 3, 1.0, &q, &t);
  MinimumJerkTrajectory traj;
  const TrajectoryOptimizerSummary s = optimizer.Optimize(Rest(Vector3(0, 0, 1)), Rest(Vector3(4, 0, 1)), q, t,
                                                          DynamicLimits{}, nan, &traj);
  EXPECT_FALSE(s.ok());
  EXPECT_TRUE(traj.empty());
}

TEST(TrajectoryOptimizer, InvalidInputsAndOptionsAreNamed) {
  TrajectoryOptimizerOptions o;
  o.samples_per_piece = 1;
  try {
    const TrajectoryOptimizer bad(o);
    ADD_FAILURE();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "samples_per_piece");
  }
  const TrajectoryOptimizer optimizer{TrajectoryOptimizerOptions{}};
  MinimumJerkTrajectory traj;
  const auto s = optimizer.Optimize(Rest(Vector3::Zero()), Rest(Vector3::Ones()), Eigen::Matrix3Xd(3, 0),
                                    Eigen::VectorXd::Constant(1, 1.0), DynamicLimits{-1.0, 1.0, 1.0}, {}, &traj);
  EXPECT_EQ(s.status, TrajectoryOptimizerSummary::Status::kInvalidInput);
  EXPECT_NE(s.message.find("v_max"), std::string::npos) << s.message;
}

}  // namespace
}  // namespace rotorguard::planning
