
#include "rotorguard/planning/trajectory_optimizer.h"

#include <algorithm>
#include <limits>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/planning/lbfgs.h"

namespace rotorguard::planning {

namespace {

constexpr int kC = MinimumJerkTrajectory::kCoefficients;

/// Splits x = [q columns, τ] into waypoints and durations.
void Unpack(const Eigen::VectorXd& x, int pieces, Eigen::Matrix3Xd* q, Eigen::VectorXd* t) {
  *q = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, pieces - 1);
  t->resize(pieces);
  for (int i = 0; i < pieces; ++i) (*t)(i) = TrajectoryOptimizer::DurationOf(x(3 * (pieces - 1) + i));
}

/// The objective's buffers, kept between evaluations (a solve makes hundreds of the same size, and
/// none then allocates): one set per thread, so that optimisers on several threads share none.
struct ObjectiveWorkspace {
  Eigen::Matrix3Xd q, dq;
  Eigen::VectorXd t, dt, d_durations;
  Eigen::MatrixX3d dc;
  MinimumJerkTrajectory traj;
};

ObjectiveWorkspace& Workspace() {
  thread_local ObjectiveWorkspace workspace;
  return workspace;
}

}  // namespace

void DynamicLimits::Validate() const {
  const auto require = [](double v, const char* field, double max) {
    if (!(v > 0.0 && v <= max)) ThrowValidation("DynamicLimits", field, v, fmt::format("a limit in (0, {:g}]", max));
  };
  require(v_max, "v_max", kMaxSpeedMS);
  require(a_max, "a_max", kMaxAccelerationMS2);
  if (limits_jerk()) require(j_max, "j_max", kMaxJerkMS3);
}

double PostFailureAccelerationLimit(double mass_kg, double rotor_max_thrust_n, double max_drag_coefficient_kg_s,
                                    double v_max, double safety_factor) {
  const double weight = mass_kg * 9.81, thrust = 2.0 * rotor_max_thrust_n;
  if (thrust <= weight) return 0.0;
  const double f_max = max_drag_coefficient_kg_s * v_max;
  return safety_factor * std::abs((std::sqrt(thrust * thrust - weight * weight) - f_max) / mass_kg);
}

double DegradedAccelerationLimit(double nominal_a_max, double weight_n, const std::vector<double>& rotor_max_thrust_n,
                                 const std::vector<double>& effectiveness) {
  if (rotor_max_thrust_n.size() != effectiveness.size() || rotor_max_thrust_n.empty()) {
    ThrowInvalidArgument("DegradedAccelerationLimit", "effectiveness", effectiveness.size(),
                         fmt::format("{} entries, one per rotor", rotor_max_thrust_n.size()));
  }
  double nominal = 0.0, weakest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < effectiveness.size(); ++i) {
    nominal += rotor_max_thrust_n[i];
    weakest = std::min(weakest, std::clamp(effectiveness[i], 0.0, 1.0) * rotor_max_thrust_n[i]);
  }
  const double degraded = static_cast<double>(effectiveness.size()) * weakest;
  const double w2 = weight_n * weight_n;
  if (degraded <= weight_n || nominal <= weight_n) return 0.0;
  return nominal_a_max * std::sqrt(degraded * degraded - w2) / std::sqrt(nominal * nominal - w2);
}

void TrajectoryOptimizerOptions::Validate() const {
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowValidation("TrajectoryOptimizerOptions", field, v, rule);
  };
  CheckDeclaredRanges("TrajectoryOptimizerOptions", weights, "weights.");
  if (!(clearance_m >= 0.0 && clearance_m <= kMaxClearanceM)) {
    ThrowValidation("TrajectoryOptimizerOptions", "clearance_m", clearance_m,
                    fmt::format("a distance in [0, {:g}] m", kMaxClearanceM));
  }
  require(samples_per_piece >= 2 && samples_per_piece <= 1000, "samples_per_piece", samples_per_piece, "in [2, 1000]");
  lbfgs.Validate();
  require(check_samples_per_piece >= samples_per_piece, "check_samples_per_piece", check_samples_per_piece,
          "at least samples_per_piece");
  require(max_slowdowns >= 0, "max_slowdowns", max_slowdowns, ">= 0");
  require(slowdown_factor > 1.0 && slowdown_factor <= 2.0, "slowdown_factor", slowdown_factor, "in (1, 2]");
}

