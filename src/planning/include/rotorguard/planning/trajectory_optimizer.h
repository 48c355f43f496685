#pragma once
/// Spatio-temporal optimisation of a minimum-jerk trajectory (paper 000, Sec. V-C, eq. 22):
///   min over {q, T} of  λ_t J_t + λ_s J_s + λ_d J_d + λ_c J_c
/// with J_t the total time (eq. 23), J_s the jerk energy (eq. 24), J_d the velocity, acceleration
/// and jerk limits sampled along each piece (eqs. 25-29) and J_c the clearance from obstacle planes
/// (eqs. 34-36), a set of planes per piece. Durations are optimised through a smooth positive
/// map, T = τ + sqrt(τ² + 1), so that the problem is unconstrained, and solved by an L-BFGS
/// (lbfgs.h: this library's by default, or Ceres'), to which any non-finite cost or gradient is a
/// failed evaluation.
///
/// Penalties alone do not guarantee limits, so the result is checked densely afterwards and, while
/// a limit is exceeded, time is stretched until it holds (see `Summary`).
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"
#include "rotorguard/planning/lbfgs.h"
#include "rotorguard/planning/minco.h"

namespace rotorguard::planning {

/// Magnitude limits on the trajectory's derivatives.
/// Each in (0, its kMax...] (core/config_schema.h): a limit beyond a multirotor's reach only makes
/// the collision checks' time steps (a step in metres over v_max) vanish.
struct DynamicLimits {
  /// j_max's value for no jerk limit: the objective then has no jerk term and the dense check
  /// samples no jerk.
  static constexpr double kNoLimit = std::numeric_limits<double>::infinity();
  double v_max = 1.0;  ///< [m/s], in (0, kMaxSpeedMS]
  double a_max = 2.0;  ///< [m/s²], in (0, kMaxAccelerationMS2] (a_max,n nominal; a_max,f of eq. 33 after a failure)
  double j_max = 6.0;  ///< [m/s³], in (0, kMaxJerkMS3], or kNoLimit
  bool limits_jerk() const { return j_max != kNoLimit; }
  /// The highest derivative with a limit: 3 (jerk), or 2 without a jerk limit.
  int highest_limited_order() const { return limits_jerk() ? 3 : 2; }
  void Validate() const;
};

/// Eq. (33): the acceleration a post-failure vehicle can still command horizontally when the rotor
/// opposite the failed one is assumed lost too, so that two rotors of max thrust `rotor_max_thrust_n`
/// remain: γ |(sqrt((2 T̄)² - (m g)²) - f_max) / m| with f_max = ||R D R^T|| v_max (= the largest
/// drag coefficient times v_max). Returns 0 when two rotors cannot hold the weight.
double PostFailureAccelerationLimit(double mass_kg, double rotor_max_thrust_n, double max_drag_coefficient_kg_s,
                                    double v_max, double safety_factor);

/// Eq. (33)'s idea for a partial loss, where every rotor still flies and yaw stays controlled: the
/// nominal limit scaled by the horizontal thrust left, a_n sqrt(T_d² - W²) / sqrt(T_n² - W²), with
/// T_n = sum of the rotors' max thrusts ū_i and T_d = n min_i(eta_i ū_i), the most a balanced split
/// (equal effective thrusts, as the NMPC's minimum-norm allocation of a symmetric vehicle) can give.
/// 0 when T_d cannot hold the weight W. Throws std::invalid_argument for sizes that differ.
double DegradedAccelerationLimit(double nominal_a_max, double weight_n, const std::vector<double>& rotor_max_thrust_n,
                                 const std::vector<double>& effectiveness);

/// An obstacle as the plane of eq. (34): through `point`, with unit `normal` pointing to free space;
/// a position p is at signed distance (p - point) . normal from it (eq. 35).
struct ObstaclePlane {
  Vector3 point;
  Vector3 normal;
};
/// A plane that one penalty sample keeps clear of (eq. 36): sample `sample` (0..samples_per_piece)
/// of its piece. The planner builds them from each sample's nearest obstacle along the initial
/// trajectory (the front end's path) and holds them during a solve: a linearisation of the
/// distance to the obstacles, exact in its gradient, that spares the cost any map query.
struct SamplePlane {
  int sample = 0;
  ObstaclePlane plane;
};
/// One list per piece; empty for free space. Optimize takes the lists in any order; Objective
/// needs each sorted by sample (as BuildSamplePlanes makes them).
using PlaneSet = std::vector<std::vector<SamplePlane>>;

/// The nearest obstacle's plane at a position (point on its surface, normal towards the
/// position), if one lies within the caller's search radius.
using NearestPlane = std::function<std::optional<ObstaclePlane>(const Vector3& position)>;

/// The planes for `traj`'s penalty samples (samples_per_piece + 1 per piece, as the optimiser
/// places them), each sample's nearest obstacle where `nearest` finds one.
PlaneSet BuildSamplePlanes(const MinimumJerkTrajectory& traj, int samples_per_piece, const NearestPlane& nearest);

/// Eq. (22)'s weights λ = [λ_t, λ_s, λ_d, λ_c] (paper 000 Sec. VI: [10, 1, 1e4, 1e4]), each in
/// [0, kMaxWeight].
struct CostWeights {
  double time = 10.0;
  double smoothness = 1.0;
  double feasibility = 1e4;
  double collision = 1e4;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("time", &time, {.meaning = "λ_t, on the trajectory's duration", .min = 0.0, .max = kMaxWeight});
    a->Visit("smoothness", &smoothness,
             {.meaning = "λ_s, on the integrated squared jerk", .min = 0.0, .max = kMaxWeight});
    a->Visit("feasibility", &feasibility,
             {.meaning = "λ_d, on speed, acceleration and jerk beyond the limits", .min = 0.0, .max = kMaxWeight});
    a->Visit("collision", &collision,
             {.meaning = "λ_c, on points closer than the clearance to an obstacle", .min = 0.0, .max = kMaxWeight});
  }
};

