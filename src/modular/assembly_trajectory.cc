
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/modular/allocation.h"
#include "rotorguard/modular/assembly_trajectory.h"
#include "rotorguard/planning/lbfgs.h"

namespace rotorguard::modular {

namespace {

constexpr int kC = planning::MinimumJerkTrajectory::kCoefficients;
using planning::CubicPenalty;
using planning::TrajectoryOptimizer;  // for its duration map T(τ)

/// The yaw as a 3-D state: the yaw in x, y and z zero.
planning::PvaState YawState(double yaw) {
  planning::PvaState s = planning::PvaState::Zero();
  s(0, 0) = yaw;
  return s;
}

planning::PvaState RestState(const Vector3& p) {
  planning::PvaState s = planning::PvaState::Zero();
  s.col(0) = p;
  return s;
}

/// The largest s in [lo, hi] with ok(s) (ok(lo) holds), to `tolerance`.
template <typename Ok>
double Bisect(double lo, double hi, double tolerance, const Ok& ok) {
  if (ok(hi)) return hi;
  while (hi - lo > tolerance) {
    const double mid = 0.5 * (lo + hi);
    (ok(mid) ? lo : hi) = mid;
  }
  return lo;
}

/// A horizontal derivative `v` of the position (world frame) at yaw `yaw` in the body's frame,
/// against the ellipse with semi-axes `x_max` and `y_max` along the body's x and y: squared, <= 1
/// within, with its gradients. Near hover the body's x acceleration needs pitch (about y) and its
/// y acceleration roll, so the snap over g is the tilt's angular acceleration and the jerk over g
/// its rate.
struct TiltDemand {
  double squared = 0.0;
  Eigen::Vector2d d_horizontal = Eigen::Vector2d::Zero();
  double d_yaw = 0.0;
};
TiltDemand TiltDemandOf(double x_max, double y_max, const Eigen::Vector2d& v, double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  const Eigen::Vector2d b(c * v.x() + s * v.y(), -s * v.x() + c * v.y());  // R_z(-ψ) v
  const Eigen::Vector2d d_b(2.0 * b.x() / (x_max * x_max), 2.0 * b.y() / (y_max * y_max));
  TiltDemand t;
  t.squared = b.x() * b.x() / (x_max * x_max) + b.y() * b.y() / (y_max * y_max);
  t.d_horizontal = Eigen::Vector2d(c * d_b.x() - s * d_b.y(), s * d_b.x() + c * d_b.y());  // R_z(ψ) d_b
  t.d_yaw = d_b.x() * b.y() - d_b.y() * b.x();  // d b / dψ = (b_y, -b_x)
  return t;
}

/// The tilt limits' ellipses (AssemblyLimits, both on): the snap's, (g α_pitch, g α_roll); and the
/// jerk's at the plan's two ends. There the held reference steps the tilt rate ω = j / g to zero;
/// stopped at the angular acceleration α the tilt overshoots by ω² / (2 α), kept within `overshoot`
/// [rad]: |j| <= g sqrt(2 α overshoot) per axis.
struct TiltEllipses {
  double snap_x = 0.0, snap_y = 0.0, end_jerk_x = 0.0, end_jerk_y = 0.0;
};
TiltEllipses TiltEllipsesOf(const AssemblyLimits& limits, double overshoot_rad) {
  return {kGravity * limits.pitch_acceleration_max, kGravity * limits.roll_acceleration_max,
          kGravity * std::sqrt(2.0 * limits.pitch_acceleration_max * overshoot_rad),
          kGravity * std::sqrt(2.0 * limits.roll_acceleration_max * overshoot_rad)};
}

}  // namespace

// ---------------------------------------------------------------------------------------------

AssemblyTrajectory::AssemblyTrajectory(planning::MinimumJerkTrajectory position, planning::MinimumJerkTrajectory yaw)
    : position_(std::move(position)), yaw_(std::move(yaw)) {}

ReferencePoint AssemblyTrajectory::Evaluate(double t) const {
  ReferencePoint r = position_.Evaluate(t);
  const ReferencePoint y = yaw_.Evaluate(t);
  r.yaw = y.p_W.x();
  r.yaw_rate = y.v_W.x();
  return r;
}

AssemblyPose AssemblyTrajectory::PoseAt(double t) const {
  const ReferencePoint r = Evaluate(t);
  return {r.p_W, r.yaw};
}

// ---------------------------------------------------------------------------------------------

AssemblyCapacity CapacityOf(const Assembly& assembly, const RotorVector& eta) {
  AssemblyAllocator alloc(assembly, {});
  alloc.SetEffectiveness(eta);
  RotorVector u;
  const auto attainable = [&](const Eigen::Vector4d& w) { return alloc.Allocate(w, &u).attainable; };
  const vehicle::VehicleParams& v = assembly.vehicle;
  const double weight = v.weight_n();
  AssemblyCapacity c;
  c.hover_attainable = attainable(Eigen::Vector4d(weight, 0.0, 0.0, 0.0));
  if (!c.hover_attainable) return c;
  const double total = v.total_max_thrust_n();
  c.max_thrust_n = Bisect(weight, total, 1e-4 * total,
                          [&](double f) { return attainable(Eigen::Vector4d(f, 0.0, 0.0, 0.0)); });
  // Upper bounds of each torque: every rotor at full thrust with its lever arm (its reaction
  // torque for yaw).
  Vector3 reach = Vector3::Zero();
  for (const vehicle::Rotor& r : v.rotors) {
    reach += r.max_thrust_n * Vector3(std::abs(r.p_B.y()), std::abs(r.p_B.x()), r.yaw_coefficient_m);
  }
  // The largest torque about `axis` (1 roll, 2 pitch, 3 yaw) of either sign at the hover thrust.
  const auto torque = [&](int axis) {
    const auto one_sign = [&](double sign) {
      return Bisect(0.0, reach(axis - 1), 1e-4 * reach(axis - 1), [&](double tau) {
        Eigen::Vector4d w(weight, 0.0, 0.0, 0.0);
        w(axis) = sign * tau;
        return attainable(w);
      });
    };
    return std::min(one_sign(1.0), one_sign(-1.0));
  };
  c.max_yaw_torque_n_m = torque(3);
  const double f = c.max_thrust_n / v.mass_kg;
  c.max_acceleration_m_s2 = std::sqrt(std::max(f * f - kGravity * kGravity, 0.0));
  c.max_yaw_acceleration_rad_s2 = c.max_yaw_torque_n_m / v.inertia_kg_m2(2, 2);
  c.max_roll_acceleration_rad_s2 = torque(1) / v.inertia_kg_m2(0, 0);
  c.max_pitch_acceleration_rad_s2 = torque(2) / v.inertia_kg_m2(1, 1);
  return c;
}

void AssemblyLimits::Validate() const {
  kinematic.Validate();
  if (!(std::isfinite(yaw_rate_max) && yaw_rate_max >= 0.0)) {
    ThrowValidation("AssemblyLimits", "yaw_rate_max", yaw_rate_max, "a finite limit >= 0 (0: none)");
  }
  if (!(std::isfinite(yaw_acceleration_max) && yaw_acceleration_max >= 0.0)) {
    ThrowValidation("AssemblyLimits", "yaw_acceleration_max", yaw_acceleration_max, "a finite limit >= 0 (0: none)");
  }
  if (!(std::isfinite(thrust_acceleration_max) && (thrust_acceleration_max == 0.0 || thrust_acceleration_max > kGravity))) {
    ThrowValidation("AssemblyLimits", "thrust_acceleration_max", thrust_acceleration_max, "0 (none) or above g");
  }
  for (const auto& [v, field] : {std::pair{roll_acceleration_max, "roll_acceleration_max"},
                                 std::pair{pitch_acceleration_max, "pitch_acceleration_max"}}) {
    if (!(std::isfinite(v) && v >= 0.0)) ThrowValidation("AssemblyLimits", field, v, "a finite limit >= 0 (0: none)");
  }
  if ((roll_acceleration_max > 0.0) != (pitch_acceleration_max > 0.0)) {
    ThrowValidation("AssemblyLimits", "pitch_acceleration_max", pitch_acceleration_max,
                    "off (0) exactly when roll_acceleration_max is");
  }
}

bool HasMargin(const AssemblyCapacity& c) {
  return c.hover_attainable && c.max_acceleration_m_s2 > 0.0 && c.max_yaw_acceleration_rad_s2 > 0.0 &&
         c.max_roll_acceleration_rad_s2 > 0.0 && c.max_pitch_acceleration_rad_s2 > 0.0;
}

AssemblyLimits DynamicsAwareLimits(const planning::DynamicLimits& kinematic, const AssemblyCapacity& capacity,
                                   double mass_kg, double yaw_rate_max, double safety_factor) {
  if (!(safety_factor > 0.0 && safety_factor <= 1.0)) {
    ThrowInvalidArgument("DynamicsAwareLimits", "safety_factor", safety_factor, "a factor in (0, 1]");
  }
  if (!HasMargin(capacity)) {
    ThrowInvalidArgument("DynamicsAwareLimits", "capacity", capacity.max_acceleration_m_s2,
                         "an assembly that can hover with thrust and yaw torque to spare");
  }
  if (!(std::isfinite(mass_kg) && mass_kg > 0.0)) ThrowInvalidArgument("DynamicsAwareLimits", "mass_kg", mass_kg, "> 0");
  AssemblyLimits l;
  l.kinematic = kinematic;
  l.thrust_acceleration_max = kGravity + safety_factor * (capacity.max_thrust_n / mass_kg - kGravity);
  l.yaw_rate_max = yaw_rate_max;
  l.yaw_acceleration_max = safety_factor * capacity.max_yaw_acceleration_rad_s2;
  l.roll_acceleration_max = safety_factor * capacity.max_roll_acceleration_rad_s2;
  l.pitch_acceleration_max = safety_factor * capacity.max_pitch_acceleration_rad_s2;
  return l;
}

// ---------------------------------------------------------------------------------------------

void AssemblyTrajectoryOptions::Validate() const {
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowValidation("AssemblyTrajectoryOptions", field, v, rule);
  };
  for (const auto& [v, f] : {std::pair{weight_time, "weight_time"}, std::pair{weight_smoothness, "weight_smoothness"},
                             std::pair{weight_obstacle, "weight_obstacle"},
                             std::pair{weight_dynamics, "weight_dynamics"},
                             std::pair{weight_attitude, "weight_attitude"}}) {
    require(std::isfinite(v) && v >= 0.0, f, v, "a finite weight >= 0");
  }
  require(std::isfinite(clearance_m) && clearance_m >= 0.0, "clearance_m", clearance_m, "a distance >= 0 m");
  require(std::isfinite(obstacle_range_m) && obstacle_range_m > clearance_m, "obstacle_range_m", obstacle_range_m,
          "a distance > clearance_m");
  require(samples_per_piece >= 2 && samples_per_piece <= 1000, "samples_per_piece", samples_per_piece, "in [2, 1000]");
  require(plane_rounds >= 1, "plane_rounds", plane_rounds, ">= 1");
  require(max_iterations >= 1, "max_iterations", max_iterations, ">= 1");
  require(relative_cost_tolerance > 0.0 && relative_cost_tolerance <= 0.1, "relative_cost_tolerance",
          relative_cost_tolerance, "in (0, 0.1]");
  require(std::isfinite(waypoint_spacing_m) && waypoint_spacing_m > 0.0, "waypoint_spacing_m", waypoint_spacing_m,
          "a distance > 0 m");
  require(check_samples_per_piece >= samples_per_piece, "check_samples_per_piece", check_samples_per_piece,
          "at least samples_per_piece");
  require(max_slowdowns >= 0, "max_slowdowns", max_slowdowns, ">= 0");
  require(collision_rounds >= 0, "collision_rounds", collision_rounds, ">= 0");
  require(collision_weight_growth >= 1.0 && std::isfinite(collision_weight_growth), "collision_weight_growth",
          collision_weight_growth, "a finite value >= 1");
  require(slowdown_factor > 1.0 && slowdown_factor <= 2.0, "slowdown_factor", slowdown_factor, "in (1, 2]");
  require(attitude_bins >= 4 && attitude_bins <= 3600, "attitude_bins", attitude_bins, "in [4, 3600]");
  require(std::isfinite(end_tilt_overshoot_rad) && end_tilt_overshoot_rad > 0.0, "end_tilt_overshoot_rad",
          end_tilt_overshoot_rad, "an angle > 0 rad");
}