PlaneSet BuildSamplePlanes(const MinimumJerkTrajectory& traj, int samples_per_piece, const NearestPlane& nearest) {
  PlaneSet planes(static_cast<std::size_t>(traj.pieces()));
  for (int i = 0; i < traj.pieces(); ++i) {
    for (int j = 0; j <= samples_per_piece; ++j) {
      const Vector3 p = traj.PieceDerivative(i, traj.durations()(i) * j / samples_per_piece, 0);
      if (const std::optional<ObstaclePlane> plane = nearest(p)) planes[static_cast<std::size_t>(i)].push_back({j, *plane});
    }
  }
  return planes;
}

const char* ToString(TrajectoryOptimizerSummary::Status status) {
  switch (status) {
    case TrajectoryOptimizerSummary::Status::kSuccess: return "success";
    case TrajectoryOptimizerSummary::Status::kInvalidInput: return "invalid_input";
    case TrajectoryOptimizerSummary::Status::kSolverFailure: return "solver_failure";
    case TrajectoryOptimizerSummary::Status::kInfeasible: return "infeasible";
  }
  return "unknown";
}

TrajectoryOptimizer::TrajectoryOptimizer(const TrajectoryOptimizerOptions& options) : options_(options) {
  options_.Validate();
}

double TrajectoryOptimizer::Objective(const PvaState& head, const PvaState& tail, const DynamicLimits& limits,
                                      const PlaneSet& planes, const Eigen::VectorXd& x,
                                      Eigen::VectorXd* gradient) const {
  ObjectiveWorkspace& w = Workspace();
  const int pieces = static_cast<int>((x.size() + 3) / 4);
  Unpack(x, pieces, &w.q, &w.t);
  MinimumJerkTrajectory& traj = w.traj;
  if (!traj.Build(head, tail, w.q, w.t)) return std::numeric_limits<double>::quiet_NaN();
  const TrajectoryOptimizerOptions& o = options_;
  const Eigen::VectorXd& t = w.t;
  Eigen::MatrixX3d& dc = w.dc;
  Eigen::VectorXd& dt = w.dt;
  traj.EnergyPartials(&dc, &dt);
  double cost = o.weights.time * t.sum() + o.weights.smoothness * traj.Energy();
  dc *= o.weights.smoothness;
  dt = dt * o.weights.smoothness + Eigen::VectorXd::Constant(pieces, o.weights.time);
  // Sampled penalties, cubed throughout (the paper cubes the clearance term only). A sample at
  // t = s T_i moves with T_i: its explicit derivative is the next derivative of the sampled
  // quantity times s. Only the derivatives a term uses are evaluated: v, a (and j with a jerk
  // limit) and the next one for the time derivative; the position only with obstacle planes.
  const double limit2[3] = {limits.v_max * limits.v_max, limits.a_max * limits.a_max, limits.j_max * limits.j_max};
  const int max_order = limits.highest_limited_order();
  const bool clearance = !planes.empty() && o.weights.collision > 0.0;
  const int first_order = clearance ? 0 : 1;
  constexpr auto& kFactor = MinimumJerkTrajectory::kDerivativeFactor;
  const int k_samples = o.samples_per_piece;
  for (int i = 0; i < pieces; ++i) {
    const Eigen::Matrix<double, kC, 3> c = traj.coefficients().middleRows<kC>(kC * i);
    Eigen::Matrix<double, kC, 3> dci = Eigen::Matrix<double, kC, 3>::Zero();
    double dti = 0.0;
    // The derivatives' polynomials: row k of poly[d] multiplies t^k in derivative d.
    Eigen::Matrix<double, kC, 3> poly[5];
    for (int d = first_order; d <= max_order + 1; ++d) {
      for (int k = 0; k + d < kC; ++k) poly[d].row(k) = kFactor[d][k + d] * c.row(k + d);
    }
    std::size_t cursor = 0;  // the piece's planes, sorted by sample: the first of sample j
    for (int j = 0; j <= k_samples; ++j) {
      const double s = static_cast<double>(j) / k_samples, ts = s * t(i);
      double power[kC];  // ts^k
      power[0] = 1.0;
      for (int k = 1; k < kC; ++k) power[k] = power[k - 1] * ts;
      Vector3 der[5];  // p, v, a, j, snap at ts, by Horner's rule
      for (int d = first_order; d <= max_order + 1; ++d) {
        Eigen::RowVector3d v = poly[d].row(kC - 1 - d);
        for (int k = kC - 2 - d; k >= 0; --k) v = v * ts + poly[d].row(k);
        der[d] = v.transpose();
      }
      // d cost / d (derivative d at this sample) into the piece's coefficients and duration.
      const auto accumulate = [&](int d, const Vector3& dp) {
        for (int k = d; k < kC; ++k) dci.row(k) += (kFactor[d][k] * power[k - d]) * dp.transpose();
        dti += dp.dot(der[d + 1]) * s;
      };
      for (int d = 1; d <= max_order; ++d) {  // J_d: velocity, acceleration, jerk (eqs. 26-29)
        double slope;
        const double pen = CubicPenalty(der[d].squaredNorm() - limit2[d - 1], &slope);
        if (slope == 0.0) continue;
        cost += o.weights.feasibility * pen;
        accumulate(d, (o.weights.feasibility * slope * 2.0) * der[d]);
      }
      if (clearance) {  // J_c (eqs. 34-36)
        const std::vector<SamplePlane>& list = planes[static_cast<std::size_t>(i)];
        while (cursor < list.size() && list[cursor].sample < j) ++cursor;
        for (std::size_t k = cursor; k < list.size() && list[k].sample == j; ++k) {
          const ObstaclePlane& plane = list[k].plane;
          double slope;
          const double pen = CubicPenalty(o.clearance_m - (der[0] - plane.point).dot(plane.normal), &slope);
          if (slope == 0.0) continue;  // (a NaN plane makes the cost NaN: a failed evaluation, not a skip)
          cost += o.weights.collision * pen;
          accumulate(0, (-o.weights.collision * slope) * plane.normal);
        }
      }
    }
    dc.middleRows<kC>(kC * i) += dci;
    dt(i) += dti;
  }
  if (gradient) {
    traj.PropagateGradient(&dc, dt, &w.dq, &w.d_durations);
    gradient->resize(x.size());
    gradient->head(3 * (pieces - 1)) = Eigen::Map<const Eigen::VectorXd>(w.dq.data(), 3 * (pieces - 1));
    for (int i = 0; i < pieces; ++i) {
      const double tau = x(3 * (pieces - 1) + i);
      (*gradient)(3 * (pieces - 1) + i) = w.d_durations(i) * t(i) / std::sqrt(tau * tau + 1.0);  // dT/dτ
    }
  }
  return cost;
}

