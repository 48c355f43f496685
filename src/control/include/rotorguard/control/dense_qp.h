#pragma once
/// Dense convex QP with bounds and general inequalities, solved by the dual active-set method of
/// Goldfarb and Idnani (Math. Programming 27, 1983):
///
///   minimise  1/2 z' H z + g' z   subject to  lb <= z <= ub,  lc <= C z <= uc,
///
/// with H symmetric positive definite. A cold solve starts from the unconstrained minimum and adds
/// violated constraints one at a time, keeping a QR factorisation of the active constraints in the
/// metric of H (J = L^-T Q, R) updated by Givens rotations. A bound is a constraint with a unit
/// normal, so adding one costs O(n (n - q)) and needs no product with C. It suits the condensed
/// NMPC QP (80 variables) where few constraints are active, as qpOASES does for ACADO (paper 000).
///
/// A sequence of similar QPs (the NMPC's calls at 200 Hz) starts each solve from the previous
/// solve's active set (ActiveSetOptions::warm_start): the method may start from any active set whose
/// equality-constrained minimum has non-negative multipliers (Goldfarb and Idnani's S-pair), so the
/// previous set is taken, its minimum for the new g and bounds computed from the factorisation, and
/// constraints whose multipliers turn negative dropped before the usual iterations. With its
/// factorisation kept when no Factorize came in between and the active constraints' rows of C are
/// unchanged, a start is hot (no Givens sweep for the constraints that stay); else the set is
/// rebuilt from J0 (warm: the bounds active when Factorize ran were ordered last and need no
/// rotation, the set's other constraints are added). The iterations themselves are the shared
/// core's (active_set.h); this class is its factorisation.
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "rotorguard/control/active_set.h"

namespace rotorguard::control {

struct DenseQpSummary {
  QpStatus status = QpStatus::kNotSolved;
  QpStart start = QpStart::kCold;
  /// Active constraints the iterations started from: those of the guessed set (the previous
  /// solve's, and for a warm start the bounds Factorize placed) that are independent, finite and
  /// kept a non-negative multiplier (0 for a cold start).
  int start_active_constraints = 0;
  int iterations = 0;          ///< active-set changes after the start
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
  DenseQpSolver(int n, int m, const ActiveSetOptions& options = {});
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
  friend class internal::DualActiveSet;  // calls the factorisation's operations below
  using Side = internal::Side;  // index < n: a bound on z_index; >= n: row index - n of C
  /// The side's bound in the form s' z >= b: b = sign * (lower or upper bound).
  double SignedBound(const DenseQp& qp, const Side& c) const;
  /// order_ and placed_ for the next factorisation: the bounds of the last solve's active set
  /// (a warm start's guess) last.
  void OrderVariables();
  /// No active constraint, and no hot start next (the bookkeeping only; J and R are left).
  void ResetActiveSet();
  /// The empty active set on the factorised Hessian: J = J0, no R.
  void ClearActiveSet();
  /// The bounds Factorize ordered last made active with no rotation (their factorisation is in
  /// J0's structure).
  void PlaceOrderedBounds();
  /// The start of the iterations: the kept active set (hot), the previous one added to the new
  /// factorisation (warm) or none (cold); returns which.
  QpStart StartActiveSet(const DenseQp& qp);
  /// Keeps what a later hot start needs: the active set of a successful solve and its rows of C.
  void KeepForWarmStart(const DenseQp& qp);
  void ComputeD(const DenseQp& qp, const Side& c);  // d_ = J' n_c
  /// Columns j and j + 1 of J_ times the rotation [cs -sn; sn cs], over their non-zero rows.
  void RotateColumns(int j, double cs, double sn);

  // The factorisation's operations for internal::DualActiveSet (active_set.h), on qp_.
  void ScanViolations(internal::ViolationSearch& search);
  internal::Direction MakeDirection(const Side& p, Eigen::Ref<Eigen::VectorXd> r);
  void TakeStep(double t) { z_ += t * step_; }
  double Slack(const Side& c) const;
  bool IterateIsFinite() const { return z_.allFinite(); }
  /// Rotates d_ = J' n_c (ComputeD) so that R gains a column; never refuses.
  bool AddToFactor(const Side& c);
  /// Removes R's column `position`; the Hessenberg rest made triangular by rotations, mirrored on J.
  void DropFromFactor(int position);
  /// With J' N = [R; 0] for the active normals N and J J' = H^-1, the minimum on N' z = b is
  /// z = J1 R^-T b - J2 J2' g, and its multipliers (H z + g = N u) u = R^-1 (R^-T b + J1' g).
  void MinimiseOnFactor(Eigen::Ref<Eigen::VectorXd> u);

  int n_, m_;
  ActiveSetOptions options_;
  Eigen::MatrixXd chol_;   // L with P H P' = L L'
  // J0 = P' L^-T: H^-1 = J0 J0' with the rows in the variables' order. P orders the variables as
  // order_ (position -> variable), with the bounds in placed_ last (OrderVariables).
  Eigen::MatrixXd J0_;
  std::vector<int> order_;
  std::vector<Side> placed_;
  std::vector<char> placed_mark_;  // scratch: per variable, whether it is placed last
  /// order_ is not the identity (some bound is placed last): J0's rows are permuted.
  bool permuted() const { return !placed_.empty(); }
  using IndexList = Eigen::Map<const Eigen::ArrayXi>;
  bool factorized_ = false;
  Eigen::MatrixXd J_;      // L^-T Q
  // Column j of J_ is zero below row height_[j] - 1: L^-T is upper triangular, and a rotation of
  // two columns gives both the larger height. The rotations skip the zero rows.
  std::vector<int> height_;
  Eigen::MatrixXd R_;      // upper triangular, q x q in the top-left corner
  Eigen::VectorXd z_, d_, step_, r_, cz_;
  Eigen::VectorXd y_bound_, y_constraint_;
  // The active set, its multipliers and the last successful solve's set (a warm start's guess).
  internal::DualActiveSet set_;
  const DenseQp* qp_ = nullptr;  // the problem of the running solve
  // Whether J_, R_ still hold the factorisation of set_.previous() for the factorised Hessian (a
  // hot start's condition), with its rows of C (a hot start needs them unchanged) and the hot
  // starts since the set was last built from J0.
  bool hot_startable_ = false;
  Eigen::MatrixXd previous_rows_;
  int hot_starts_in_a_row_ = 0;
  DenseQpSummary summary_;
};

}  // namespace rotorguard::control