const char* ToString(AssemblyTrajectorySummary::Status status) {
  using S = AssemblyTrajectorySummary::Status;
  switch (status) {
    case S::kSuccess: return "success";
    case S::kInvalidInput: return "invalid_input";
    case S::kSolverFailure: return "solver_failure";
    case S::kInfeasible: return "infeasible";
    case S::kCollides: return "collides";
  }
  return "unknown";
}

AssemblyTrajectoryOptimizer::AssemblyTrajectoryOptimizer(const Assembly& assembly, const RotorVector& eta,
                                                         const AssemblyTrajectoryOptions& options)
    : assembly_(assembly), options_(options) {
  options_.Validate();
  // Eq. (7) depends on the yaw relative to the direction of flight only: solve it once, flying
  // along x.
  optimal_relative_yaws_ = OptimalYaws(assembly, eta, Eigen::Vector2d::UnitX(), options_.attitude_bins);
  for (double& a : optimal_relative_yaws_) a = std::fmod(a + 2.0 * std::numbers::pi, 2.0 * std::numbers::pi);
  if (optimal_relative_yaws_.empty()) {
    ThrowInvalidArgument("AssemblyTrajectoryOptimizer", "eta", "(no minimiser)", "rotors whose eq. (7) is finite");
  }
  std::sort(optimal_relative_yaws_.begin(), optimal_relative_yaws_.end());
  for (const Vector3& r : assembly.unit_position_B) yaw_length_m_ = std::max(yaw_length_m_, r.head<2>().norm());
}

