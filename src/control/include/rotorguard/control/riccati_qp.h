#pragma once
/// The OCP QP of ocp_qp.h solved in its stage form, without condensing: a Riccati factorisation
/// of the stage-wise KKT system, O(N (nx^3 + nx^2 nu)), and the dual active-set method of Goldfarb
/// and Idnani in its range-space form on top of it.
///
/// Every constraint of the QP is a bound on one component of the trajectory (an input u_k[i], or
/// a bounded state x_k[j]), so the method needs the QP's inverse Hessian only through the
/// responses v_a = H^-1 e_a of the dynamics-constrained problem to a unit linear term at one
/// bounded component a: one backward and one forward pass of the factorised Riccati recursion,
/// O(N nx^2) each. The active set is held as the Cholesky factor of its Schur complement
/// M = N' H^-1 N (a principal submatrix of the responses, q x q), updated by one row when a
/// constraint is added and by a rank-one update when one is dropped; the iterate and every step
/// live in the space of the bounded components only (N nu + N nbx numbers, 140 for the NMPC).
///
/// Its cost is a factorisation of O(N nx^3) and one response per constraint the iterations touch,
/// where condensing (CondensingQpSolver) pays O(N^2 nx^2 nu) and a Cholesky factorisation and
/// inversion of the N nu-square Hessian before its first iteration: the Riccati form wins where
/// few bounds are active (docs/control.md, "Two QP solvers"; the measurements that chose it are in
/// CHANGELOG.md).
#include <Eigen/Core>
#include <vector>

#include "rotorguard/control/active_set.h"
#include "rotorguard/control/ocp_qp.h"

namespace rotorguard::control {

class RiccatiQpSolver final : public OcpQpSolver {
 public:
  /// Workspace for problems of `dims`; options.feasibility_tolerance and max_iterations act as for
  /// DenseQpSolver, and warm_start starts each solve from the previous solve's active set.
  explicit RiccatiQpSolver(const OcpQpDims& dims, const ActiveSetOptions& options = {});
  /// The factorisation, the cost-to-go's linear terms and, for a warm start, the previous active
  /// set's responses and Schur complement: everything but the forward pass from x0.
  const OcpQpSummary& Prepare(const OcpQp& qp) override;
  /// Only the cost-to-go's linear terms and the bounds; the factorisation, the responses and the
  /// active set with its Schur complement are kept (a hot start).
  const OcpQpSummary& PrepareVectors(const OcpQp& qp) override;
  /// The forward pass from x0 (the unconstrained minimum), the minimum on the start's active set,
  /// the active-set iterations and the trajectory.
  const OcpQpSummary& Feedback(const Eigen::VectorXd& x0) override;
  /// Multipliers of the bounds at the solution, positive at a lower bound and negative at an
  /// upper one (stationarity: the gradient of the Lagrangian with the dynamics' multipliers
  /// equals their sum): input_multipliers()[k][i] for u_k[i], state_multipliers()[k][b] for
  /// x_k[state_bound_index[b]], k = 1..N (entry 0 is zero).
  const std::vector<Eigen::VectorXd>& input_multipliers() const { return y_u_; }
  const std::vector<Eigen::VectorXd>& state_multipliers() const { return y_x_; }

 private:
  friend class internal::DualActiveSet;  // calls the factorisation's operations below
  /// One side of a bound on bounded component `index`: s z[index] >= s * (lower or upper bound).
  using Side = internal::Side;
  /// Backward Riccati recursion for the matrices: P_k, the stage's P_{k+1} B_k, the Cholesky
  /// factor of R_k + B_k' P_{k+1} B_k and the feedback gains K_k. False when a stage's reduced
  /// input Hessian is not positive definite or the data are not finite.
  template <int NX, int NU>
  bool Factorize(const OcpQp& qp);
  /// h <- (R_k + B_k' P_{k+1} B_k)^-1 h by the stage's Cholesky factor.
  template <int NX, int NU>
  void SolveStageHessian(int k, Eigen::Matrix<double, NU, 1>* h) const;
  /// The backward pass for the linear terms: the feedforwards kff_.
  template <int NX, int NU>
  void BackwardVectors(const OcpQp& qp);
  /// The factorised recursion forward, writing the trajectory's bounded components to `out`: from
  /// *x0 with the gaps c_k (the unconstrained minimum), or from zero without them (x0 null: a
  /// response), with the feedforwards of stages 0..last.
  template <int NX, int NU>
  void ForwardPass(const Eigen::VectorXd* x0, const std::vector<Eigen::VectorXd>& feedforward, int last,
                   Eigen::Ref<Eigen::VectorXd> out) const;
  /// Prepare and PrepareVectors: the factorisation when `whole`.
  const OcpQpSummary& Prepare(const OcpQp& qp, bool whole);
  /// No active side.
  void ClearActiveSet();
  /// Column `index` of responses_: H^-1 e_index in the bounded components.
  template <int NX, int NU>
  void ComputeResponse(int index);
  /// The response of `index`, computed on first use after a factorisation.
  Eigen::Ref<const Eigen::VectorXd> Response(int index);

