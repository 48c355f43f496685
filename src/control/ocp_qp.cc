
#include "rotorguard/control/ocp_qp.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "rotorguard/control/riccati_qp.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/stopwatch.h"
#include "stage_maps.h"

namespace rotorguard::control {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
using internal::StageMaps;
}  // namespace

void OcpQpDims::Validate() const {
  if (horizon < 1 || horizon > 1000) ThrowValidation("OcpQpDims", "horizon", horizon, "an integer in [1, 1000]");
  if (nx < 1) ThrowValidation("OcpQpDims", "nx", nx, "an integer >= 1");
  if (nu < 1) ThrowValidation("OcpQpDims", "nu", nu, "an integer >= 1");
  for (int i : state_bound_index) {
    if (i < 0 || i >= nx) ThrowValidation("OcpQpDims", "state_bound_index", i, fmt::format("an index in [0, {})", nx));
  }
}

OcpQp::OcpQp(const OcpQpDims& d) : dims(d) {
  dims.Validate();
  const int N = d.horizon, nbx = static_cast<int>(d.state_bound_index.size());
  x0 = Eigen::VectorXd::Zero(d.nx);
  A.assign(N, Eigen::MatrixXd::Identity(d.nx, d.nx));
  B.assign(N, Eigen::MatrixXd::Zero(d.nx, d.nu));
  c.assign(N, Eigen::VectorXd::Zero(d.nx));
  Q.assign(N + 1, Eigen::MatrixXd::Zero(d.nx, d.nx));
  q.assign(N + 1, Eigen::VectorXd::Zero(d.nx));
  R.assign(N, Eigen::MatrixXd::Identity(d.nu, d.nu));
  r.assign(N, Eigen::VectorXd::Zero(d.nu));
  u_lower.assign(N, Eigen::VectorXd::Constant(d.nu, -kInf));
  u_upper.assign(N, Eigen::VectorXd::Constant(d.nu, kInf));
  x_lower.assign(N + 1, Eigen::VectorXd::Constant(nbx, -kInf));
  x_upper.assign(N + 1, Eigen::VectorXd::Constant(nbx, kInf));
}

std::string OcpQpSummary::BriefReport() const {
  return fmt::format(
      "OCP QP {}: {} start, {} iterations, {} active, objective {:.6g}, prepare {:.1f} us, feedback "
      "{:.1f} us",
      ToString(status), ToString(start), iterations, active_constraints, objective, prepare_time_s * 1e6,
      feedback_time_s * 1e6);
}

CondensingQpSolver::CondensingQpSolver(const OcpQpDims& dims, const ActiveSetOptions& options)
    : dims_(dims),
      options_(options),
      dense_(dims.horizon * dims.nu, dims.horizon * static_cast<int>(dims.state_bound_index.size())),
      dense_solver_(dims.horizon * dims.nu, dims.horizon * static_cast<int>(dims.state_bound_index.size()),
                    options) {
  dims_.Validate();
  const int N = dims.horizon, nx = dims.nx, nu = dims.nu;
  s_rows_.resize(N + 1);
  for (int k = 0; k <= N; ++k) s_rows_[k] = Eigen::MatrixXd::Zero(nx, k * nu);
  w_matrix_.assign(N + 1, Eigen::MatrixXd::Zero(nx, nx));
  y_.assign(N, Eigen::MatrixXd::Zero(nx, nu));
  x_bar_.assign(N + 1, Eigen::VectorXd::Zero(nx));
  w_vector_.assign(N + 1, Eigen::VectorXd::Zero(nx));
  x_.assign(N + 1, Eigen::VectorXd::Zero(nx));
  u_.assign(N, Eigen::VectorXd::Zero(nu));
  tmp_.resize(nx, nx);
  const int n = N * nu, m = N * static_cast<int>(dims.state_bound_index.size());
  dx_.resize(nx);
  dx_next_.resize(nx);
  cdx_.resize(m);
  z_.resize(n);
  pattern_fixed_.reserve(static_cast<std::size_t>(n));
  fixed_.reserve(static_cast<std::size_t>(n));
  free_.reserve(static_cast<std::size_t>(n));
  qx_.resize(nx);
  ru_.resize(nu);
}