double AssemblyTrajectoryOptimizer::AttitudeError(double yaw, double heading) const {
  double best = std::numeric_limits<double>::infinity();
  for (const double a : optimal_relative_yaws_) {
    const double e = WrapAngle(heading + a - yaw);
    if (std::abs(e) < std::abs(best)) best = e;
  }
  return best;
}

bool AssemblyTrajectoryOptimizer::Build(const Problem& problem, const Eigen::VectorXd& x,
                                        AssemblyTrajectory* out) const {
  const int m = static_cast<int>((x.size() + 4) / 5);
  if (m < 1 || x.size() != 5 * m - 4) return false;
  const Eigen::Matrix3Xd qp = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, m - 1);
  Eigen::Matrix3Xd qy = Eigen::Matrix3Xd::Zero(3, m - 1);
  qy.row(0) = x.segment(3 * (m - 1), m - 1).transpose();
  Eigen::VectorXd t(m);
  for (int i = 0; i < m; ++i) t(i) = TrajectoryOptimizer::DurationOf(x(4 * (m - 1) + i));
  planning::MinimumJerkTrajectory pos, yaw;
  if (!pos.Build(RestState(problem.start.p_W), RestState(problem.goal.p_W), qp, t)) return false;
  if (!yaw.Build(YawState(problem.start.yaw_rad), YawState(problem.goal.yaw_rad), qy, t)) return false;
  *out = AssemblyTrajectory(std::move(pos), std::move(yaw));
  return true;
}

