
#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/planning/trajectory_optimizer.h"

namespace rotorguard::planning {
namespace {

/// A vertical cylinder's surface: the nearest surface point within `search` and the outward
/// normal (the gradient of the exact distance).
NearestPlane Cylinder(const Eigen::Vector2d& center, double radius, double search) {
  return [=](const Vector3& p) -> std::optional<ObstaclePlane> {
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

// The objective's gradient (time, energy, the three limits and the clearance all active) against
// central differences, in waypoints and in the duration parameters.
TEST(TrajectoryOptimizer, ObjectiveGradientMatchesFiniteDifferences) {
  TrajectoryOptimizerOptions o;
  o.weights.feasibility = 10.0;
  o.weights.collision = 10.0;
  o.clearance_m = 0.5;
  const TrajectoryOptimizer optimizer(o);
  DynamicLimits limits{0.5, 0.4, 0.6};  // tight: every penalty active somewhere
  const PvaState head = Rest(Vector3(0, 0, 1)), tail = Rest(Vector3(6, 1, 1.5));
  Rng rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    const int pieces = 2 + trial;
    Eigen::Matrix3Xd q;
    Eigen::VectorXd t;
    StraightGuess(head.col(0), tail.col(0), pieces, 1.0, &q, &t);
    Eigen::VectorXd x(4 * pieces - 3);
    for (int i = 0; i < q.cols(); ++i) x.segment<3>(3 * i) = q.col(i) + Vector3(rng.Uniform(-0.3, 0.3), rng.Uniform(-0.3, 0.3), 0.0);
    for (int i = 0; i < pieces; ++i) x(3 * (pieces - 1) + i) = TrajectoryOptimizer::TauOf(t(i) * rng.Uniform(0.7, 1.3));
    MinimumJerkTrajectory initial;
    ASSERT_TRUE(initial.Build(head, tail, q, t));
    const PlaneSet obstacles = BuildSamplePlanes(initial, o.samples_per_piece, Cylinder(Eigen::Vector2d(3.0, 0.7), 0.3, 1.0));
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
TEST(TrajectoryOptimizer, DegradedAccelerationLimitScalesTheNominalByTheHorizontalThrustLeft) {
  const double w = 1.15 * 9.81;
  const std::vector<double> max_thrust(4, 11.5);
  EXPECT_NEAR(DegradedAccelerationLimit(3.0, w, max_thrust, {1, 1, 1, 1}), 3.0, 1e-12);  // nothing lost
  // Rotor 0 at half: a balanced split gives 4 x 5.75 N = 23 N of the 46 N.
  EXPECT_NEAR(DegradedAccelerationLimit(3.0, w, max_thrust, {0.5, 1, 1, 1}),
              3.0 * std::sqrt(23.0 * 23.0 - w * w) / std::sqrt(46.0 * 46.0 - w * w), 1e-12);
  EXPECT_EQ(DegradedAccelerationLimit(3.0, w, max_thrust, {1, 1, 0.2, 1}), 0.0) << "4 x 2.3 N cannot hold 11.3 N";
  EXPECT_THROW(DegradedAccelerationLimit(3.0, w, max_thrust, {1, 1}), std::invalid_argument);
}

TEST(TrajectoryOptimizer, PostFailureAccelerationLimitIsEquation33) {
  const double w = 1.15 * 9.81;
  EXPECT_NEAR(PostFailureAccelerationLimit(1.15, 11.5, 0.65, 1.0, 0.5), 0.5 * (std::sqrt(23.0 * 23.0 - w * w) - 0.65) / 1.15,
              1e-12);
  EXPECT_EQ(PostFailureAccelerationLimit(1.15, 5.0, 0.65, 1.0, 0.5), 0.0) << "two rotors cannot hold the weight";
}

// Free space, rest to rest over 8 m: the result respects v, a and j limits on a sampling 30 times
// denser than the optimiser's own check and takes no less than the bang-bang time, for nominal
// limits and for a lower post-failure acceleration limit, which makes the flight longer; with
// either L-BFGS.
TEST(TrajectoryOptimizer, OutputRespectsItsLimitsAndALowerAccelerationLimitSlowsIt) {
  for (const LbfgsMethod method : {LbfgsMethod::kCeres, LbfgsMethod::kLewisOverton}) {
    TrajectoryOptimizerOptions options;
    options.lbfgs.method = method;
    const TrajectoryOptimizer optimizer(options);
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
      EXPECT_LE(traj.MaxNorm(1, 2000), limits.v_max * 1.001);
      EXPECT_LE(traj.MaxNorm(2, 2000), limits.a_max * 1.001);
      EXPECT_LE(traj.MaxNorm(3, 2000), limits.j_max * 1.001);
      EXPECT_LT((traj.Evaluate(traj.total_duration()).p_W - tail.col(0)).norm(), 1e-9);
      // No flight from rest to rest over d within v_max and a_max is faster than the bang-bang
      // profile: d / v + v / a when it reaches v_max, else 2 sqrt(d / a).
      const double d = (tail.col(0) - head.col(0)).norm(), v = limits.v_max, a = limits.a_max;
      EXPECT_GE(traj.total_duration(), d >= v * v / a ? d / v + v / a : 2.0 * std::sqrt(d / a));
      durations[run++] = traj.total_duration();
    }
    EXPECT_GT(durations[1], durations[0]) << "a_max,f = 0.3 m/s² takes longer than 2 m/s²";
  }
}

// A pillar on the straight line: planes from the initial guess's samples, then, as the planner
// does, planes again from the result until it keeps the clearance from the pillar's surface
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
  ASSERT_TRUE(traj.Build(head, tail, q, t));
  PlaneSet planes(6);
  for (int round = 0; round < 3; ++round) {
    const PlaneSet more = BuildSamplePlanes(traj, o.samples_per_piece, Cylinder(pillar, 0.25, 1.0));
    for (std::size_t i = 0; i < planes.size(); ++i) planes[i].insert(planes[i].end(), more[i].begin(), more[i].end());
    const TrajectoryOptimizerSummary s = optimizer.Optimize(head, tail, q, t, DynamicLimits{}, planes, &traj);
    ASSERT_TRUE(s.ok()) << s.message;
  }
  double closest = 1e9;
  for (double tt = 0.0; tt <= traj.total_duration(); tt += 0.005) {
    closest = std::min(closest, (traj.Evaluate(tt).p_W.head<2>() - pillar).norm() - 0.25);
  }
  EXPECT_GT(closest, 0.25) << "within a few cm of the 0.3 m clearance";
}

// A NaN plane makes the objective non-finite: a clear failure, never a trajectory.
TEST(TrajectoryOptimizer, NonFinitePlanesAreAFailureNotAConvergence) {
  const TrajectoryOptimizer optimizer{TrajectoryOptimizerOptions{}};
  Eigen::Matrix3Xd q;
  Eigen::VectorXd t;
  StraightGuess(Vector3(0, 0, 1), Vector3(4, 0, 1), 3, 1.0, &q, &t);
  PlaneSet planes(3);
  planes[1].push_back({4, ObstaclePlane{Vector3(2, 0.2, 1), Vector3::Constant(std::nan(""))}});
  MinimumJerkTrajectory traj;
  const TrajectoryOptimizerSummary s =
      optimizer.Optimize(Rest(Vector3(0, 0, 1)), Rest(Vector3(4, 0, 1)), q, t, DynamicLimits{}, planes, &traj);
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

// Without a jerk limit the objective is the one whose jerk limit is never reached (its penalty
// term is zero everywhere), value and gradient, and its gradient still matches central
// differences; the optimum keeps v and a within their limits on a dense check. Only j_max may be
// unlimited, and a NaN limit is no limit but an error.
TEST(TrajectoryOptimizer, NoJerkLimitDropsTheJerkTermAndItsCheck) {
  TrajectoryOptimizerOptions o;
  o.weights.collision = 0.0;
  const TrajectoryOptimizer optimizer(o);
  const PvaState head = Rest(Vector3(0, 0, 1)), tail = Rest(Vector3(6, 3, 1.5));
  Eigen::Matrix3Xd q;
  Eigen::VectorXd t;
  StraightGuess(head.col(0), tail.col(0), 4, 1.5, &q, &t);  // fast: v and a penalties active
  Eigen::VectorXd x = TrajectoryOptimizer::Variables(q, t);
  x.head(9) += Eigen::VectorXd::LinSpaced(9, -0.2, 0.2);
  const DynamicLimits none{1.0, 0.8, DynamicLimits::kNoLimit}, unreachable{1.0, 0.8, 1e9};
  Eigen::VectorXd g_none, g_unreachable;
  const double f_none = optimizer.Objective(head, tail, none, {}, x, &g_none);
  EXPECT_NEAR(f_none, optimizer.Objective(head, tail, unreachable, {}, x, &g_unreachable), 1e-12 * f_none);
  EXPECT_LT((g_none - g_unreachable).norm(), 1e-12 * g_none.norm());
  EXPECT_GT(f_none, 10.0 * t.sum() + 1.0) << "the limits' penalties are active";
  for (int k = 0; k < x.size(); ++k) {
    const double h = 1e-6;
    Eigen::VectorXd plus = x, minus = x;
    plus(k) += h;
    minus(k) -= h;
    const double fd = (optimizer.Objective(head, tail, none, {}, plus, nullptr) -
                       optimizer.Objective(head, tail, none, {}, minus, nullptr)) /
                      (2 * h);
    EXPECT_NEAR(g_none(k), fd, 1e-5 * std::max(1.0, std::abs(fd))) << "variable " << k;
  }
  MinimumJerkTrajectory traj;
  const TrajectoryOptimizerSummary s = optimizer.Optimize(head, tail, q, t, none, {}, &traj);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_LE(traj.MaxNorm(1, 2000), none.v_max * 1.001);
  EXPECT_LE(traj.MaxNorm(2, 2000), none.a_max * 1.001);
  EXPECT_GT(s.check_ms, 0.0);  // measured: the check sampled something
  EXPECT_LE(s.check_ms, s.solve_ms);

  EXPECT_NO_THROW(none.Validate());
  for (const DynamicLimits& bad :
       {DynamicLimits{DynamicLimits::kNoLimit, 1.0, 1.0}, DynamicLimits{1.0, DynamicLimits::kNoLimit, 1.0},
        DynamicLimits{1.0, 1.0, std::nan("")}}) {
    EXPECT_THROW(bad.Validate(), ValidationError);
  }
}

}  // namespace
}  // namespace rotorguard::planning