template <int NX, int NU>
void CondensingQpSolver::CondenseMatrices(const OcpQp& qp) {
  using MatXX = Eigen::Matrix<double, NX, NX>;
  using MatXU = Eigen::Matrix<double, NX, NU>;
  const int N = dims_.horizon, nx = dims_.nx, nu = dims_.nu;
  const std::vector<int>& idx = dims_.state_bound_index;
  const int nbx = static_cast<int>(idx.size());
  const StageMaps<NX, NU> stage{qp, nx, nu};
  using MatXN = Eigen::Matrix<double, NX, Eigen::Dynamic>;
  const auto Srow = [&](int k) { return Eigen::Map<MatXN>(s_rows_[k].data(), nx, k * nu); };
  const auto W = [&](int k) { return Eigen::Map<MatXX>(w_matrix_[k].data(), nx, nx); };
  const auto Y = [&](int k) { return Eigen::Map<MatXU>(y_[k].data(), nx, nu); };
  Eigen::Map<MatXX> tmp(tmp_.data(), nx, nx);

  // Sensitivities S_kj = A_{k-1} ... A_{j+1} B_j, a stage's row [S_k0 ... S_k,k-2] = A_{k-1}
  // [S_{k-1,0} ... S_{k-1,k-2}] as one product (faster than k-1 products of 17 x 17 by 17 x 4:
  // CHANGELOG.md, "Condensing a stage at a time").
  for (int k = 1; k <= N; ++k) {
    if (k > 1) Srow(k).leftCols((k - 1) * nu).noalias() = stage.A(k - 1) * Srow(k - 1);
    Srow(k).rightCols(nu) = stage.B(k - 1);
  }
  // Backward: W_m = Q_m + A_m' W_{m+1} A_m.
  W(N) = stage.Q(N);
  for (int m = N - 1; m >= 1; --m) {
    tmp.noalias() = W(m + 1) * stage.A(m);
    W(m) = stage.Q(m);
    // Eigen's product evaluator, not lazyProduct: with AVX2 it runs A' (W A) in 12 µs per
    // condensing where lazyProduct's dot products took 21 (CHANGELOG.md).
    W(m).noalias() += stage.A(m).transpose() * tmp;
  }
  // Hessian blocks H_ij = S_{j+1,i}' W_{j+1} B_j (i <= j) plus R_j: input j's column of blocks is
  // one product, [S_{j+1,0} ... S_{j+1,j}]' Y_j, mirrored into its row.
  for (int j = 0; j < N; ++j) {
    Y(j).noalias() = W(j + 1) * stage.B(j);
    auto column = dense_.H.block(0, j * nu, (j + 1) * nu, nu);
    column.noalias() = Srow(j + 1).transpose() * Y(j);
    dense_.H.block(j * nu, 0, nu, j * nu) = column.topRows(j * nu).transpose();
    dense_.H.block(j * nu, j * nu, nu, nu) += stage.R(j);
  }
  // State bounds become rows of C: x_k[idx] = x_bar_k[idx] + sum_{j<k} S_kj[idx, :] u_j.
  if (nbx > 0) {
    dense_.C.setZero();
    for (int k = 1; k <= N; ++k) {
      for (int b = 0; b < nbx; ++b) dense_.C.block((k - 1) * nbx + b, 0, 1, k * nu) = Srow(k).row(idx[b]);
    }
  }
}

template <int NX, int NU>
void CondensingQpSolver::CondenseVectors(const OcpQp& qp) {
  using VecX = Eigen::Matrix<double, NX, 1>;
  using VecU = Eigen::Matrix<double, NU, 1>;
  const int N = dims_.horizon, nx = dims_.nx, nu = dims_.nu;
  const StageMaps<NX, NU> stage{qp, nx, nu};
  const auto xb = [&](int k) { return Eigen::Map<VecX>(x_bar_[k].data(), nx); };
  const auto wv = [&](int k) { return Eigen::Map<VecX>(w_vector_[k].data(), nx); };

  // Free response x_bar (u = 0), then backward w_m = Q_m x_bar_m + q_m + A_m' w_{m+1} and the
  // gradient g_j = r_j + B_j' w_{j+1}.
  xb(0) = qp.x0;
  for (int k = 0; k < N; ++k) xb(k + 1).noalias() = stage.A(k) * xb(k) + Eigen::Map<const VecX>(qp.c[k].data(), nx);
  wv(N).noalias() = stage.Q(N) * xb(N) + Eigen::Map<const VecX>(qp.q[N].data(), nx);
  for (int m = N - 1; m >= 1; --m) {
    wv(m) = Eigen::Map<const VecX>(qp.q[m].data(), nx);
    wv(m).noalias() += stage.Q(m) * xb(m) + stage.A(m).transpose() * wv(m + 1);
  }
  for (int j = 0; j < N; ++j) {
    VecU g(nu);
    g.noalias() = stage.B(j).transpose() * wv(j + 1);
    dense_.g.segment(j * nu, nu) = g + qp.r[j];
    dense_.lb.segment(j * nu, nu) = qp.u_lower[j];
    dense_.ub.segment(j * nu, nu) = qp.u_upper[j];
  }
  const std::vector<int>& idx = dims_.state_bound_index;
  for (int k = 1; k <= N; ++k) {
    for (int b = 0; b < static_cast<int>(idx.size()); ++b) {
      const int row = (k - 1) * static_cast<int>(idx.size()) + b;
      dense_.lc[row] = qp.x_lower[k][b] - x_bar_[k][idx[b]];
      dense_.uc[row] = qp.x_upper[k][b] - x_bar_[k][idx[b]];
    }
  }
}

