#pragma once
/// Paper 002, Sec. III-2: the dynamical trajectory of an assembly through the A* sequence of
/// eq. (10), by eq. (11):
///
///   min over {c, T}:  λ_m J_m + λ_t J_t + λ_o G_o + λ_d G_d,
///   G_d = λ_v G_v + λ_a G_a + λ_j G_j + λ_Φ G_Φ                           (eq. 12a)
///
/// The centre of mass's position and the yaw are minimum-jerk polynomials on the same pieces
/// (MINCO with s = 3, yaw as the fourth flat output; roll and pitch follow from the acceleration).
/// J_m is their jerk energy, J_t the total time. G_o is the footprint's clearance, the
/// implicit-shape idea of SVSDF (the paper's ref. [6]) at sample points: the centre of every unit,
/// rotated with the yaw, kept clear of its nearest obstacle's plane by the unit's radius plus a
/// margin. G_v, G_a, G_j are the kinematic limits; this project adds the assembly's own dynamics to
/// G_d (the yaw acceleration its rotors' reaction torques can give, the acceleration its thrust can
/// give after a fault, AssemblyCapacity). G_Φ of eq. (12b) is the yaw's distance from the optimal
/// attitude of eqs. (7)-(8) for the direction of flight at each sample.
///
/// The baseline of Table II (SVSDF) is the same optimiser with kinematic limits only and λ_Φ = 0.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rotorguard/core/trajectory.h"
#include "rotorguard/modular/assembly.h"
#include "rotorguard/modular/assembly_astar.h"
#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/planning/minco.h"
#include "rotorguard/planning/trajectory_optimizer.h"

namespace rotorguard::modular {

/// The assembly's reference: position and yaw, minimum-jerk on the same pieces.
class AssemblyTrajectory final : public ReferenceTrajectory {
 public:
  AssemblyTrajectory() = default;
  /// `yaw` carries the yaw [rad] in its x coordinate (y and z zero); both have the same durations.
  AssemblyTrajectory(planning::MinimumJerkTrajectory position, planning::MinimumJerkTrajectory yaw);

  /// Position through jerk and the yaw with its rate at time t since the start; before the start
  /// the first point, after the end the final one at rest.
  ReferencePoint Evaluate(double t) const override;
  double duration() const override { return position_.duration(); }
  /// The pose (centre of mass and yaw) at time t.
  AssemblyPose PoseAt(double t) const;
  const planning::MinimumJerkTrajectory& position() const { return position_; }
  const planning::MinimumJerkTrajectory& yaw() const { return yaw_; }
  bool empty() const { return position_.empty(); }