double AssemblyTrajectoryOptimizer::Objective(const Problem& problem, const Eigen::VectorXd& x,
                                              Eigen::VectorXd* gradient) const {
  AssemblyTrajectory traj;
  if (!Build(problem, x, &traj)) return std::numeric_limits<double>::quiet_NaN();
  const planning::MinimumJerkTrajectory& pos = traj.position();
  const planning::MinimumJerkTrajectory& yaw = traj.yaw();
  const int m = pos.pieces();
  const Eigen::VectorXd& t = pos.durations();
  const AssemblyTrajectoryOptions& o = options_;
  const AssemblyLimits& lim = problem.limits;

  // J_t and J_m: the yaw's jerk energy counts as its farthest unit's (ψ times that distance).
  const double l2 = yaw_length_m_ * yaw_length_m_;
  Eigen::MatrixX3d dcp, dcy;
  Eigen::VectorXd dtp, dty;
  pos.EnergyPartials(&dcp, &dtp);
  yaw.EnergyPartials(&dcy, &dty);
  double cost = o.weight_time * t.sum() + o.weight_smoothness * (pos.Energy() + l2 * yaw.Energy());
  dcp *= o.weight_smoothness;
  dcy *= o.weight_smoothness * l2;
  Eigen::VectorXd dt = o.weight_smoothness * (dtp + l2 * dty) + Eigen::VectorXd::Constant(m, o.weight_time);

  const double limit2[3] = {lim.kinematic.v_max * lim.kinematic.v_max, lim.kinematic.a_max * lim.kinematic.a_max,
                            lim.kinematic.j_max * lim.kinematic.j_max};
  const double yaw_limit2[2] = {lim.yaw_rate_max * lim.yaw_rate_max,
                                lim.yaw_acceleration_max * lim.yaw_acceleration_max};
  const double required = assembly_.unit_radius_m + o.clearance_m;
  const int k_samples = o.samples_per_piece;
  // The tilt's ellipses penalised in snap² and jerk² units, as the kinematic terms (each one's
  // smaller axis squared).
  const TiltEllipses ellipse = TiltEllipsesOf(lim, o.end_tilt_overshoot_rad);
  const double tilt_scale = std::pow(std::min(ellipse.snap_x, ellipse.snap_y), 2);
  const double end_scale = std::pow(std::min(ellipse.end_jerk_x, ellipse.end_jerk_y), 2);
  for (int i = 0; i < m; ++i) {
    const auto cp = pos.coefficients().middleRows<kC>(kC * i);
    const auto cy = yaw.coefficients().middleRows<kC>(kC * i).col(0);
    std::size_t cursor = 0;
    for (int j = 0; j <= k_samples; ++j) {
      const double s = static_cast<double>(j) / k_samples, ts = s * t(i);
      const Eigen::Matrix<double, 5, kC> basis = planning::MinimumJerkTrajectory::BasisRows(ts);
      const Eigen::Matrix<double, 5, 3> der = basis * cp;  // p, v, a, j, snap
      const Eigen::Matrix<double, 5, 1> psi = basis * cy;  // ψ and its derivatives
      // Accumulates d cost / d (position derivative `d`) and d cost / d (yaw derivative `d`).
      const auto add_position = [&](int d, const Eigen::RowVector3d& g) {
        dcp.middleRows<kC>(kC * i) += basis.row(d).transpose() * g;
        // The sample moves with T_i; the quintic's fifth derivative is 5! times its last coefficient.
        dt(i) += g.dot(d < 4 ? Eigen::RowVector3d(der.row(d + 1)) : Eigen::RowVector3d(120.0 * cp.row(5))) * s;
      };
      const auto add_yaw = [&](int d, double g) {
        dcy.middleRows<kC>(kC * i).col(0) += basis.row(d).transpose() * g;
        dt(i) += g * psi(d + 1) * s;
      };
      // G_v, G_a, G_j (kinematic).
      for (int d = 1; d <= 3; ++d) {
        double slope;
        const double pen = CubicPenalty(der.row(d).squaredNorm() - limit2[d - 1], &slope);
        if (slope == 0.0) continue;
        cost += o.weight_dynamics * pen;
        add_position(d, o.weight_dynamics * slope * 2.0 * der.row(d));
      }
      // The thrust per kilogram, |a + g e_z| (the assembly's dynamics; 0: off).
      if (lim.thrust_acceleration_max > 0.0) {
        Eigen::RowVector3d f = der.row(2);
        f.z() += kGravity;
        double slope;
        const double pen = CubicPenalty(f.squaredNorm() - lim.thrust_acceleration_max * lim.thrust_acceleration_max,
                                        &slope);
        if (slope != 0.0) {
          cost += o.weight_dynamics * pen;
          add_position(2, o.weight_dynamics * slope * 2.0 * f);
        }
      }
      // A horizontal derivative `order` kept within the tilt's ellipse with semi-axes x_max, y_max
      // (TiltEllipsesOf), penalised in its units squared (`scale`: the smaller axis squared).
      const auto tilt_term = [&](int order, double x_max, double y_max, double scale) {
        const TiltDemand d = TiltDemandOf(x_max, y_max, der.row(order).head<2>().transpose(), psi(0));
        double slope;
        const double pen = CubicPenalty(scale * (d.squared - 1.0), &slope);
        if (slope == 0.0) return;
        const double w = o.weight_dynamics * slope * scale;
        cost += o.weight_dynamics * pen;
        add_position(order, Eigen::RowVector3d(w * d.d_horizontal.x(), w * d.d_horizontal.y(), 0.0));
        add_yaw(0, w * d.d_yaw);
      };
      if (lim.roll_acceleration_max > 0.0) {  // the assembly's dynamics; 0: off
        // The tilt's angular acceleration, the snap over g.
        tilt_term(4, ellipse.snap_x, ellipse.snap_y, tilt_scale);
        // Its rate, the jerk over g, where the plan starts and ends at rest: the held reference steps
        // it to or from zero there, so a row with little angular acceleration to spare (a long one
        // about its pitch) would overshoot, saturate its rotors and diverge.
        if ((i == 0 && j == 0) || (i == m - 1 && j == k_samples)) {
          tilt_term(3, ellipse.end_jerk_x, ellipse.end_jerk_y, end_scale);
        }
      }
      // The yaw's rate and acceleration (the assembly's dynamics; 0: off).
      for (int d = 1; d <= 2; ++d) {
        if (yaw_limit2[d - 1] <= 0.0) continue;
        double slope;
        const double pen = CubicPenalty(psi(d) * psi(d) - yaw_limit2[d - 1], &slope);
        if (slope == 0.0) continue;
        cost += o.weight_dynamics * pen;
        add_yaw(d, o.weight_dynamics * slope * 2.0 * psi(d));
      }
      // G_Φ (eq. 12b): |v_xy|² e², e = ψ* - ψ with ψ* = χ + α*, χ = atan2(v_y, v_x). The weight
      // cancels the heading's singularity: dχ/dv_xy = (-v_y, v_x) / |v_xy|², so
      // d/dv_xy = 2 e² v_xy + 2 e (-v_y, v_x).
      const Eigen::Vector2d vh = der.row(1).head<2>().transpose();
      if (o.weight_attitude > 0.0 && vh.squaredNorm() > 1e-12) {
        const double e = AttitudeError(psi(0), std::atan2(vh.y(), vh.x()));
        const double w = o.weight_attitude;
        cost += w * vh.squaredNorm() * e * e;
        Eigen::RowVector3d gv = Eigen::RowVector3d::Zero();
        gv.head<2>() = w * (2.0 * e * e * vh + 2.0 * e * Eigen::Vector2d(-vh.y(), vh.x())).transpose();
        add_position(1, gv);
        add_yaw(0, -w * 2.0 * vh.squaredNorm() * e);
      }
      // G_o: each unit's centre p + R_z(ψ) r_k against its plane.
      const double weight_obstacle = o.weight_obstacle * problem.obstacle_weight_scale;
      if (!problem.planes.empty() && weight_obstacle > 0.0) {
        const std::vector<FootprintPlane>& list = problem.planes[static_cast<std::size_t>(i)];
        while (cursor < list.size() && list[cursor].sample < j) ++cursor;
        for (std::size_t k = cursor; k < list.size() && list[k].sample == j; ++k) {
          const Vector3& r = assembly_.unit_position_B[static_cast<std::size_t>(list[k].unit)];
          const planning::ObstaclePlane& plane = list[k].plane;
          const Vector3 offset = QuaternionFromYaw(psi(0)) * r;  // R_z(ψ) r
          const Vector3 c = der.row(0).transpose() + offset;
          double slope;
          const double pen = CubicPenalty(required - (c - plane.point).dot(plane.normal), &slope);
          if (slope == 0.0) continue;
          cost += weight_obstacle * pen;
          const Eigen::RowVector3d gc = -weight_obstacle * slope * plane.normal.transpose();
          add_position(0, gc);
          add_yaw(0, gc.dot(Vector3::UnitZ().cross(offset).transpose()));  // d(R_z(ψ) r)/dψ = e_z × R_z(ψ) r
        }
      }
    }
  }
  if (gradient) {
    Eigen::Matrix3Xd dqp, dqy;
    Eigen::VectorXd dtp_total, dty_total;
    pos.PropagateGradient(&dcp, dt, &dqp, &dtp_total);
    yaw.PropagateGradient(&dcy, Eigen::VectorXd::Zero(m), &dqy, &dty_total);
    gradient->resize(x.size());
    gradient->head(3 * (m - 1)) = Eigen::Map<const Eigen::VectorXd>(dqp.data(), 3 * (m - 1));
    gradient->segment(3 * (m - 1), m - 1) = dqy.row(0).transpose();
    for (int i = 0; i < m; ++i) {
      const double tau = x(4 * (m - 1) + i);
      (*gradient)(4 * (m - 1) + i) = (dtp_total(i) + dty_total(i)) * t(i) / std::sqrt(tau * tau + 1.0);
    }
  }
  return cost;
}

