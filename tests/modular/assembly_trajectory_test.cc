
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/modular/assembly_trajectory.h"
#include "assembly_fixture.h"
#include "test_util.h"

namespace rotorguard::modular {
namespace {

constexpr double kPi = std::numbers::pi;
using testing::Band;
using testing::WallWithGap;

/// A single MARS unit as a one-unit assembly.
Assembly OneUnit() {
  AssemblySpec s = testing::MarsSpec("3x1");
  s.slots = {Eigen::Vector2i(0, 0)};
  return BuildAssembly(s);
}

TEST(AssemblyCapacity, OneUnitMatchesTheClosedForms) {
  const Assembly a = OneUnit();
  const AssemblyCapacity c = CapacityOf(a, RotorVector::Ones(4));
  ASSERT_TRUE(c.hover_attainable);
  EXPECT_NEAR(c.max_thrust_n, 4 * 2.6, 1e-3 * 10.4);  // every rotor at full thrust
  // At the hover thrust W the largest yaw torque puts W on one diagonal pair (W / 2 = 2.45 N each,
  // within 2.6 N) and nothing on the other: kappa W.
  const double w = 0.5 * kGravity;
  EXPECT_NEAR(c.max_yaw_torque_n_m, 0.016 * w, 1e-3 * 0.016 * w);
  EXPECT_NEAR(c.max_yaw_acceleration_rad_s2, 0.016 * w / 4.0e-3, 1e-3 * 0.016 * w / 4.0e-3);
  EXPECT_NEAR(c.max_acceleration_m_s2, std::sqrt(std::pow(10.4 / 0.5, 2) - kGravity * kGravity), 0.05);
  // The largest roll torque at W: the two rotors at y = +0.075 m carry W / 2 each (one of either
  // spin, so no yaw; one either side of x, so no pitch), those at y = -0.075 m nothing: 0.075 W.
  // Pitch likewise about x. Over the frame's 2.2e-3 kg m².
  EXPECT_NEAR(c.max_roll_acceleration_rad_s2, 0.075 * w / 2.2e-3, 1e-3 * 0.075 * w / 2.2e-3);
  EXPECT_NEAR(c.max_pitch_acceleration_rad_s2, 0.075 * w / 2.2e-3, 1e-3 * 0.075 * w / 2.2e-3);
}

TEST(AssemblyCapacity, ADeadEndUnitLeavesTheThrustOfTheLinearProgramSolvedByHand) {
  // 4x1 with unit No. 4 (x = +0.375 m) dead. Zero pitch torque: the rotors at x = +0.05, +0.2 m
  // (four, at 2.6 N: 1.3 N m) balance the nearest rotors behind the centre, x = -0.05, -0.2 m
  // (four at 2.6 N: exactly 1.3 N m). Most thrust: those eight at full, 20.8 N.
  const Assembly a = testing::MarsAssembly("4x1");
  RotorVector eta = RotorVector::Ones(16);
  eta.segment(12, 4).setZero();
  const AssemblyCapacity c = CapacityOf(a, eta);
  ASSERT_TRUE(c.hover_attainable);
  EXPECT_NEAR(c.max_thrust_n, 20.8, 0.01);
  EXPECT_NEAR(c.max_acceleration_m_s2, std::sqrt(10.4 * 10.4 - kGravity * kGravity), 0.01);
  // The pitch torque at the hover thrust W = 19.62 N, as a linear program over the rotor pairs at
  // x = -0.45, -0.3, -0.2, -0.05, 0.05, 0.2 m (each pair 0..5.2 N; one of either spin, at
  // y = ±0.075 m, so no roll or yaw): towards +x the pairs at 0.2, 0.05, -0.05 m full and 4.02 N at
  // -0.2 m give 0.236 N m; towards -x 5.14 N m. The smaller over I_yy = 0.5 (2 0.375² + 2 0.125²)
  // + 4 2.2e-3 = 0.16505 kg m².
  const double hover = 2.0 * kGravity, rest = hover - 3 * 5.2;
  const double pitch_torque = 5.2 * 0.2 + 5.2 * 0.05 - 5.2 * 0.05 - rest * 0.2;
  EXPECT_NEAR(c.max_pitch_acceleration_rad_s2, pitch_torque / 0.16505, 0.01 * pitch_torque / 0.16505);
  // Two dead units at one end cannot hover: no capacity, and ours has no limits to give.
  eta.segment(8, 4).setZero();
  const AssemblyCapacity none = CapacityOf(a, eta);
  EXPECT_FALSE(none.hover_attainable);
  EXPECT_FALSE(HasMargin(none));
  EXPECT_THROW(DynamicsAwareLimits({}, none, a.vehicle.mass_kg, 1.0, 0.8), std::invalid_argument);
}

TEST(AssemblyTrajectoryOptimizer, AttitudeErrorIsTheDistanceToTheNearestOptimalYaw) {
  const Assembly a = testing::MarsAssembly("4x1");
  const AssemblyTrajectoryOptimizer opt(a, RotorVector::Ones(16), {});
  ASSERT_EQ(opt.optimal_relative_yaws().size(), 2u);  // lengthwise, either way round
  EXPECT_NEAR(opt.AttitudeError(0.3, 0.0), -0.3, 1e-12);
  EXPECT_NEAR(opt.AttitudeError(0.5 * kPi + 0.1, 0.0), 0.5 * kPi - 0.1, 1e-12);  // towards pi
  EXPECT_NEAR(opt.AttitudeError(1.0, 1.2), 0.2, 1e-12);
}

/// A problem with every term active: tight limits, yaw limits, the attitude term and planes.
AssemblyTrajectoryOptimizer::Problem ActiveProblem() {
  AssemblyTrajectoryOptimizer::Problem p;
  p.start = {Vector3(0.0, 0.0, 1.5), 0.3};
  p.goal = {Vector3(3.0, 1.0, 1.6), 1.1};
  p.limits.kinematic = {0.5, 0.3, 0.3};
  p.limits.yaw_rate_max = 0.3;
  p.limits.yaw_acceleration_max = 0.2;
  p.limits.thrust_acceleration_max = 9.815;  // above g by less than the climb's acceleration
  p.limits.roll_acceleration_max = 0.02;     // unequal, so the yaw's gradient of the ellipse counts
  p.limits.pitch_acceleration_max = 0.01;
  p.planes.resize(3);
  p.planes[1].push_back({3, 0, {Vector3(1.5, 0.7, 1.5), Vector3(0.0, -1.0, 0.0)}});
  p.planes[1].push_back({3, 2, {Vector3(1.5, 0.7, 1.5), Vector3(0.0, -1.0, 0.0)}});
  p.planes[1].push_back({5, 3, {Vector3(1.4, 0.6, 1.5), Vector3(-0.6, -0.8, 0.0)}});
  return p;
}

TEST(AssemblyTrajectoryOptimizer, GradientMatchesFiniteDifferences) {
  const Assembly a = testing::MarsAssembly("4x1");
  AssemblyTrajectoryOptions o;
  o.samples_per_piece = 8;
  const AssemblyTrajectoryOptimizer opt(a, RotorVector::Ones(16), o);
  const AssemblyTrajectoryOptimizer::Problem p = ActiveProblem();
  const int m = 3;
  Eigen::VectorXd x(5 * m - 4);
  x << 1.0, 0.3, 1.55, 2.0, 0.6, 1.5, 1.8, -0.6, 1.2, 0.9, 1.2;
  Eigen::VectorXd g;
  const double f = opt.Objective(p, x, &g);
  ASSERT_TRUE(std::isfinite(f));
  // Every term is active at x: dropping any lowers the cost.
  const auto without = [&](auto change) {
    AssemblyTrajectoryOptions less = o;
    AssemblyTrajectoryOptimizer::Problem q = p;
    change(&less, &q);
    return AssemblyTrajectoryOptimizer(a, RotorVector::Ones(16), less).Objective(q, x, nullptr);
  };
  EXPECT_LT(without([](auto* w, auto*) { w->weight_obstacle = 0.0; }), f - 1.0);
  EXPECT_LT(without([](auto* w, auto*) { w->weight_attitude = 0.0; }), f - 1.0);
  EXPECT_LT(without([](auto*, auto* q) { q->limits.kinematic = {10.0, 10.0, 10.0}; }), f - 1.0);
  EXPECT_LT(without([](auto*, auto* q) { q->limits.yaw_rate_max = 0.0; }), f - 1.0);
  EXPECT_LT(without([](auto*, auto* q) { q->limits.yaw_acceleration_max = 0.0; }), f - 1.0);
  EXPECT_LT(without([](auto*, auto* q) { q->limits.thrust_acceleration_max = 0.0; }), f - 1e-6);
  EXPECT_LT(without([](auto*, auto* q) { q->limits.roll_acceleration_max = q->limits.pitch_acceleration_max = 0.0; }),
            f - 1e-6);
  ASSERT_EQ(g.size(), x.size());
  for (int k = 0; k < x.size(); ++k) {
    const double h = 1e-6;
    Eigen::VectorXd xp = x, xm = x;
    xp(k) += h;
    xm(k) -= h;
    const double fd = (opt.Objective(p, xp, nullptr) - opt.Objective(p, xm, nullptr)) / (2.0 * h);
    const double rounding = 1e-15 * std::abs(f) / h;  // of the difference quotient itself
    EXPECT_NEAR(g(k), fd, 1e-5 * std::max(1.0, std::abs(fd)) + 10.0 * rounding) << "variable " << k;
  }
}

/// The straight A* path of a row from (-2, 0) to (2, 0) at yaw `yaw`, a pose per 0.1 m.
AssemblyPath StraightPath(double yaw) {
  AssemblyPath path;
  path.status = AssemblyPathStatus::kFound;
  for (int k = 0; k <= 40; ++k) path.poses.push_back({Vector3(-2.0 + 0.1 * k, 0.0, 1.5), yaw});
  return path;
}

AssemblyLimits Limits() {
  AssemblyLimits l;
  l.kinematic = {1.0, 1.5, 4.0};
  l.yaw_rate_max = 1.0;
  l.yaw_acceleration_max = 1.5;
  l.thrust_acceleration_max = 10.5;  // a climb of at most 0.69 m/s²
  return l;
}

TEST(AssemblyTrajectoryOptimizer, TheAttitudeTermTurnsABroadsideRowLengthwiseWithinTheLimits) {
  const Assembly a = testing::MarsAssembly("4x1");
  const perception::VoxelMap map = WallWithGap(100.0);  // open space
  AssemblyTrajectoryOptions ours;
  AssemblyTrajectoryOptions baseline = ours;
  baseline.weight_attitude = 0.0;
  AssemblyTrajectory t_ours, t_base;
  const AssemblyTrajectorySummary s_ours =
      AssemblyTrajectoryOptimizer(a, RotorVector::Ones(16), ours).Optimize(map, StraightPath(0.5 * kPi), Limits(), &t_ours);
  const AssemblyTrajectorySummary s_base = AssemblyTrajectoryOptimizer(a, RotorVector::Ones(16), baseline)
                                               .Optimize(map, StraightPath(0.5 * kPi), Limits(), &t_base);
  ASSERT_TRUE(s_ours.ok()) << s_ours.message;
  ASSERT_TRUE(s_base.ok()) << s_base.message;
  // Both end where asked, at rest, and hold every limit on an independent dense check.
  for (const AssemblyTrajectory* t : {&t_ours, &t_base}) {
    EXPECT_TRUE(testing::MatricesNear(t->Evaluate(t->duration()).p_W, Vector3(2.0, 0.0, 1.5), 1e-9));
    EXPECT_NEAR(t->Evaluate(t->duration()).yaw, 0.5 * kPi, 1e-9);
    for (double time = 0.0; time <= t->duration(); time += 0.005) {
      const ReferencePoint r = t->Evaluate(time);
      EXPECT_LE(r.v_W.norm(), 1.0 + 1e-6);
      EXPECT_LE(r.a_W.norm(), 1.5 + 1e-6);
      EXPECT_LE(r.j_W.norm(), 4.0 + 1e-6);
      EXPECT_LE(std::abs(r.yaw_rate), 1.0 + 1e-6);
      EXPECT_LE((r.a_W + Vector3(0.0, 0.0, kGravity)).norm(), 10.5 + 1e-6);
    }
  }
  // The baseline has no reason to turn (it stays broadside, 90 degrees off); ours turns the row
  // towards its flight.
  EXPECT_GT(s_base.attitude_deviation_rad, 0.5 * kPi - 0.05);
  EXPECT_LT(s_ours.attitude_deviation_rad, 0.5 * s_base.attitude_deviation_rad)
      << s_ours.attitude_deviation_rad << " rad against " << s_base.attitude_deviation_rad;
}

TEST(AssemblyTrajectoryOptimizer, TheTiltLimitKeepsTheSnapWithinWhatTheRotorsCanTiltTheRow) {
  // A row flown lengthwise brakes with pitch, broadside with roll: with pitch 5x slower to
  // accelerate than roll, the snap (g times the tilt's angular acceleration near hover) along the
  // body's x stays within g α_pitch, and the broadside flight is the quicker.
  const Assembly a = testing::MarsAssembly("4x1");
  const perception::VoxelMap map = WallWithGap(100.0);  // open space
  AssemblyTrajectoryOptions o;
  o.weight_attitude = 0.0;  // no preference of heading: only the tilt's limits tell the yaws apart
  AssemblyLimits tilt = Limits();
  tilt.roll_acceleration_max = 0.5;
  tilt.pitch_acceleration_max = 0.1;
  const AssemblyTrajectoryOptimizer opt(a, RotorVector::Ones(16), o);
  // The largest demand on the ellipse, from the snap by central differences of the jerk (not the
  // optimiser's own fourth derivative) in the frame of the yaw.
  const auto demand = [](const AssemblyTrajectory& t) {
    double worst = 0.0;
    const double h = 1e-4;
    for (double time = h; time <= t.duration() - h; time += 0.005) {
      const Vector3 snap = (t.Evaluate(time + h).j_W - t.Evaluate(time - h).j_W) / (2.0 * h);
      const double yaw = t.Evaluate(time).yaw, c = std::cos(yaw), sn = std::sin(yaw);
      const double bx = c * snap.x() + sn * snap.y(), by = -sn * snap.x() + c * snap.y();
      worst = std::max(worst, std::pow(bx / (kGravity * 0.1), 2) + std::pow(by / (kGravity * 0.5), 2));
    }
    return worst;
  };
  AssemblyTrajectory lengthwise, broadside, free;
  const AssemblyTrajectorySummary s_length = opt.Optimize(map, StraightPath(0.0), tilt, &lengthwise);
  const AssemblyTrajectorySummary s_broad = opt.Optimize(map, StraightPath(0.5 * kPi), tilt, &broadside);
  const AssemblyTrajectorySummary s_free = opt.Optimize(map, StraightPath(0.0), Limits(), &free);
  ASSERT_TRUE(s_length.ok()) << s_length.message;
  ASSERT_TRUE(s_broad.ok()) << s_broad.message;
  ASSERT_TRUE(s_free.ok()) << s_free.message;
  EXPECT_GE(s_length.limit_margin, 0.0);
  EXPECT_LE(demand(lengthwise), 1.0 + 1e-3);
  EXPECT_LE(demand(broadside), 1.0 + 1e-3);
  EXPECT_GT(demand(free), 2.0);  // the limit binds: without it the plan asks for more
  EXPECT_LT(s_broad.duration_s, s_length.duration_s);
  EXPECT_LT(s_free.duration_s, s_length.duration_s);
}

TEST(AssemblyTrajectoryOptimizer, WithTheTiltLimitThePlansEndsAskForATiltRateTheRotorsCanStop) {
  // Near hover the tilt rate is the horizontal jerk over g. The plan starts and ends at rest and the
  // reference held before and after it has no jerk: the rate at either end is started or stopped at
  // once, and stopped at the limit's angular acceleration α it overshoots by ω² / (2 α). With the
  // tilt limits on that stays within end_tilt_overshoot_rad; without them it is what a minimum-jerk
  // plan leaves there (a rest-to-rest quintic's 60 h / T³ of jerk).
  const Assembly a = testing::MarsAssembly("4x1");
  const perception::VoxelMap map = WallWithGap(100.0);  // open space
  AssemblyTrajectoryOptions o;
  o.weight_attitude = 0.0;
  AssemblyLimits tilt = Limits();
  tilt.roll_acceleration_max = 0.5;
  tilt.pitch_acceleration_max = 0.1;
  const AssemblyTrajectoryOptimizer opt(a, RotorVector::Ones(16), o);
  // Flown lengthwise (yaw 0), the body's x is the world's: pitch, at 0.1 rad/s² at most.
  const auto overshoot = [](const AssemblyTrajectory& t, double time) {
    const double rate = t.Evaluate(time).j_W.head<2>().norm() / kGravity;
    return rate * rate / (2.0 * 0.1);
  };
  AssemblyTrajectory limited, free;
  const AssemblyTrajectorySummary s_limited = opt.Optimize(map, StraightPath(0.0), tilt, &limited);
  ASSERT_TRUE(s_limited.ok()) << s_limited.message;
  ASSERT_TRUE(opt.Optimize(map, StraightPath(0.0), Limits(), &free).ok());
  EXPECT_GE(s_limited.limit_margin, 0.0);
  for (const double end : {1e-9, 1.0 - 1e-9}) {
    EXPECT_LE(overshoot(limited, end * limited.duration()), o.end_tilt_overshoot_rad * (1.0 + 1e-3)) << end;
    EXPECT_GT(overshoot(free, end * free.duration()), 2.0 * o.end_tilt_overshoot_rad) << end;
  }
}

/// By brute force: the smallest distance from a unit's centre to a wall voxel's cube (0.1 m, about
/// its centre) minus the unit's radius, every 10 ms of `traj`.
double BruteForceClearance(const Assembly& a, const AssemblyTrajectory& traj, const std::vector<Vector3>& wall) {
  double nearest = 1e9;
  for (double time = 0.0; time <= traj.duration(); time += 0.01) {
    const AssemblyPose pose = traj.PoseAt(time);
    const double c = std::cos(pose.yaw_rad), sn = std::sin(pose.yaw_rad);
    for (const Vector3& u : a.unit_position_B) {
      const Vector3 p = pose.p_W + Vector3(c * u.x() - sn * u.y(), sn * u.x() + c * u.y(), 0.0);
      for (const Vector3& w : wall) {
        nearest = std::min(nearest, ((p - w).cwiseAbs().array() - 0.05).cwiseMax(0.0).matrix().norm());
      }
    }
  }
  return nearest - a.unit_radius_m;
}

TEST(AssemblyTrajectoryOptimizer, TheFootprintPassesAGapNarrowerThanTheRowIsLong) {
  const Assembly a = testing::MarsAssembly("4x1");  // 1.05 m long, 0.3 m wide
  std::vector<Vector3> wall;
  const perception::VoxelMap map = WallWithGap(0.8, &wall);
  const RotorVector eta = RotorVector::Ones(16);
  const AssemblyPath path =
      FindAssemblyPath(map, a, eta, {Vector3(-1.5, 0.0, 1.5), 0.5 * kPi}, Vector3(1.5, 0.0, 1.5), Band());
  ASSERT_EQ(path.status, AssemblyPathStatus::kFound);
  for (const double weight : {50.0, 0.0}) {  // ours and the baseline
    AssemblyTrajectoryOptions o;
    o.weight_attitude = weight;
    AssemblyTrajectory traj;
    const AssemblyTrajectorySummary s = AssemblyTrajectoryOptimizer(a, eta, o).Optimize(map, path, Limits(), &traj);
    ASSERT_TRUE(s.ok()) << ToString(s.status) << ": " << s.message;
    EXPECT_GE(s.min_clearance_m, 0.0);
    // The truth by brute force: no unit's sphere reaches a wall voxel's cube.
    EXPECT_GE(BruteForceClearance(a, traj, wall), 0.0) << "weight " << weight;
  }
}

TEST(AssemblyTrajectoryOptimizer, CollisionRoundsPlanWhatOneSolveLeavesColliding) {
  // Starts and goals moved about a gap barely wider than the row: one solve's planes (each
  // sample's nearest obstacle) leave some footprints reaching a wall voxel; the collision rounds
  // plan every one of them clear, on an independent check.
  const Assembly a = testing::MarsAssembly("4x1");
  std::vector<Vector3> wall;
  const perception::VoxelMap map = WallWithGap(0.8, &wall);
  const RotorVector eta = RotorVector::Ones(16);
  AssemblyTrajectoryOptions one_solve;
  one_solve.collision_rounds = 0;
  int collided_once = 0, planned = 0, trials = 0;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const Vector3 start(-1.5, -0.3 + 0.2 * i, 1.5), goal(1.5, 0.3 - 0.2 * j, 1.5);
      const AssemblyPath path = FindAssemblyPath(map, a, eta, {start, 0.5 * kPi}, goal, Band());
      if (path.status != AssemblyPathStatus::kFound) continue;
      ++trials;
      for (const double weight : {50.0, 0.0}) {  // ours and the baseline
        AssemblyTrajectoryOptions o;
        o.weight_attitude = weight;
        one_solve.weight_attitude = weight;
        AssemblyTrajectory traj, once;
        const AssemblyTrajectorySummary s = AssemblyTrajectoryOptimizer(a, eta, o).Optimize(map, path, Limits(), &traj);
        const AssemblyTrajectorySummary s1 =
            AssemblyTrajectoryOptimizer(a, eta, one_solve).Optimize(map, path, Limits(), &once);
        if (s1.status == AssemblyTrajectorySummary::Status::kCollides) {
          ++collided_once;
          EXPECT_LT(BruteForceClearance(a, once, wall), 0.5 * std::sqrt(3.0) * 0.1);  // what it reported
        }
        if (!s.ok()) {
          ADD_FAILURE() << "start " << start.transpose() << ", goal " << goal.transpose() << ", weight " << weight
                        << ": " << ToString(s.status) << ": " << s.message;
          continue;
        }
        ++planned;
        EXPECT_GE(BruteForceClearance(a, traj, wall), 0.0) << "start " << start.transpose() << ", weight " << weight;
      }
    }
  }
  EXPECT_GE(trials, 8);
  EXPECT_EQ(planned, 2 * trials);
  EXPECT_GE(collided_once, 1) << "no case needed the collision rounds";
}

TEST(AssemblyTrajectoryOptimizer, BadInputIsReportedNotFlown) {
  const Assembly a = testing::MarsAssembly("4x1");
  AssemblyTrajectoryOptions o;
  o.samples_per_piece = 1;
  RG_EXPECT_THROW_WITH(AssemblyTrajectoryOptimizer(a, RotorVector::Ones(16), o), ValidationError,
                       "samples_per_piece = 1");
  const AssemblyTrajectoryOptimizer opt(a, RotorVector::Ones(16), {});
  AssemblyTrajectory traj;
  AssemblyPath none;
  EXPECT_EQ(opt.Optimize(WallWithGap(100.0), none, Limits(), &traj).status,
            AssemblyTrajectorySummary::Status::kInvalidInput);
  AssemblyLimits bad = Limits();
  bad.yaw_rate_max = -1.0;
  const AssemblyTrajectorySummary s = opt.Optimize(WallWithGap(100.0), StraightPath(0.0), bad, &traj);
  EXPECT_EQ(s.status, AssemblyTrajectorySummary::Status::kInvalidInput);
  EXPECT_NE(s.message.find("yaw_rate_max"), std::string::npos);
  EXPECT_TRUE(traj.empty());
}

}  // namespace
}  // namespace rotorguard::modular