 private:
  planning::MinimumJerkTrajectory position_, yaw_;
};

/// What the assembly's remaining rotors can do, from the allocator's exact QP (its attainable
/// wrenches): the dynamics the kinematic baseline does not know.
struct AssemblyCapacity {
  bool hover_attainable = false;
  double max_thrust_n = 0.0;         ///< largest collective thrust with zero torque [N]
  double max_yaw_torque_n_m = 0.0;   ///< largest |yaw torque| of either sign at the hover thrust [N m]
  /// sqrt((max_thrust / m)^2 - g^2): the largest horizontal acceleration in level flight (the
  /// planner bounds the thrust itself, AssemblyLimits::thrust_acceleration_max).
  double max_acceleration_m_s2 = 0.0;
  double max_yaw_acceleration_rad_s2 = 0.0;  ///< max_yaw_torque / I_zz
  /// The largest |roll| and |pitch| torque of either sign at the hover thrust over I_xx and I_yy
  /// [rad/s²]: how fast the remaining rotors can tilt the assembly (its snap, AssemblyLimits).
  double max_roll_acceleration_rad_s2 = 0.0;
  double max_pitch_acceleration_rad_s2 = 0.0;
};

/// Bisects the allocator's attainability (to 1e-4 of the range) for the rotors' effectiveness `eta`.
AssemblyCapacity CapacityOf(const Assembly& assembly, const RotorVector& eta);

/// The limits of G_d. The dynamic ones at 0 are off (the kinematic baseline).
struct AssemblyLimits {
  planning::DynamicLimits kinematic;
  double yaw_rate_max = 0.0;          ///< [rad/s], >= 0
  double yaw_acceleration_max = 0.0;  ///< [rad/s²], >= 0
  /// The thrust the assembly may ask for, per kilogram: |a + g e_z| <= this [m/s²]; 0 (off) or > g.
  double thrust_acceleration_max = 0.0;
  /// The tilt's angular acceleration the plan may ask for about the body's x and y axes
  /// [rad/s²], both 0 (off) or both > 0. Near hover the thrust's direction is a + g e_z, so the
  /// tilt's angular acceleration is the horizontal snap over g: the snap in the body's frame
  /// (rotated by the yaw) is kept in the ellipse (s_x / (g α_y))² + (s_y / (g α_x))² <= 1. With
  /// these on, the plan's first and last jerk are bounded too (AssemblyTrajectoryOptions::
  /// end_tilt_overshoot_rad).
  double roll_acceleration_max = 0.0;
  double pitch_acceleration_max = 0.0;
  void Validate() const;
};

/// Whether the assembly has thrust, roll, pitch and yaw torque to spare at hover (what
/// DynamicsAwareLimits needs).
bool HasMargin(const AssemblyCapacity& capacity);

/// Ours: the kinematic limits with the assembly's dynamics, each at `safety_factor` (in (0, 1]) of
/// its margin: the thrust per kilogram g + γ (F_max / m - g), the yaw acceleration γ τ_z / I_zz, the
/// roll and pitch accelerations γ τ_x / I_xx and γ τ_y / I_yy, and `yaw_rate_max`. Throws std::invalid_argument when !HasMargin(capacity).
AssemblyLimits DynamicsAwareLimits(const planning::DynamicLimits& kinematic, const AssemblyCapacity& capacity,
                                   double mass_kg, double yaw_rate_max, double safety_factor);

struct AssemblyTrajectoryOptions {
  double weight_time = 10.0;        ///< λ_t, >= 0
  double weight_smoothness = 1.0;   ///< λ_m, >= 0 (the yaw's jerk counts as that of its farthest unit)
  double weight_obstacle = 1e4;     ///< λ_o, >= 0
  double weight_dynamics = 1e4;     ///< λ_d (λ_v = λ_a = λ_j = 1, and the yaw limits), >= 0
  /// λ_d λ_Φ of eq. (12a) [per (m/s)² rad²]: G_Φ sums |v_xy|² (ψ* - ψ)² over the samples, the
  /// squared and speed-weighted form of eq. (12b) (smooth, and silent at rest where the direction
  /// of flight, hence ψ*, is undefined). >= 0; 0 is the baseline.
  double weight_attitude = 50.0;
  double clearance_m = 0.15;  ///< distance kept beyond a unit's radius from an occupied voxel's centre [m], >= 0
  /// Obstacles farther than this from a unit's centre are not penalised [m], > clearance + unit radius.
  double obstacle_range_m = 1.0;
  int samples_per_piece = 32;    ///< penalty samples per piece, in [2, 1000]
  int plane_rounds = 3;          ///< solves, each with the planes of the last one's trajectory, >= 1
  /// When the dense check finds a unit's sphere reaching an occupied voxel: at most this many
  /// further solves from that trajectory, each keeping the planes so far, adding those of the
  /// trajectory that collided and weighting G_o `collision_weight_growth` times more, >= 0.
  int collision_rounds = 3;
  double collision_weight_growth = 4.0;  ///< >= 1
  int max_iterations = 300;      ///< L-BFGS iterations per solve, >= 1
  double relative_cost_tolerance = 1e-5;  ///< in (0, 0.1]
  /// The initial guess keeps one A* pose per this distance (and every yaw turn) [m], > 0.
  double waypoint_spacing_m = 0.6;
  /// The dense check after the solve: samples per piece, and at most `max_slowdowns` rounds of
  /// stretching time by the worst excess times `slowdown_factor` (as planning::TrajectoryOptimizer).
  int check_samples_per_piece = 64;
  int max_slowdowns = 10;
  double slowdown_factor = 1.02;
  /// Optimal relative yaws of eq. (7) are searched among this many yaw steps per turn, >= 4.
  int attitude_bins = 72;
  /// With the tilt limits on (AssemblyLimits): the tilt rate at the plan's start and end (its
  /// jerk over g), which the held reference steps to or from zero there, is kept so small that
  /// stopping it at the limit's angular acceleration overshoots the tilt by at most this [rad], > 0.
  double end_tilt_overshoot_rad = 0.05;
  /// Throws ValidationError naming the field.
  void Validate() const;
};

struct AssemblyTrajectorySummary {
  enum class Status { kSuccess, kInvalidInput, kSolverFailure, kInfeasible, kCollides };
  Status status = Status::kInvalidInput;
  std::string message;
  int iterations = 0, evaluations = 0, slowdowns = 0;
  int collision_rounds = 0;  ///< further solves after a dense check found a collision
  double solve_ms = 0.0;
  double duration_s = 0.0;
  /// Eq. (12b) on the dense check: the mean over samples in flight (|v_xy| > 0.1 m/s) of
  /// |ψ* - ψ| [rad], ψ* the optimal yaw nearest to ψ.
  double attitude_deviation_rad = 0.0;
  /// The smallest distance from a unit's centre to an occupied voxel's centre minus the unit's
  /// radius on the dense check [m] (capped at obstacle_range_m). Below the voxel's half-diagonal
  /// the sphere may reach the occupied cube: kCollides.
  double min_clearance_m = 0.0;
  /// 1 - the time-stretch factor the dense check would still call for (v / v_max, sqrt(a / a_max),
  /// cbrt(j / j_max) and the yaw's, thrust's and tilt's likewise, the largest): >= 0 when every
  /// limit holds.
  double limit_margin = 0.0;
  bool ok() const { return status == Status::kSuccess; }
};
const char* ToString(AssemblyTrajectorySummary::Status status);

/// A plane that one footprint sample keeps clear of: unit `unit` at sample `sample` of its piece.
struct FootprintPlane {
  int sample = 0;
  int unit = 0;
  planning::ObstaclePlane plane;
};
using FootprintPlaneSet = std::vector<std::vector<FootprintPlane>>;  ///< per piece, sorted by sample

class AssemblyTrajectoryOptimizer {
 public:
  /// Throws ValidationError on invalid options, std::invalid_argument when eq. (7) has no
  /// minimiser (a non-finite objective).
  AssemblyTrajectoryOptimizer(const Assembly& assembly, const RotorVector& eta,
                              const AssemblyTrajectoryOptions& options);

