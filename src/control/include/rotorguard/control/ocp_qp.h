#pragma once
/// The QP of one NMPC iteration, in stage form (what a Gauss-Newton SQP step of paper 000's eq. 8
/// produces):
///
///   minimise   sum_{k=0}^{N} 1/2 x_k' Q_k x_k + q_k' x_k  +  sum_{k=0}^{N-1} 1/2 u_k' R_k u_k + r_k' u_k
///   subject to x_0 given,  x_{k+1} = A_k x_k + B_k u_k + c_k          (k = 0 .. N-1)
///              u_lower_k <= u_k <= u_upper_k                            (k = 0 .. N-1)
///              x_lower_k <= x_k[state_bound_index] <= x_upper_k         (k = 1 .. N)
///
/// and its two solvers, which take the same Goldfarb-Idnani dual active-set path to the same point
/// and differ in what they factorise: CondensingQpSolver (here) eliminates the states
/// (x_k = x_bar_k + sum_j S_kj u_j) with O(N^2) recursions and solves the dense QP in the N*nu
/// inputs (DenseQpSolver); RiccatiQpSolver (riccati_qp.h) keeps the stage form and factorises it by
/// a Riccati recursion. docs/control.md, "Two QP solvers", compares them.
#include <Eigen/Core>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "rotorguard/control/dense_qp.h"
#include "rotorguard/core/config_schema.h"

namespace rotorguard::control {

/// The two solvers of an OcpQp.
enum class OcpQpMethod {
  kCondensing,  ///< CondensingQpSolver: the states eliminated, a dense active-set solve
  kRiccati,     ///< RiccatiQpSolver (riccati_qp.h): the stage form, factorised by a Riccati recursion
};
/// As bench qp's --solver writes them.
inline constexpr EnumName<OcpQpMethod> kOcpQpMethodNames[] = {{OcpQpMethod::kCondensing, "condensing"},
                                                              {OcpQpMethod::kRiccati, "riccati"}};
constexpr std::span<const EnumName<OcpQpMethod>> NamesOf(const OcpQpMethod*) { return kOcpQpMethodNames; }

struct OcpQpDims {
  int horizon = 20;  ///< N, >= 1
  int nx = 17;       ///< state size, >= 1
  int nu = 4;        ///< input size, >= 1
  std::vector<int> state_bound_index;  ///< indices of x bounded at stages 1..N, each in [0, nx)
  void Validate() const;
};

/// Problem data, allocated once for its dimensions. Bounds default to +-infinity.
struct OcpQp {
  explicit OcpQp(const OcpQpDims& dims);
  OcpQpDims dims;
  Eigen::VectorXd x0;
  std::vector<Eigen::MatrixXd> A, B;  ///< N each
  std::vector<Eigen::VectorXd> c;     ///< N
  std::vector<Eigen::MatrixXd> Q;     ///< N + 1 (Q_0 only shifts the cost: x_0 is fixed)
  std::vector<Eigen::VectorXd> q;     ///< N + 1
  std::vector<Eigen::MatrixXd> R;     ///< N, positive definite
  std::vector<Eigen::VectorXd> r;     ///< N
  std::vector<Eigen::VectorXd> u_lower, u_upper;  ///< N
  std::vector<Eigen::VectorXd> x_lower, x_upper;  ///< N + 1; entry 0 is unused
};

struct OcpQpSummary {
  QpStatus status = QpStatus::kNotSolved;
  QpStart start = QpStart::kCold;  ///< how the dense solver started (ActiveSetOptions::warm_start)
  int iterations = 0;           ///< active-set changes of the dense solver
  int active_constraints = 0;
  double objective = 0.0;
  double max_violation = 0.0;   ///< largest bound violation of the returned trajectory
  /// Prepare / PrepareVectors: condensing and the dense factorisation, or the Riccati
  /// factorisation and the warm start's Schur complement.
  double prepare_time_s = 0.0;
  /// Feedback: the shift by the measured x0, the active-set iterations and the trajectory.
  double feedback_time_s = 0.0;
  double total_time_s = 0.0;
  bool IsSolutionUsable() const { return status == QpStatus::kSolved; }
  std::string BriefReport() const;
};

/// A solver of OcpQp in the real-time iteration's two phases: the preparation, before the state is
/// measured, and the feedback once it is. CondensingQpSolver and RiccatiQpSolver (riccati_qp.h).
class OcpQpSolver {
 public:
  virtual ~OcpQpSolver() = default;
  /// Solves `qp` (whose dims must equal the solver's): Prepare(qp) then Feedback(qp.x0).
  const OcpQpSummary& Solve(const OcpQp& qp);
  /// Preparation phase: everything that does not depend on qp.x0. `qp` must outlive the following
  /// Feedback calls and stay unchanged.
  virtual const OcpQpSummary& Prepare(const OcpQp& qp) = 0;
  /// Preparation for a `qp` whose matrices (A, B, Q, R) are those of the last Prepare, its vectors
  /// (x0, c, q, r and the bounds) new: what depends on the matrices alone is kept. The caller
  /// vouches for the matrices; without a usable preparation before, it is Prepare.
  virtual const OcpQpSummary& PrepareVectors(const OcpQp& qp) = 0;
  /// Feedback phase: the prepared QP for the initial state x0, and its trajectory.
  virtual const OcpQpSummary& Feedback(const Eigen::VectorXd& x0) = 0;
  const std::vector<Eigen::VectorXd>& u() const { return u_; }  ///< N inputs
  const std::vector<Eigen::VectorXd>& x() const { return x_; }  ///< N + 1 states
  const OcpQpSummary& summary() const { return summary_; }