/// [m]: the largest clearance a plan keeps from obstacles; more than any vehicle's margin, and the
/// obstacle planes are searched for that far around every sample.
inline constexpr double kMaxClearanceM = 10.0;

struct TrajectoryOptimizerOptions {
  CostWeights weights;
  double clearance_m = 0.3;      ///< C_o of eq. (36), the safe distance [m], in [0, kMaxClearanceM]
  int samples_per_piece = 16;    ///< penalty samples per piece (κ / M), >= 2
  /// The L-BFGS (lbfgs.h): this library's (the default: lower costs than Ceres' and than GCOPTER's
  /// L-BFGS on the same problems) or Ceres', at most 200 iterations, and a relative cost tolerance
  /// in (0, 0.1] (docs/planning.md, "The L-BFGS").
  LbfgsOptions lbfgs{.method = LbfgsMethod::kLewisOverton};
  /// The dense feasibility check: samples per piece, and the at most `max_slowdowns` rounds that
  /// stretch all durations by the factor that the worst excess calls for (v / k, a / k², j / k³),
  /// times `slowdown_factor` for a margin.
  int check_samples_per_piece = 64;
  int max_slowdowns = 10;
  double slowdown_factor = 1.02;
  void Validate() const;
};

struct TrajectoryOptimizerSummary {
  enum class Status { kSuccess, kInvalidInput, kSolverFailure, kInfeasible };
  Status status = Status::kInvalidInput;
  std::string message;
  int iterations = 0;
  int evaluations = 0;
  int slowdowns = 0;            ///< rounds of time stretching by the feasibility repair
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double solve_ms = 0.0;
  double check_ms = 0.0;  ///< of solve_ms, the dense limit check and its time stretching
  /// min over v, a, j of (limit - max value) / limit on the dense check: >= 0 when all hold.
  /// (A head velocity or acceleration beyond its limit raises that limit to the head's value.)
  double limit_margin = 0.0;
  bool ok() const { return status == Status::kSuccess; }
};
const char* ToString(TrajectoryOptimizerSummary::Status status);

class TrajectoryOptimizer {
 public:
  /// Throws ValidationError on invalid options.
  explicit TrajectoryOptimizer(const TrajectoryOptimizerOptions& options);

  /// Optimises the waypoints and durations from an initial guess (waypoints 3 x (M - 1), durations
  /// M > 0); `planes` is empty (free space) or holds one list per piece. On success `out` holds a
  /// trajectory within `limits` on the dense check.
  TrajectoryOptimizerSummary Optimize(const PvaState& head, const PvaState& tail, const Eigen::Matrix3Xd& waypoints,
                                      const Eigen::VectorXd& durations, const DynamicLimits& limits,
                                      const PlaneSet& planes, MinimumJerkTrajectory* out) const;

  /// The objective of eq. (22) at x = [q (column by column), τ] and its gradient (may be null); the
  /// problem's head, tail, limits and obstacles as for Optimize. Returns NaN when the trajectory
  /// cannot be built. Public for the gradient tests.
  double Objective(const PvaState& head, const PvaState& tail, const DynamicLimits& limits, const PlaneSet& planes,
                   const Eigen::VectorXd& x, Eigen::VectorXd* gradient) const;

  /// x = [q (column by column), τ] of waypoints (3 x (M - 1)) and durations (M > 0): Objective's
  /// variables, from which Optimize starts.
  static Eigen::VectorXd Variables(const Eigen::Matrix3Xd& waypoints, const Eigen::VectorXd& durations);
  /// T(τ) = τ + sqrt(τ² + 1) and its inverse.
  static double DurationOf(double tau) { return tau + std::sqrt(tau * tau + 1.0); }
  static double TauOf(double duration) { return (duration * duration - 1.0) / (2.0 * duration); }

  const TrajectoryOptimizerOptions& options() const { return options_; }

 private:
  TrajectoryOptimizerOptions options_;
};

}  // namespace rotorguard::planning