  /// From `path` (the A* sequence, start at rest to goal at rest) on `map` under `limits`. On
  /// success and on kCollides (on the dense check a unit's sphere may reach an occupied voxel:
  /// min_clearance_m below the voxel's half-diagonal; reported, not hidden) `out` holds the
  /// trajectory.
  AssemblyTrajectorySummary Optimize(const perception::VoxelMap& map, const AssemblyPath& path,
                                     const AssemblyLimits& limits, AssemblyTrajectory* out) const;

  /// The problem in the optimiser's variables x = [position waypoints (3 x (M-1), by column), yaw
  /// waypoints (M-1), τ (M), T = τ + sqrt(τ² + 1)] between the rest states at `start` and `goal`.
  struct Problem {
    AssemblyPose start, goal;
    AssemblyLimits limits;
    FootprintPlaneSet planes;  ///< empty (free space) or one list per piece
    double obstacle_weight_scale = 1.0;  ///< G_o's weight is weight_obstacle times this
  };
  /// Eq. (11) at x and its gradient (may be null); NaN when no trajectory can be built. Public for
  /// the gradient tests.
  double Objective(const Problem& problem, const Eigen::VectorXd& x, Eigen::VectorXd* gradient) const;
  /// The trajectory of x.
  bool Build(const Problem& problem, const Eigen::VectorXd& x, AssemblyTrajectory* out) const;
  /// The planes of `traj`'s penalty samples: each unit's nearest obstacle within obstacle_range_m.
  FootprintPlaneSet BuildPlanes(const perception::VoxelMap& map, const AssemblyTrajectory& traj) const;
  /// The yaws relative to the direction of flight that minimise eq. (7) (sorted, in [0, 2π)).
  const std::vector<double>& optimal_relative_yaws() const { return optimal_relative_yaws_; }
  /// ψ* - ψ for the optimal relative yaw nearest to ψ - χ, wrapped to (-π, π] (χ the heading).
  double AttitudeError(double yaw, double heading) const;

 private:
  /// Stretches time while a limit is exceeded on the dense check (summary's slowdowns and
  /// limit_margin): nothing when every limit holds, else the failure.
  std::optional<std::pair<AssemblyTrajectorySummary::Status, std::string>> StretchToLimits(
      const Problem& problem, Eigen::VectorXd* x, AssemblyTrajectory* traj, AssemblyTrajectorySummary* summary) const;
  /// The footprint's clearance and eq. (12b) on the dense check, with the duration, into `summary`.
  void DenseCheck(const perception::VoxelMap& map, const AssemblyTrajectory& traj,
                  AssemblyTrajectorySummary* summary) const;

  Assembly assembly_;
  AssemblyTrajectoryOptions options_;
  std::vector<double> optimal_relative_yaws_;
  double yaw_length_m_ = 0.0;  ///< the farthest unit centre's distance from the centre of mass
};

}  // namespace rotorguard::modular