const OcpQpSummary& OcpQpSolver::Solve(const OcpQp& qp) {
  Prepare(qp);
  if (summary_.status == QpStatus::kNumericalFailure) return summary_;
  return Feedback(qp.x0);
}

void OcpQpSolver::RequireSameDims(const OcpQp& qp, const OcpQpDims& dims, const char* solver) {
  if (qp.dims.horizon != dims.horizon || qp.dims.nx != dims.nx || qp.dims.nu != dims.nu ||
      qp.dims.state_bound_index != dims.state_bound_index) {
    throw std::invalid_argument(fmt::format("{}: the problem's dimensions differ from the solver's", solver));
  }
}

std::unique_ptr<OcpQpSolver> MakeOcpQpSolver(OcpQpMethod method, const OcpQpDims& dims, const ActiveSetOptions& options) {
  if (method == OcpQpMethod::kRiccati) return std::make_unique<RiccatiQpSolver>(dims, options);
  return std::make_unique<CondensingQpSolver>(dims, options);
}

const OcpQpSummary& CondensingQpSolver::Prepare(const OcpQp& qp) { return Prepare(qp, /*whole=*/true); }

const OcpQpSummary& CondensingQpSolver::PrepareVectors(const OcpQp& qp) {
  return Prepare(qp, /*whole=*/prepared_ == nullptr || summary_.status == QpStatus::kNumericalFailure);
}

const OcpQpSummary& CondensingQpSolver::Prepare(const OcpQp& qp, bool whole) {
  const Stopwatch clock;
  summary_ = OcpQpSummary{};
  RequireSameDims(qp, dims_, "CondensingQpSolver");
  // The NMPC's sizes get their own instantiation: fixed-size products (measured: CHANGELOG.md,
  // "The NMPC's implementation").
  const bool nmpc_sizes = internal::IsNmpcSize(dims_);
  if (nmpc_sizes) {
    CondenseVectors<17, 4>(qp);
  } else {
    CondenseVectors<Eigen::Dynamic, Eigen::Dynamic>(qp);
  }
  if (!whole) {
    // Inputs newly fixed or freed change the reduced QP's Hessian: that takes a whole preparation.
    FindFixedInputs();
    whole = pattern_fixed_ != fixed_;
  }
  if (whole && nmpc_sizes) {
    CondenseMatrices<17, 4>(qp);
  } else if (whole) {
    CondenseMatrices<Eigen::Dynamic, Eigen::Dynamic>(qp);
  }
  KeepPreparedVectors(qp);
  if (!whole) {
    if (reduced_) ReducedVectors();
  } else if (!PrepareReduced()) {
    summary_.status = QpStatus::kNumericalFailure;
  }
  summary_.prepare_time_s = clock.seconds();
  return summary_;
}

void CondensingQpSolver::KeepPreparedVectors(const OcpQp& qp) {
  g0_ = dense_.g;
  lc0_ = dense_.lc;
  uc0_ = dense_.uc;
  prepared_x0_ = qp.x0;
  prepared_ = &qp;
}

void CondensingQpSolver::FindFixedInputs() {
  pattern_fixed_.clear();
  for (int i = 0; i < dense_.num_variables(); ++i) {
    if (dense_.lb[i] == dense_.ub[i]) pattern_fixed_.push_back(i);
  }
}

bool CondensingQpSolver::PrepareReduced() {
  // Allocation-free after the first call for a pattern (the real-time iteration's rule): the
  // pattern is built in scratch reserved at construction, the products written out.
  const int n = dense_.num_variables(), m = dense_.num_constraints();
  FindFixedInputs();
  const int nF = static_cast<int>(pattern_fixed_.size()), nf = n - nF;
  if (nF == 0 || nf == 0) {  // nothing to eliminate, or nothing left: the whole QP
    fixed_.clear();
    reduced_.reset();
    return dense_solver_.Factorize(dense_.H);
  }
  if (pattern_fixed_ != fixed_ || !reduced_) {  // a new pattern (a rotor just failed): allocate once for it
    fixed_ = pattern_fixed_;
    free_.clear();
    for (int i = 0, b = 0; i < n; ++i) {
      if (b < nF && fixed_[static_cast<std::size_t>(b)] == i) {
        ++b;
      } else {
        free_.push_back(i);
      }
    }
    reduced_ = std::make_unique<DenseQp>(nf, m);
    reduced_solver_ = std::make_unique<DenseQpSolver>(nf, m, options_);
    z_fixed_.resize(nF);
    g_fixed_.resize(nf);
    c_fixed_.resize(m);
  }
  // Indexed views copy coefficient by coefficient.
  const IndexList free = FreeInputs();
  reduced_->H = dense_.H(free, free);
  reduced_->C = dense_.C(Eigen::all, free);
  ReducedVectors();
  return reduced_solver_->Factorize(reduced_->H);
}