 protected:
  /// Throws std::invalid_argument naming `solver` when qp's dims differ from `dims`.
  static void RequireSameDims(const OcpQp& qp, const OcpQpDims& dims, const char* solver);
  std::vector<Eigen::VectorXd> x_, u_;
  OcpQpSummary summary_;
};

/// The solver `method` names, for `dims`.
std::unique_ptr<OcpQpSolver> MakeOcpQpSolver(OcpQpMethod method, const OcpQpDims& dims,
                                             const ActiveSetOptions& options = {});

class CondensingQpSolver final : public OcpQpSolver {
 public:
  explicit CondensingQpSolver(const OcpQpDims& dims, const ActiveSetOptions& options = {});
  /// Preparation phase of a real-time iteration: condenses `qp` around its x0 and factorises the
  /// Hessian. Inputs whose bounds coincide (a failed rotor's, u_bar_i = 0) are fixed: they are
  /// eliminated, and the dense QP is solved over the free inputs only (fewer variables, and no
  /// active-set changes for bounds that hold by construction). `qp` must outlive the following
  /// Feedback calls and stay unchanged.
  const OcpQpSummary& Prepare(const OcpQp& qp) override;
  /// Preparation for a `qp` whose matrices (A, B, Q, R) are those of the last Prepare, its vectors
  /// (x0, c, q, r and the bounds) new: the condensed Hessian, the state-bound rows and the
  /// factorisation are kept, and only the condensed gradient and bounds are recomputed, O(N nx^2)
  /// instead of O(N^2 nx^2 nu) plus a factorisation. The mixed-level real-time iteration's cheap
  /// step (NmpcOptions::relinearise_every). The caller vouches for the matrices; a change in which
  /// inputs are fixed by equal bounds, or no usable preparation before, falls back to Prepare.
  const OcpQpSummary& PrepareVectors(const OcpQp& qp) override;
  /// Feedback phase: the QP for the measured initial state x0 (only the gradient and bounds move,
  /// linearly in x0 - prepared x0, by one forward pass through the A_k), solved on the prepared
  /// factorisation, and the trajectory.
  const OcpQpSummary& Feedback(const Eigen::VectorXd& x0) override;
  /// The condensed problem of the last Solve (for inspection and tests).
  const DenseQp& condensed() const { return dense_; }

 private:
  /// Prepare and PrepareVectors: the vectors always, the matrices and factorisation when `whole`
  /// or when the fixed inputs changed.
  const OcpQpSummary& Prepare(const OcpQp& qp, bool whole);
  /// Fill dense_ from qp: its Hessian and state-bound rows, and its gradient and bounds. NX and NU
  /// are the sizes when known at compile time, else Dynamic.
  template <int NX, int NU>
  void CondenseMatrices(const OcpQp& qp);
  template <int NX, int NU>
  void CondenseVectors(const OcpQp& qp);
  /// The prepared gradient and bounds, from which Feedback shifts by the measured x0.
  void KeepPreparedVectors(const OcpQp& qp);
  /// pattern_fixed_: the inputs whose bounds in dense_ coincide.
  void FindFixedInputs();

  /// Finds the inputs fixed by equal bounds in dense_ and, when there are any, builds and
  /// factorises the QP over the others (reduced_); false when its Hessian cannot be factorised.
  bool PrepareReduced();
  /// The reduced QP's bounds and the fixed inputs' shares of its gradient and constraint rows.
  void ReducedVectors();

  OcpQpDims dims_;
  ActiveSetOptions options_;
  // s_rows_[k] = [S_k0 ... S_k,k-1] side by side (nx x k nu), S_kj = dx_k/du_j: one product per
  // stage builds a row of them, and one per input the Hessian's column of blocks.
  std::vector<Eigen::MatrixXd> s_rows_, w_matrix_, y_;
  std::vector<Eigen::VectorXd> x_bar_, w_vector_;
  Eigen::MatrixXd tmp_;
  // The prepared gradient and state-bound rows, and the scratch of their shift by x0 in Feedback.
  Eigen::VectorXd g0_, lc0_, uc0_, prepared_x0_, dx_, dx_next_, cdx_, qx_, ru_;
  const OcpQp* prepared_ = nullptr;
  DenseQp dense_;
  DenseQpSolver dense_solver_;
  // The QP over the free inputs when some are fixed: their indices in dense_, the fixed ones and
  // their values, and what the fixed values add to the gradient (H_fF z_F) and to C z (C_F z_F);
  // pattern_fixed_ is the scratch in which Prepare finds the fixed ones.
  std::vector<int> free_, fixed_, pattern_fixed_;
  // free_ and fixed_ as index lists of Eigen's indexed views (an IndexedView of a std::vector
  // would copy it, an allocation per use).
  using IndexList = Eigen::Map<const Eigen::ArrayXi>;
  IndexList FreeInputs() const { return IndexList(free_.data(), static_cast<Eigen::Index>(free_.size())); }
  IndexList FixedInputs() const { return IndexList(fixed_.data(), static_cast<Eigen::Index>(fixed_.size())); }
  Eigen::VectorXd z_fixed_, g_fixed_, c_fixed_, z_;
  std::unique_ptr<DenseQp> reduced_;
  std::unique_ptr<DenseQpSolver> reduced_solver_;
};

}  // namespace rotorguard::control