Eigen::VectorXd TrajectoryOptimizer::Variables(const Eigen::Matrix3Xd& waypoints, const Eigen::VectorXd& durations) {
  const auto pieces = durations.size();
  Eigen::VectorXd x(4 * pieces - 3);
  x.head(3 * (pieces - 1)) = Eigen::Map<const Eigen::VectorXd>(waypoints.data(), 3 * (pieces - 1));
  for (Eigen::Index i = 0; i < pieces; ++i) x(3 * (pieces - 1) + i) = TauOf(durations(i));
  return x;
}

TrajectoryOptimizerSummary TrajectoryOptimizer::Optimize(const PvaState& head, const PvaState& tail,
                                                         const Eigen::Matrix3Xd& waypoints,
                                                         const Eigen::VectorXd& durations, const DynamicLimits& limits,
                                                         const PlaneSet& planes,
                                                         MinimumJerkTrajectory* out) const {
  using Status = TrajectoryOptimizerSummary::Status;
  const Stopwatch clock;
  TrajectoryOptimizerSummary summary;
  const int pieces = static_cast<int>(durations.size());
  const auto fail = [&](Status status, std::string message) {
    summary.status = status;
    summary.message = std::move(message);
    summary.solve_ms = clock.milliseconds();
    return summary;
  };
  if (const auto broken = BrokenRule([&] { limits.Validate(); })) return fail(Status::kInvalidInput, *broken);
  if (pieces < 1 || waypoints.cols() != pieces - 1 || !waypoints.allFinite() || !durations.allFinite() ||
      (durations.array() <= 0.0).any() || !head.allFinite() || !tail.allFinite() ||
      (!planes.empty() && static_cast<int>(planes.size()) != pieces)) {
    return fail(Status::kInvalidInput,
                "need finite head, tail, M - 1 waypoints, M positive durations and no planes or M lists");
  }
  PlaneSet sorted = planes;  // the objective walks each piece's planes in sample order
  for (std::vector<SamplePlane>& list : sorted) {
    std::stable_sort(list.begin(), list.end(), [](const SamplePlane& a, const SamplePlane& b) { return a.sample < b.sample; });
  }
  Eigen::VectorXd x = Variables(waypoints, durations);
  summary.initial_cost = Objective(head, tail, limits, sorted, x, nullptr);
  if (!std::isfinite(summary.initial_cost)) return fail(Status::kInvalidInput, "the initial guess has no trajectory");

  const LbfgsSummary lbfgs = MinimizeLbfgs(
      [&](const Eigen::VectorXd& v, Eigen::VectorXd* g) { return Objective(head, tail, limits, sorted, v, g); },
      options_.lbfgs, &x);
  summary.iterations = lbfgs.iterations;
  summary.evaluations = lbfgs.evaluations;
  summary.final_cost = Objective(head, tail, limits, sorted, x, nullptr);
  if (!x.allFinite() || !std::isfinite(summary.final_cost) || lbfgs.failed) {
    return fail(Status::kSolverFailure, "L-BFGS: " + lbfgs.message);
  }

  // Honest feasibility: check densely and, while a limit is exceeded, stretch time. With the
  // durations scaled by k a trajectory between rest states is the same path with v / k, a / k² and
  // j / k³; with a moving head it is close to that. So k comes from the worst excess of each.
  Eigen::Matrix3Xd q;
  Eigen::VectorXd t;
  Unpack(x, pieces, &q, &t);
  MinimumJerkTrajectory traj;
  // The head state is given: where it already exceeds a limit (a replan right after the limit
  // dropped on a failure) the check holds the trajectory to the head's own value instead, which
  // no choice of waypoints or durations could undercut.
  const double limit[3] = {std::max(limits.v_max, head.col(1).norm()), std::max(limits.a_max, head.col(2).norm()),
                           limits.j_max};
  const Stopwatch check_clock;
  for (;;) {
    if (!traj.Build(head, tail, q, t)) return fail(Status::kSolverFailure, "the optimised trajectory cannot be built");
    double ratio[3] = {0.0, 0.0, 0.0};  // max |derivative| / limit, of the limited ones
    for (int d = 1; d <= limits.highest_limited_order(); ++d) {
      ratio[d - 1] = traj.MaxNorm(d, options_.check_samples_per_piece) / limit[d - 1];
    }
    summary.limit_margin = 1.0 - std::max({ratio[0], ratio[1], ratio[2]});
    if (summary.limit_margin >= 0.0) break;
    if (summary.slowdowns == options_.max_slowdowns) {
      return fail(Status::kInfeasible, "a limit still exceeded after stretching time " +
                                           std::to_string(summary.slowdowns) + " times");
    }
    ++summary.slowdowns;
    const double k = std::max({ratio[0], std::sqrt(ratio[1]), std::cbrt(ratio[2]), 1.0}) * options_.slowdown_factor;
    t *= std::min(k, 2.0);
  }
  summary.check_ms = check_clock.milliseconds();
  *out = std::move(traj);
  summary.status = Status::kSuccess;
  summary.message = lbfgs.message;
  summary.solve_ms = clock.milliseconds();
  return summary;
}

}  // namespace rotorguard::planning