void CondensingQpSolver::ReducedVectors() {
  // The fixed inputs' shares are coefficient-based products (lazyProduct), which need no
  // temporary.
  const IndexList free = FreeInputs(), fixed = FixedInputs();
  z_fixed_ = dense_.lb(fixed);
  g_fixed_.noalias() = dense_.H(free, fixed).lazyProduct(z_fixed_);
  reduced_->lb = dense_.lb(free);
  reduced_->ub = dense_.ub(free);
  c_fixed_.noalias() = dense_.C(Eigen::all, fixed).lazyProduct(z_fixed_);
}

const OcpQpSummary& CondensingQpSolver::Feedback(const Eigen::VectorXd& x0) {
  if (prepared_ == nullptr) throw std::logic_error("CondensingQpSolver::Feedback called before Prepare");
  const Stopwatch clock;
  const OcpQp& qp = *prepared_;
  const int N = dims_.horizon, nu = dims_.nu;
  if (summary_.status == QpStatus::kNumericalFailure || x0.size() != dims_.nx || !x0.allFinite()) {
    summary_.status = QpStatus::kNumericalFailure;
    return summary_;
  }
  // Only what depends on the measured state. x_bar_k moves by dx_k = A_{k-1} dx_{k-1} (dx_0 =
  // x0 - prepared x0), so g_j moves by B_j' W_{j+1} dx_{j+1} = Y_j' dx_{j+1} and the state-bound
  // rows by -dx_k[idx]: one forward pass of matrix-vector products, O(N nx^2).
  const std::vector<int>& idx = dims_.state_bound_index;
  const int nbx = static_cast<int>(idx.size());
  dx_ = x0 - prepared_x0_;
  dense_.g = g0_;
  for (int k = 0; k < N; ++k) {
    dx_next_.noalias() = qp.A[k] * dx_;
    dx_.swap(dx_next_);  // dx_ now holds dx_{k+1}
    dense_.g.segment(k * nu, nu).noalias() += y_[k].transpose() * dx_;
    for (int b = 0; b < nbx; ++b) cdx_[k * nbx + b] = dx_[idx[b]];
  }
  if (dense_.num_constraints() > 0) {
    dense_.lc = lc0_ - cdx_;
    dense_.uc = uc0_ - cdx_;
  }
  const DenseQpSummary* ds = nullptr;
  if (reduced_) {
    // Over the free inputs: the fixed ones' share of the gradient and of C z moved to the data.
    reduced_->g = dense_.g(FreeInputs()) + g_fixed_;
    if (dense_.num_constraints() > 0) {
      reduced_->lc = dense_.lc - c_fixed_;
      reduced_->uc = dense_.uc - c_fixed_;
    }
    ds = &reduced_solver_->SolveFactorized(*reduced_);
    z_(FreeInputs()) = reduced_solver_->z();
    z_(FixedInputs()) = z_fixed_;
  } else {
    ds = &dense_solver_.SolveFactorized(dense_);
    z_ = dense_solver_.z();
  }
  summary_.status = ds->status;
  summary_.start = ds->start;
  summary_.iterations = ds->iterations;
  summary_.active_constraints = ds->active_constraints + static_cast<int>(reduced_ ? fixed_.size() : 0);
  summary_.max_violation = ds->max_violation;
  // Expand the trajectory by forward simulation of the inputs.
  const Eigen::VectorXd& z = z_;
  x_[0] = x0;
  for (int k = 0; k < N; ++k) {
    u_[k] = z.segment(k * nu, nu);
    x_[k + 1].noalias() = qp.A[k] * x_[k];
    x_[k + 1].noalias() += qp.B[k] * u_[k];
    x_[k + 1] += qp.c[k];
  }
  // The objective of the returned trajectory, with the solver's own scratch vectors.
  double objective = 0.0;
  for (int k = 0; k <= N; ++k) {
    qx_.noalias() = qp.Q[k] * x_[k];
    objective += 0.5 * x_[k].dot(qx_) + qp.q[k].dot(x_[k]);
    if (k < N) {
      ru_.noalias() = qp.R[k] * u_[k];
      objective += 0.5 * u_[k].dot(ru_) + qp.r[k].dot(u_[k]);
    }
  }
  summary_.objective = objective;
  summary_.feedback_time_s = clock.seconds();
  summary_.total_time_s = summary_.prepare_time_s + summary_.feedback_time_s;
  return summary_;
}

}  // namespace rotorguard::control