FootprintPlaneSet AssemblyTrajectoryOptimizer::BuildPlanes(const perception::VoxelMap& map,
                                                           const AssemblyTrajectory& traj) const {
  const planning::MinimumJerkTrajectory& pos = traj.position();
  FootprintPlaneSet planes(static_cast<std::size_t>(pos.pieces()));
  for (int i = 0; i < pos.pieces(); ++i) {
    for (int j = 0; j <= options_.samples_per_piece; ++j) {
      const double ts = pos.durations()(i) * j / options_.samples_per_piece;
      const Vector3 p = pos.PieceDerivative(i, ts, 0);
      const double psi = traj.yaw().PieceDerivative(i, ts, 0).x();
      for (int k = 0; k < assembly_.num_units; ++k) {
        const Vector3 c = p + QuaternionFromYaw(psi) * assembly_.unit_position_B[static_cast<std::size_t>(k)];
        if (const auto hit = map.Nearest(c, options_.obstacle_range_m)) {
          planes[static_cast<std::size_t>(i)].push_back({j, k, {hit->point_W, hit->normal_W}});
        }
      }
    }
  }
  return planes;
}

std::optional<std::pair<AssemblyTrajectorySummary::Status, std::string>> AssemblyTrajectoryOptimizer::StretchToLimits(
    const Problem& problem, Eigen::VectorXd* x, AssemblyTrajectory* traj, AssemblyTrajectorySummary* summary) const {
  // Honest feasibility: check densely and stretch time while a limit is exceeded (between rest
  // states, durations times k scale v, a, j by 1/k, 1/k², 1/k³ and the yaw's rate and
  // acceleration by 1/k, 1/k²).
  using Status = AssemblyTrajectorySummary::Status;
  const AssemblyLimits& limits = problem.limits;
  const int dense = options_.check_samples_per_piece;
  for (int slowdowns = 0;; ++slowdowns) {
    const planning::MinimumJerkTrajectory& pos = traj->position();
    const int m = pos.pieces();
    std::vector<double> ratio = {pos.MaxNorm(1, dense) / limits.kinematic.v_max,
                                 std::sqrt(pos.MaxNorm(2, dense) / limits.kinematic.a_max),
                                 std::cbrt(pos.MaxNorm(3, dense) / limits.kinematic.j_max)};
    if (limits.yaw_rate_max > 0.0) ratio.push_back(traj->yaw().MaxNorm(1, dense) / limits.yaw_rate_max);
    if (limits.yaw_acceleration_max > 0.0) {
      ratio.push_back(std::sqrt(traj->yaw().MaxNorm(2, dense) / limits.yaw_acceleration_max));
    }
    // The thrust per kilogram and the tilt's demand on one pass over the dense samples.
    const TiltEllipses ellipse = TiltEllipsesOf(limits, options_.end_tilt_overshoot_rad);
    double thrust = 0.0, tilt = 0.0;
    if (limits.thrust_acceleration_max > 0.0 || limits.roll_acceleration_max > 0.0) {
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j <= dense; ++j) {
          const double ts = pos.durations()(i) * j / dense;
          thrust = std::max(thrust, (pos.PieceDerivative(i, ts, 2) + kGravity * Vector3::UnitZ()).norm());
          if (limits.roll_acceleration_max > 0.0) {
            tilt = std::max(tilt, TiltDemandOf(ellipse.snap_x, ellipse.snap_y, pos.PieceDerivative(i, ts, 4).head<2>(),
                                               traj->yaw().PieceDerivative(i, ts, 0).x())
                                      .squared);
          }
        }
      }
    }
    if (limits.thrust_acceleration_max > 0.0 && thrust > limits.thrust_acceleration_max) {
      // |a + g e_z| <= |a| + g: stretching until |a| <= limit - g is enough (a scales by 1 / k²).
      ratio.push_back(std::sqrt(pos.MaxNorm(2, dense) / (limits.thrust_acceleration_max - kGravity)));
    }
    if (limits.roll_acceleration_max > 0.0) {
      ratio.push_back(std::pow(tilt, 1.0 / 8.0));  // snap scales by 1 / k⁴
      for (const auto& [piece, time] : {std::pair{0, 0.0}, std::pair{m - 1, pos.durations()(m - 1)}}) {
        const double end = TiltDemandOf(ellipse.end_jerk_x, ellipse.end_jerk_y,
                                        pos.PieceDerivative(piece, time, 3).head<2>(),
                                        traj->yaw().PieceDerivative(piece, time, 0).x())
                               .squared;
        ratio.push_back(std::pow(end, 1.0 / 6.0));  // jerk scales by 1 / k³
      }
    }
    const double worst = *std::max_element(ratio.begin(), ratio.end());
    summary->limit_margin = 1.0 - worst;  // of the stretch factor's scale: >= 0 when all hold
    if (worst <= 1.0) return std::nullopt;
    if (slowdowns == options_.max_slowdowns) {
      return std::pair{Status::kInfeasible,
                       "a limit still exceeded after stretching time " + std::to_string(slowdowns) + " times"};
    }
    ++summary->slowdowns;
    const double k = std::min(worst * options_.slowdown_factor, 2.0);
    for (int i = 0; i < m; ++i) (*x)(4 * (m - 1) + i) = TrajectoryOptimizer::TauOf(k * pos.durations()(i));
    if (!Build(problem, *x, traj)) {
      return std::pair{Status::kSolverFailure, std::string("the stretched trajectory cannot be built")};
    }
  }
}

