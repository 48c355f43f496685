#pragma once
/// Minimum-jerk piecewise polynomials parameterised by their waypoints and durations: MINCO with
/// s = 3 (paper 000, eqs. 19-21 and 24; Wang et al., T-RO 2022). M pieces of degree 5 join at the
/// intermediate waypoints q_1..q_{M-1} with continuous derivatives up to the fourth; the head and
/// tail states (position, velocity, acceleration) are fixed. For given (q, T) the coefficients
/// c = M(q, T) minimise the jerk energy, and follow from a banded linear system in O(M); the
/// gradient of any cost of (c, T) maps back to (q, T) through one solve with the transposed
/// system, so that an optimiser moves the waypoints and durations directly.
#include <vector>

#include <Eigen/Dense>

#include "rotorguard/core/trajectory.h"
#include "rotorguard/core/types.h"
#include "rotorguard/planning/banded.h"

namespace rotorguard::planning {

/// Position, velocity and acceleration as the columns of a 3 x 3 matrix.
using PvaState = Eigen::Matrix3d;

class MinimumJerkTrajectory final : public ReferenceTrajectory {
 public:
  static constexpr int kCoefficients = 6;  // degree 5 = 2s - 1
  /// k! / (k - order)!: the factor of t^(k - order) in the order-th derivative of t^k.
  static constexpr double kDerivativeFactor[6][kCoefficients] = {{1, 1, 1, 1, 1, 1},    {0, 1, 2, 3, 4, 5},
                                                                 {0, 0, 2, 6, 12, 20},  {0, 0, 0, 6, 24, 60},
                                                                 {0, 0, 0, 0, 24, 120}, {0, 0, 0, 0, 0, 120}};

  MinimumJerkTrajectory() = default;

  /// Builds the minimum-jerk coefficients for `waypoints` (3 x (M - 1), the junctions) and
  /// `durations` (M, each > 0), in this trajectory's storage (no allocation when it held M pieces
  /// before). Returns false (leaving the trajectory empty) when a duration is not positive and
  /// finite, an input is not finite or the sizes do not match.
  bool Build(const PvaState& head, const PvaState& tail, const Eigen::Matrix3Xd& waypoints,
             const Eigen::VectorXd& durations);

  /// A chain of straight pieces, each flown from rest to rest: piece i runs from points.col(i) to
  /// points.col(i + 1) in durations(i) along the quintic 10s^3 - 15s^4 + 6s^5 of s = t / T_i (the
  /// minimum-jerk profile between rest states), so that the trajectory never leaves the polyline.
  /// Velocity and acceleration are continuous (zero at every corner), the jerk is not, unlike
  /// Build's. For a path that must be flown exactly (the planner's fallback); PropagateGradient
  /// does not apply to it. Returns false (leaving the trajectory empty) on fewer than two points,
  /// a duration that is not positive and finite, a point that is not finite or mismatched sizes.
  bool BuildRestToRest(const Eigen::Ref<const Eigen::Matrix3Xd>& points, const Eigen::VectorXd& durations);

  int pieces() const { return static_cast<int>(durations_.size()); }
  bool empty() const { return durations_.size() == 0; }
  const Eigen::VectorXd& durations() const { return durations_; }
  /// Coefficients, 6M x 3: row 6i + k multiplies t^k on piece i (t from the piece's start).
  const Eigen::MatrixX3d& coefficients() const { return coefficients_; }

  /// J_s = sum over pieces of the integral of |jerk|^2 (eq. 24), in closed form.
  double Energy() const;
  /// The partial derivatives of J_s: with respect to the coefficients (6M x 3) and, with the
  /// coefficients held, to the durations (|jerk(T_i)|^2).
  void EnergyPartials(Eigen::MatrixX3d* d_coefficients, Eigen::VectorXd* d_durations) const;

  /// Maps the partial derivatives of a cost J(c, T) to its total derivatives with respect to the
  /// waypoints (3 x (M - 1)) and durations (M) through the adjoint of the banded system, solved in
  /// place: `d_coefficients` holds the adjoint afterwards (no allocation for the optimisers).
  void PropagateGradient(Eigen::MatrixX3d* d_coefficients, const Eigen::VectorXd& d_durations_partial,
                         Eigen::Matrix3Xd* d_waypoints, Eigen::VectorXd* d_durations) const;

  /// The row d^order/dt^order [1, t, ..., t^5]: a piece's derivative is Basis(t, order) times its
  /// 6 x 3 coefficients.
  static Eigen::Matrix<double, 1, kCoefficients> Basis(double t, int order);
  /// The rows of Basis(t, 0) .. Basis(t, 4) at once (the optimiser's samples need all five).
  static Eigen::Matrix<double, 5, kCoefficients> BasisRows(double t);

  /// Derivative `order` (0 position .. 5) of piece i at local time t in [0, T_i].
  Vector3 PieceDerivative(int piece, double t, int order) const;

  /// The largest |derivative `order`| over the trajectory, sampled at samples_per_piece + 1 evenly
  /// spaced instants of every piece (ends included).
  double MaxNorm(int order, int samples_per_piece) const;

  /// ReferenceTrajectory: position through jerk at time t since `start_time()`; before it the
  /// first point, after the end the final state with zero velocity and higher derivatives (the
  /// tail is a rest state when the trajectory stops at a goal).
  ReferencePoint Evaluate(double t) const override;
  double duration() const override { return start_time_ + total_duration_; }
  void set_start_time(double t0) { start_time_ = t0; }
  double start_time() const { return start_time_; }
  double total_duration() const { return total_duration_; }
  void set_yaw(double yaw) { yaw_ = yaw; }

 private:
  void Clear();  // empty: no pieces

  Eigen::VectorXd durations_;
  Eigen::MatrixX3d coefficients_;
  BandedMatrix system_{0, 4, 3};  // factored
  double total_duration_ = 0.0, start_time_ = 0.0, yaw_ = 0.0;
};

}  // namespace rotorguard::planning
