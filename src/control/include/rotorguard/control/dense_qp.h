#pragma once
/// Dense convex QP with bounds and general inequalities, solved by the dual active-set method of
/// Goldfarb and Idnani (Math. Programming 27, 1983):
///
///   minimise  1/2 z' H z + g' z   subject to  lb <= z <= ub,  lc <= C z <= uc,
///
/// with H symmetric positive definite. The method starts from the unconstrained minimum and adds
/// violated constraints one at a time, keeping a QR factorisation of the active constraints in the
/// metric of H (J = L^-T Q, R) updated by Givens rotations. A bound is a constraint with a unit
/// normal, so adding one costs O(n (n - q)) and needs no product with C. It suits the condensed
/// NMPC QP (80 variables) where few constraints are active, as qpOASES does for ACADO (paper 000).
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace rotorguard::control {

struct DenseQpOptions {
  /// Largest violation of a constraint accepted at the solution (absolute, in the constraint's
  /// units); > 0.
  double feasibility_tolerance = 1e-9;
  /// Cap on active-set changes (adds plus drops); >= 1.
  int max_iterations = 1000;
  void Validate() const;
};

enum class QpStatus {
  kNotSolved,          ///< Solve() was not called
  kSolved,             ///< optimal within tolerance
  kMaxIterations,      ///< stopped at max_iterations; the iterate is not optimal
  kInfeasible,         ///< the constraints admit no point
  kNumericalFailure,   ///< H not positive definite, or non-finite data
};
std::string_view ToString(QpStatus status);

struct DenseQpSummary {
  QpStatus status = QpStatus::kNotSolved;
  int iterations = 0;          ///< active-set changes
  int active_constraints = 0;  ///< at the returned point
  double objective = 0.0;      ///< 1/2 z'Hz + g'z
  double max_violation = 0.0;  ///< largest constraint violation at the returned point
  double solve_time_s = 0.0;
  bool IsSolutionUsable() const { return status == QpStatus::kSolved; }
  std::string BriefReport() const;
};

/// Problem data; sizes n (variables) and m (general constraints) fixed at construction.
struct DenseQp {
  DenseQp(int n, int m);
  Eigen::MatrixXd H;   ///< n x n, symmetric positive definite
  Eigen::VectorXd g;   ///< n
  Eigen::VectorXd lb, ub;  ///< n; -inf / +inf for free sides
  Eigen::MatrixXd C;   ///< m x n
  Eigen::VectorXd lc, uc;  ///< m; -inf / +inf for free sides
  int num_variables() const { return static_cast<int>(g.size()); }
  int num_constraints() const { return static_cast<int>(lc.size()); }
};

class DenseQpSolver {
 public:
  /// Allocates all workspace for problems of n variables and m general constraints.
  DenseQpSolver(int n, int m, const DenseQpOptions& options = {});
  /// Solves `qp`; the solution is in z() and the multipliers in bound_multipliers() and
  /// constraint_multipliers() (positive at a lower bound, negative at an upper bound; the KKT
  /// stationarity reads H z + g = y_b + C' y_c). Equals Factorize(qp.H) then SolveFactorized(qp).
  const DenseQpSummary& Solve(const DenseQp& qp);
  /// Factorises a Hessian (Cholesky and J = L^-T, O(n^3)) ahead of the data that changes: the
  /// preparation phase of a real-time iteration. False when H is not finite positive definite.
  bool Factorize(const Eigen::MatrixXd& H);
  /// Solves `qp` whose H was given to the last successful Factorize (qp.H serves only the reported
  /// objective): the feedback phase, O(n^2) per active-set change.
  const DenseQpSummary& SolveFactorized(const DenseQp& qp);
  const Eigen::VectorXd& z() const { return z_; }
  const Eigen::VectorXd& bound_multipliers() const { return y_bound_; }
  const Eigen::VectorXd& constraint_multipliers() const { return y_constraint_; }
  const DenseQpSummary& summary() const { return summary_; }

 private:
  // A one-sided constraint s' z >= b: index < n is a bound on z_index; >= n a row of C. sign is
  // +1 for a lower side, -1 for an upper side.
  struct Side {
    int index;
    double sign;
  };
  double Slack(const DenseQp& qp, const Side& c) const;
  void ComputeD(const DenseQp& qp, const Side& c);  // d_ = J' n_c
  double NormalDotStep(const DenseQp& qp, const Side& c) const;
  void AddToActiveSet(const Side& c);
  void DropFromActiveSet(int position);
  /// Columns j and j + 1 of J_ times the rotation [cs -sn; sn cs], over their non-zero rows.
  void RotateColumns(int j, double cs, double sn);

  int n_, m_;
  DenseQpOptions options_;
  Eigen::MatrixXd chol_;   // L with H = L L'
  Eigen::MatrixXd J0_;     // L^-T of the factorised H
  bool factorized_ = false;
  Eigen::MatrixXd J_;      // L^-T Q
  // Column j of J_ is zero below row height_[j] - 1: L^-T is upper triangular, and a rotation of
  // two columns gives both the larger height. The rotations skip the zero rows.
  std::vector<int> height_;
  Eigen::MatrixXd R_;      // upper triangular, q x q in the top-left corner
  Eigen::VectorXd z_, d_, step_, r_, u_, cz_;
  Eigen::VectorXd y_bound_, y_constraint_;
  std::vector<Side> active_;
  std::vector<char> is_active_;  // per side: 2 * index + (sign < 0)
  int q_ = 0;
  DenseQpSummary summary_;
};

}  // namespace rotorguard::control