void AssemblyTrajectoryOptimizer::DenseCheck(const perception::VoxelMap& map, const AssemblyTrajectory& traj,
                                             AssemblyTrajectorySummary* summary) const {
  // The dense check of the footprint and of eq. (12b).
  const int dense = options_.check_samples_per_piece;
  const planning::MinimumJerkTrajectory& pos = traj.position();
  summary->duration_s = pos.total_duration();
  summary->min_clearance_m = options_.obstacle_range_m;
  double deviation = 0.0;
  int moving = 0;
  for (int i = 0; i < pos.pieces(); ++i) {
    for (int j = 0; j <= dense; ++j) {
      const double ts = pos.durations()(i) * j / dense;
      const AssemblyPose pose{pos.PieceDerivative(i, ts, 0), traj.yaw().PieceDerivative(i, ts, 0).x()};
      const Vector3 v = pos.PieceDerivative(i, ts, 1);
      if (v.head<2>().norm() > 0.1) {
        deviation += std::abs(AttitudeError(pose.yaw_rad, std::atan2(v.y(), v.x())));
        ++moving;
      }
      for (const Vector3& r : assembly_.unit_position_B) {
        if (const auto hit = map.Nearest(pose.p_W + QuaternionFromYaw(pose.yaw_rad) * r, options_.obstacle_range_m)) {
          summary->min_clearance_m = std::min(summary->min_clearance_m, hit->distance_m - assembly_.unit_radius_m);
        }
      }
    }
  }
  summary->attitude_deviation_rad = moving > 0 ? deviation / moving : 0.0;
}