  /// Whether `index` is an input fixed by equal bounds (out of the recursion, never active).
  bool IsFixed(int index) const { return index < dims_.horizon * dims_.nu && fixed_[static_cast<std::size_t>(index)]; }
  double SignedBound(const Side& c) const { return c.sign * (c.sign > 0 ? lower_[c.index] : upper_[c.index]); }
  /// c's row of the Schur complement's Cholesky factor, l = L^-1 N_A' H^-1 n_c, left in b_, and the
  /// square of the new diagonal, d² = n_c' H^-1 n_c - |l|², left in d2_.
  void SchurComplementRow(const Side& c);
  /// Whether c's normal, with the d² of SchurComplementRow(c), is independent of the active ones
  /// (kDependence).
  bool IsIndependent(const Side& c) const;

  // The factorisation's operations for internal::DualActiveSet (active_set.h).
  void ScanViolations(internal::ViolationSearch& search) const { search.Scan(w_, lower_, upper_, 0); }
  internal::Direction MakeDirection(const Side& p, Eigen::Ref<Eigen::VectorXd> r);
  void TakeStep(double t) { w_ += t * step_; }
  double Slack(const Side& c) const { return c.sign * w_[c.index] - SignedBound(c); }
  bool IterateIsFinite() const { return w_.allFinite(); }
  /// Appends c with the row SchurComplementRow(c) left in b_. False (nothing added) when c is
  /// dependent on the active sides or the factor is full.
  bool AddToFactor(const Side& c);
  /// M's factor without row and column `position`: a rank-one update of the trailing block.
  void DropFromFactor(int position);
  /// On the active sides as equalities the minimum is w = w0 + V λ with V = H^-1 N and λ the
  /// multipliers, M λ = b_A - N_A' w0.
  void MinimiseOnFactor(Eigen::Ref<Eigen::VectorXd> lambda);
  /// The iterations from the start's S-pair, then again from the minimum on the final set computed
  /// afresh; the status they end with.
  QpStatus Iterate();
  /// u_, x_, the multipliers and the summary's objective and violation from w_ and x0.
  template <int NX, int NU>
  void ExpandTrajectory(const Eigen::VectorXd& x0);
  /// The summary of a solve that ends without a trajectory: zero inputs and states, never a NaN.
  const OcpQpSummary& Fail(QpStatus status);

  OcpQpDims dims_;
  ActiveSetOptions options_;
  int nbx_ = 0, nc_ = 0;  // bounded states per stage; bounded components N nu + N nbx
  bool nmpc_sizes_ = false;
  const OcpQp* qp_ = nullptr;  // the prepared problem
  bool prepared_ = false;      // a usable preparation of *qp_
  bool crossed_ = false;       // some lower bound above its upper one: infeasible
  QpStart start_ = QpStart::kCold;
  // The factorisation: P_k (k = 1..N), P_{k+1} B_k, the lower Cholesky factor of
  // R_k + B_k' P_{k+1} B_k, and K_k with u_k = K_k x_k + k_k.
  std::vector<Eigen::MatrixXd> P_, PB_, Lu_, K_;
  // B_k with the columns of fixed inputs zeroed; per input k * nu + i, whether equal bounds fix it
  // (and the scratch in which a preparation finds them).
  std::vector<Eigen::MatrixXd> Bt_;
  std::vector<char> fixed_, pattern_;
  Eigen::VectorXd costate_;
  // The unconstrained solution's feedforwards k_k, and a response's.
  std::vector<Eigen::VectorXd> kff_, kr_, y_u_, y_x_;
  Eigen::MatrixXd tmp_xx_;
  // Bounded components: the lower and upper bounds, the unconstrained minimum w0, the iterate w,
  // a step and the responses (column a: H^-1 e_a, valid where have_response_).
  Eigen::VectorXd lower_, upper_, w0_, w_, step_;
  Eigen::MatrixXd responses_;
  std::vector<char> have_response_;
  // The active set with its multipliers and the last solve's set, and the lower Cholesky factor L
  // of M = N' H^-1 N; b_ and d2_ the last SchurComplementRow.
  internal::DualActiveSet set_;
  Eigen::MatrixXd L_;
  Eigen::VectorXd b_, update_;
  double d2_ = 0.0;
};

}  // namespace rotorguard::control