AssemblyTrajectorySummary AssemblyTrajectoryOptimizer::Optimize(const perception::VoxelMap& map,
                                                                const AssemblyPath& path,
                                                                const AssemblyLimits& limits,
                                                                AssemblyTrajectory* out) const {
  using Status = AssemblyTrajectorySummary::Status;
  const Stopwatch clock;
  AssemblyTrajectorySummary summary;
  const auto finish = [&](Status status, std::string message) {
    summary.status = status;
    summary.message = std::move(message);
    summary.solve_ms = clock.milliseconds();
    return summary;
  };
  if (const auto broken = BrokenRule([&] { limits.Validate(); })) return finish(Status::kInvalidInput, *broken);
  if (path.status != AssemblyPathStatus::kFound || path.poses.size() < 2) {
    return finish(Status::kInvalidInput, "need a found A* path of at least two poses");
  }

  // The initial guess: the A* poses, one per waypoint_spacing_m of the path and at every yaw
  // turn, the yaw unwrapped so that each step turns the short way.
  std::vector<AssemblyPose> poses = path.poses;
  std::vector<AssemblyPose> keep{poses.front()};
  double since = 0.0;
  for (std::size_t k = 1; k < poses.size(); ++k) {
    const double turn = WrapAngle(poses[k].yaw_rad - path.poses[k - 1].yaw_rad);
    poses[k].yaw_rad = poses[k - 1].yaw_rad + turn;
    since += (poses[k].p_W - poses[k - 1].p_W).norm();
    if (since >= options_.waypoint_spacing_m || std::abs(turn) > 1e-9 || k + 1 == poses.size()) {
      keep.push_back(poses[k]);
      since = 0.0;
    }
  }
  const int m = static_cast<int>(keep.size()) - 1;
  Problem problem;
  problem.start = keep.front();
  problem.goal = keep.back();
  problem.limits = limits;
  const double v_guess = 0.5 * limits.kinematic.v_max;
  const double w_guess = limits.yaw_rate_max > 0.0 ? 0.5 * limits.yaw_rate_max : 0.5;
  Eigen::VectorXd x(5 * m - 4);
  for (int i = 0; i < m; ++i) {
    const AssemblyPose &a = keep[static_cast<std::size_t>(i)], &b = keep[static_cast<std::size_t>(i) + 1];
    if (i + 1 < m) {
      x.segment<3>(3 * i) = b.p_W;
      x(3 * (m - 1) + i) = b.yaw_rad;
    }
    const double duration =
        std::max({(b.p_W - a.p_W).norm() / v_guess, std::abs(b.yaw_rad - a.yaw_rad) / w_guess, 0.2});
    x(4 * (m - 1) + i) = TrajectoryOptimizer::TauOf(duration);
  }

  AssemblyTrajectory traj;
  if (!Build(problem, x, &traj)) return finish(Status::kInvalidInput, "the initial guess has no trajectory");
  std::string message;
  const auto solve = [&] {
    const planning::LbfgsSummary lbfgs = planning::MinimizeLbfgs(
        [&](const Eigen::VectorXd& v, Eigen::VectorXd* g) { return Objective(problem, v, g); },
        {options_.max_iterations, options_.relative_cost_tolerance}, &x);
    summary.iterations += lbfgs.iterations;
    summary.evaluations += lbfgs.evaluations;
    message = lbfgs.message;
    return x.allFinite() && !lbfgs.failed && Build(problem, x, &traj);
  };
  for (int round = 0; round < options_.plane_rounds; ++round) {
    problem.planes = BuildPlanes(map, traj);
    if (!solve()) return finish(Status::kSolverFailure, "L-BFGS: " + message);
  }

  const double reach = 0.5 * std::sqrt(3.0) * map.resolution();
  for (;;) {
    if (const auto failed = StretchToLimits(problem, &x, &traj, &summary)) return finish(failed->first, failed->second);
    DenseCheck(map, traj, &summary);
    if (summary.min_clearance_m >= reach) break;
    if (summary.collision_rounds == options_.collision_rounds) {
      *out = traj;
      return finish(Status::kCollides,
                    fmt::format("a unit's sphere may reach an occupied voxel: it comes within {:.3f} m of a voxel's "
                                "centre beyond its radius, less than the voxel's half-diagonal {:.3f} m",
                                summary.min_clearance_m, reach));
    }
    // The planes of each sample's nearest obstacles are local: where the solution crossed into
    // another obstacle's reach, solve again with its planes added and the clearance weighted more.
    ++summary.collision_rounds;
    const FootprintPlaneSet added = BuildPlanes(map, traj);
    for (std::size_t i = 0; i < added.size(); ++i) {
      std::vector<FootprintPlane>& list = problem.planes[i];
      const auto kept = static_cast<std::ptrdiff_t>(list.size());
      list.insert(list.end(), added[i].begin(), added[i].end());  // both sorted by sample
      std::inplace_merge(list.begin(), list.begin() + kept, list.end(),
                         [](const FootprintPlane& a, const FootprintPlane& b) { return a.sample < b.sample; });
    }
    problem.obstacle_weight_scale *= options_.collision_weight_growth;
    if (!solve()) return finish(Status::kSolverFailure, "L-BFGS: " + message);
  }
  *out = traj;
  return finish(Status::kSuccess, message);
}

}  // namespace rotorguard::modular
