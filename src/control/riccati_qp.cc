#include "rotorguard/control/riccati_qp.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "rotorguard/core/stopwatch.h"
#include "stage_maps.h"

namespace rotorguard::control {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
using internal::StageMaps;
// A side whose normal keeps less than this share of its H^-1 norm outside the span of the active
// normals (d² = e'H^-1 e - b'M^-1 b against e'H^-1 e) is taken as dependent on them: no primal step
// (Goldfarb and Idnani's dual step only) and never added.
constexpr double kDependence = 1e-12;
}  // namespace

RiccatiQpSolver::RiccatiQpSolver(const OcpQpDims& dims, const ActiveSetOptions& options)
    : dims_(dims), options_(options) {
  dims_.Validate();
  options_.Validate();
  const int N = dims.horizon, nx = dims.nx, nu = dims.nu;
  nbx_ = static_cast<int>(dims.state_bound_index.size());
  nc_ = N * nu + N * nbx_;
  nmpc_sizes_ = internal::IsNmpcSize(dims_);
  P_.assign(N + 1, Eigen::MatrixXd::Zero(nx, nx));
  PB_.assign(N, Eigen::MatrixXd::Zero(nx, nu));
  Lu_.assign(N, Eigen::MatrixXd::Zero(nu, nu));
  K_.assign(N, Eigen::MatrixXd::Zero(nu, nx));
  Bt_.assign(N, Eigen::MatrixXd::Zero(nx, nu));
  fixed_.assign(static_cast<std::size_t>(N * nu), 0);
  pattern_.assign(static_cast<std::size_t>(N * nu), 0);
  costate_.resize(nx);
  kff_.assign(N, Eigen::VectorXd::Zero(nu));
  kr_.assign(N, Eigen::VectorXd::Zero(nu));
  x_.assign(N + 1, Eigen::VectorXd::Zero(nx));
  u_.assign(N, Eigen::VectorXd::Zero(nu));
  y_u_.assign(N, Eigen::VectorXd::Zero(nu));
  y_x_.assign(N + 1, Eigen::VectorXd::Zero(nbx_));
  tmp_xx_.resize(nx, nx);
  lower_.resize(nc_);
  upper_.resize(nc_);
  w0_.resize(nc_);
  w_.resize(nc_);
  step_.resize(nc_);
  responses_.resize(nc_, nc_);
  have_response_.assign(static_cast<std::size_t>(nc_), 0);
  // At most N nu sides are independent (the inputs' count), and dependent ones are never added;
  // rounding may pass one more through the test (AddToFactor).
  const int max_active = std::min(nc_, N * nu);
  set_ = internal::DualActiveSet(nc_, max_active + 1);
  L_ = Eigen::MatrixXd::Zero(max_active + 1, max_active + 1);
  b_.resize(max_active + 1);
  update_.resize(max_active + 1);
}

template <int NX, int NU>
bool RiccatiQpSolver::Factorize(const OcpQp& qp) {
  using MatXX = Eigen::Matrix<double, NX, NX>;
  using MatXU = Eigen::Matrix<double, NX, NU>;
  using MatUX = Eigen::Matrix<double, NU, NX>;
  using MatUU = Eigen::Matrix<double, NU, NU>;
  const int N = dims_.horizon, nx = dims_.nx, nu = dims_.nu;
  const StageMaps<NX, NU> stage{qp, nx, nu};
  const auto P = [&](int k) { return Eigen::Map<MatXX>(P_[k].data(), nx, nx); };
  Eigen::Map<MatXX> tmp(tmp_xx_.data(), nx, nx);
  // P_N = Q_N; for k = N-1 .. 0: u_k = K_k x_k minimises the stage cost plus the cost-to-go
  // 1/2 x' P_{k+1} x with K_k = -(R_k + B'P_{k+1}B)^-1 B'P_{k+1}A, and P_k = Q_k + A'P_{k+1}A +
  // (B'P_{k+1}A)' K_k. P_0 is not needed: x_0 is fixed.
  // An input fixed by equal bounds (a failed rotor's) is taken out of the stage: its column of B
  // is zeroed (its share moves into c_k in BackwardVectors) and its row and column of R become a
  // unit, so that it decouples and the recursion gives it exactly its value, k_k[i] = u_i with
  // K_k's row i zero. It never enters the active set.
  P(N) = stage.Q(N);
  for (int k = N - 1; k >= 0; --k) {
    Eigen::Map<MatXU> Bt(Bt_[k].data(), nx, nu);
    Bt = stage.B(k);
    MatUU Ru(nu, nu);
    Ru = stage.R(k);
    for (int i = 0; i < nu; ++i) {
      if (!fixed_[static_cast<std::size_t>(k * nu + i)]) continue;
      Bt.col(i).setZero();
      Ru.row(i).setZero();
      Ru.col(i).setZero();
      Ru(i, i) = 1.0;
    }
    Eigen::Map<MatXU> PB(PB_[k].data(), nx, nu);
    PB.noalias() = P(k + 1) * Bt;
    Ru.noalias() += Bt.transpose() * PB;
    if (!Ru.allFinite()) return false;
    Eigen::LLT<MatUU> llt(Ru);
    if (llt.info() != Eigen::Success) return false;
    Eigen::Map<MatUU>(Lu_[k].data(), nu, nu) = llt.matrixL();
    MatUX F(nu, nx);
    F.noalias() = PB.transpose() * stage.A(k);
    Eigen::Map<MatUX> K(K_[k].data(), nu, nx);
    K = -llt.solve(F);
    if (k == 0) return K.allFinite();
    tmp.noalias() = P(k + 1) * stage.A(k);
    P(k) = stage.Q(k);
    P(k).noalias() += stage.A(k).transpose() * tmp;
    P(k).noalias() += F.transpose() * K;
    // Symmetric in exact arithmetic; rounding would make the products drift apart over the horizon.
    tmp = P(k).transpose();
    P(k) = 0.5 * (P(k) + tmp);
  }
  return true;
}

template <int NX, int NU>
void RiccatiQpSolver::SolveStageHessian(int k, Eigen::Matrix<double, NU, 1>* h) const {
  const int nu = dims_.nu;
  const auto L =
      Eigen::Map<const Eigen::Matrix<double, NU, NU>>(Lu_[k].data(), nu, nu).template triangularView<Eigen::Lower>();
  L.solveInPlace(*h);
  L.transpose().solveInPlace(*h);
}

template <int NX, int NU>
void RiccatiQpSolver::BackwardVectors(const OcpQp& qp) {
  using MatXX = Eigen::Matrix<double, NX, NX>;
  using MatXU = Eigen::Matrix<double, NX, NU>;
  using VecX = Eigen::Matrix<double, NX, 1>;
  using VecU = Eigen::Matrix<double, NU, 1>;
  const int N = dims_.horizon, nx = dims_.nx, nu = dims_.nu;
  const StageMaps<NX, NU> stage{qp, nx, nu};
  const auto vx = [&](const Eigen::VectorXd& v) { return Eigen::Map<const VecX>(v.data(), nx); };
  // The cost-to-go's linear term p_k (1/2 x'P_k x + p_k'x): with s = P_{k+1} c_k + p_{k+1}, the
  // feedforward is k_k = -(R_k + B'P_{k+1}B)^-1 (r_k + B's) and p_k = q_k + A'(s + P_{k+1} B k_k).
  // A fixed input u_i = f adds B_i f to c_k and R_k[:, i] f to r_k, and its decoupled unit row
  // gets the linear term -f (Factorize).
  VecX p = vx(qp.q[N]);
  for (int k = N - 1; k >= 0; --k) {
    VecX s = vx(qp.c[k]);
    VecU h = Eigen::Map<const VecU>(qp.r[k].data(), nu);
    for (int i = 0; i < nu; ++i) {
      if (!fixed_[static_cast<std::size_t>(k * nu + i)]) continue;
      const double f = lower_[k * nu + i];
      s += f * stage.B(k).col(i);
      h += f * stage.R(k).col(i);
    }
    for (int i = 0; i < nu; ++i) {
      if (fixed_[static_cast<std::size_t>(k * nu + i)]) h[i] = -lower_[k * nu + i];
    }
    s = Eigen::Map<const MatXX>(P_[k + 1].data(), nx, nx) * s + p;
    h.noalias() += Eigen::Map<const MatXU>(Bt_[k].data(), nx, nu).transpose() * s;
    SolveStageHessian<NX, NU>(k, &h);
    Eigen::Map<VecU>(kff_[k].data(), nu) = -h;
    if (k > 0) {
      s.noalias() -= Eigen::Map<const MatXU>(PB_[k].data(), nx, nu) * h;
      p = vx(qp.q[k]);
      p.noalias() += stage.A(k).transpose() * s;
    }
  }
}

template <int NX, int NU>
void RiccatiQpSolver::ForwardPass(const Eigen::VectorXd* x0, const std::vector<Eigen::VectorXd>& feedforward, int last,
                                  Eigen::Ref<Eigen::VectorXd> out) const {
  using MatUX = Eigen::Matrix<double, NU, NX>;
  using VecX = Eigen::Matrix<double, NX, 1>;
  using VecU = Eigen::Matrix<double, NU, 1>;
  const int N = dims_.horizon, nx = dims_.nx, nu = dims_.nu;
  const StageMaps<NX, NU> stage{*qp_, nx, nu};
  const std::vector<int>& idx = dims_.state_bound_index;
  // u_k = K_k x_k + k_k (k_k zero after stage `last`), x_{k+1} = A_k x_k + B_k u_k (+ c_k).
  VecX x = x0 != nullptr ? VecX(Eigen::Map<const VecX>(x0->data(), nx)) : VecX(VecX::Zero(nx));
  for (int k = 0; k < N; ++k) {
    VecU u(nu);
    u.noalias() = Eigen::Map<const MatUX>(K_[k].data(), nu, nx) * x;
    if (k <= last) u += Eigen::Map<const VecU>(feedforward[k].data(), nu);
    out.segment(k * nu, nu) = u;
    VecX next(nx);
    next.noalias() = stage.A(k) * x;
    next.noalias() += stage.B(k) * u;
    if (x0 != nullptr) next += Eigen::Map<const VecX>(qp_->c[k].data(), nx);
    x = next;
    for (int b = 0; b < nbx_; ++b) out[N * nu + k * nbx_ + b] = x[idx[b]];
  }
}

template <int NX, int NU>
void RiccatiQpSolver::ComputeResponse(int index) {
  using MatXU = Eigen::Matrix<double, NX, NU>;
  using VecX = Eigen::Matrix<double, NX, 1>;
  using VecU = Eigen::Matrix<double, NU, 1>;
  const int N = dims_.horizon, nx = dims_.nx, nu = dims_.nu;
  const StageMaps<NX, NU> stage{*qp_, nx, nu};
  // v = H^-1 e minimises 1/2 z'Hz - e'z over the trajectories from x_0 = 0 with c = 0: the linear
  // term -e sits at one stage, so the backward pass starts there, and the feedforwards k_k are
  // non-zero only up to it.
  VecX p(nx);
  int last = 0;  // the last stage whose feedforward is non-zero
  int from = 0;  // the first stage of the backward pass below
  if (index < N * nu) {
    // r_j = -e_i: k_j = (R_j + B'P_{j+1}B)^-1 e_i and p_j = A_j' P_{j+1} B_j k_j.
    const int j = index / nu;
    VecU h = VecU::Zero(nu);
    h[index % nu] = 1.0;
    SolveStageHessian<NX, NU>(j, &h);
    Eigen::Map<VecU>(kr_[j].data(), nu) = h;
    if (j > 0) p.noalias() = stage.A(j).transpose() * (Eigen::Map<const MatXU>(PB_[j].data(), nx, nu) * h);
    last = j;
    from = j - 1;
  } else {
    // q_k = -e_i for the bounded state i of stage k (1..N): p_k = -e_i.
    const int s = index - N * nu, k = 1 + s / nbx_;
    p.setZero();
    p[dims_.state_bound_index[static_cast<std::size_t>(s % nbx_)]] = -1.0;
    last = from = k - 1;
  }
  // With no linear term of its own, stage m has k_m = -(R_m + B'P_{m+1}B)^-1 B'p_{m+1} and
  // p_m = A'(p_{m+1} + P_{m+1} B k_m).
  for (int m = from; m >= 0; --m) {
    VecU h(nu);
    h.noalias() = Eigen::Map<const MatXU>(Bt_[m].data(), nx, nu).transpose() * p;
    SolveStageHessian<NX, NU>(m, &h);
    h = -h;
    Eigen::Map<VecU>(kr_[m].data(), nu) = h;
    if (m > 0) {
      p.noalias() += Eigen::Map<const MatXU>(PB_[m].data(), nx, nu) * h;
      p = stage.A(m).transpose() * p;
    }
  }
  // Forward from x_0 = 0 with no gaps, writing the bounded components.
  ForwardPass<NX, NU>(nullptr, kr_, last, responses_.col(index));
}

Eigen::Ref<const Eigen::VectorXd> RiccatiQpSolver::Response(int index) {
  if (!have_response_[static_cast<std::size_t>(index)]) {
    if (nmpc_sizes_) {
      ComputeResponse<17, 4>(index);
    } else {
      ComputeResponse<Eigen::Dynamic, Eigen::Dynamic>(index);
    }
    have_response_[static_cast<std::size_t>(index)] = 1;
  }
  return responses_.col(index);
}

void RiccatiQpSolver::SchurComplementRow(const Side& c) {
  // M's new row would be [N_A' H^-1 n_c; n_c' H^-1 n_c]: l = L^-1 N_A' H^-1 n_c (into b_) and the
  // new diagonal's square d² = n_c' H^-1 n_c - |l|², the part of n_c outside the active normals' span.
  const Eigen::Ref<const Eigen::VectorXd> v = Response(c.index);
  const int q = set_.size();
  for (int j = 0; j < q; ++j) b_[j] = set_[j].sign * c.sign * v[set_[j].index];
  auto l = b_.head(q);
  L_.topLeftCorner(q, q).triangularView<Eigen::Lower>().solveInPlace(l);
  d2_ = v[c.index] - l.squaredNorm();
}

bool RiccatiQpSolver::IsIndependent(const Side& c) const { return d2_ > kDependence * responses_(c.index, c.index); }

bool RiccatiQpSolver::AddToFactor(const Side& c) {
  // At most N nu normals are independent; rounding may pass one more through the test, never more
  // than the factor's rows.
  const int q = set_.size();
  if (q >= static_cast<int>(L_.rows()) || !IsIndependent(c)) return false;
  L_.row(q).head(q) = b_.head(q).transpose();
  L_(q, q) = std::sqrt(d2_);
  return true;
}

void RiccatiQpSolver::DropFromFactor(int position) {
  // Without row and column `position`, M's factor keeps its rows above; below, the trailing block
  // T (rows and columns after `position`) must factorise T T' + x x' with x the dropped column's
  // part below the diagonal: a rank-one update by rotations, then everything moves up and left.
  const int q = set_.size();
  const int m = q - 1 - position, first = position + 1;
  auto x = update_.head(m);
  x = L_.col(position).segment(first, m);
  for (int k = 0; k < m; ++k) {
    const double lkk = L_(first + k, first + k), xk = x[k];
    const double r = std::sqrt(lkk * lkk + xk * xk), cs = r / lkk, sn = xk / lkk;
    L_(first + k, first + k) = r;
    for (int i = k + 1; i < m; ++i) {
      double& lik = L_(first + i, first + k);
      lik = (lik + sn * x[i]) / cs;
      x[i] = cs * x[i] - sn * lik;
    }
  }
  for (int i = first; i < q; ++i) {
    L_.row(i - 1).head(position) = L_.row(i).head(position);
    L_.row(i - 1).segment(position, i - position) = L_.row(i).segment(first, i - position);
  }
  L_.row(q - 1).head(q).setZero();
}

void RiccatiQpSolver::MinimiseOnFactor(Eigen::Ref<Eigen::VectorXd> lambda) {
  const int q = set_.size();
  for (int j = 0; j < q; ++j) lambda[j] = SignedBound(set_[j]) - set_[j].sign * w0_[set_[j].index];
  const auto L = L_.topLeftCorner(q, q).triangularView<Eigen::Lower>();
  L.solveInPlace(lambda);
  L.transpose().solveInPlace(lambda);
  w_ = w0_;
  for (int j = 0; j < q; ++j) w_ += (lambda[j] * set_[j].sign) * Response(set_[j].index);
}

internal::Direction RiccatiQpSolver::MakeDirection(const Side& p, Eigen::Ref<Eigen::VectorXd> r) {
  // The dual direction r = M^-1 N_A' H^-1 n_p = L^-T l and the primal one H^-1 n_p - V r; b_ keeps
  // l for p's row of the factor should p be added.
  const int q = set_.size();
  SchurComplementRow(p);
  r = b_.head(q);
  L_.topLeftCorner(q, q).triangularView<Eigen::Lower>().transpose().solveInPlace(r);
  step_ = p.sign * responses_.col(p.index);
  for (int j = 0; j < q; ++j) step_ -= (r[j] * set_[j].sign) * Response(set_[j].index);
  return {.independent = IsIndependent(p), .normal_dot_step = p.sign * step_[p.index]};
}

QpStatus RiccatiQpSolver::Iterate() {
  set_.MinimiseOnActiveSet(*this);
  QpStatus status = set_.Iterate(*this, options_);
  if (status == QpStatus::kSolved) {
    // The iterate accumulated its steps' rounding: the minimum on the final active set, computed
    // afresh, and the iterations again should that have moved a side past its bound.
    set_.MinimiseOnActiveSet(*this);
    status = set_.Iterate(*this, options_);
  }
  return status;
}

template <int NX, int NU>
void RiccatiQpSolver::ExpandTrajectory(const Eigen::VectorXd& x0) {
  using VecX = Eigen::Matrix<double, NX, 1>;
  using VecU = Eigen::Matrix<double, NU, 1>;
  const OcpQp& qp = *qp_;
  const int N = dims_.horizon, nx = dims_.nx, nu = dims_.nu;
  const StageMaps<NX, NU> stage{qp, nx, nu};
  const auto X = [&](int k) { return Eigen::Map<VecX>(x_[k].data(), nx); };
  const auto U = [&](int k) { return Eigen::Map<VecU>(u_[k].data(), nu); };
  const std::vector<int>& idx = dims_.state_bound_index;
  for (int k = 0; k < N; ++k) y_u_[k].setZero();
  for (int k = 0; k <= N; ++k) y_x_[k].setZero();
  for (int j = 0; j < set_.size(); ++j) {
    const Side& c = set_[j];
    const double y = c.sign * set_.multipliers()[j];
    if (c.index < N * nu) {
      y_u_[c.index / nu][c.index % nu] += y;
    } else {
      const int s = c.index - N * nu;
      y_x_[1 + s / nbx_][s % nbx_] += y;
    }
  }
  // The inputs are components of w; the states follow from them by the dynamics, exactly.
  x_[0] = x0;
  double objective = 0.0, violation = 0.0;
  for (int k = 0; k < N; ++k) {
    U(k) = w_.segment(k * nu, nu);
    X(k + 1) = Eigen::Map<const VecX>(qp.c[k].data(), nx);
    X(k + 1).noalias() += stage.A(k) * X(k);
    X(k + 1).noalias() += stage.B(k) * U(k);
    violation = std::max({violation, (qp.u_lower[k] - u_[k]).maxCoeff(), (u_[k] - qp.u_upper[k]).maxCoeff()});
    for (int b = 0; b < nbx_; ++b) {
      const double xb = x_[k + 1][idx[b]];
      violation = std::max({violation, qp.x_lower[k + 1][b] - xb, xb - qp.x_upper[k + 1][b]});
    }
  }
  for (int k = 0; k <= N; ++k) {
    objective += X(k).dot(0.5 * (stage.Q(k) * X(k)) + Eigen::Map<const VecX>(qp.q[k].data(), nx));
    if (k < N) objective += U(k).dot(0.5 * (stage.R(k) * U(k)) + Eigen::Map<const VecU>(qp.r[k].data(), nu));
  }
  summary_.objective = objective;
  summary_.max_violation = violation;
  if (std::find(fixed_.begin(), fixed_.end(), 1) == fixed_.end()) return;
  // A fixed input's multiplier from stationarity in u_k, R u_k + r_k + B_k' λ_{k+1} = y_k, with the
  // costate of the dynamics λ_N = Q_N x_N + q_N - E y_N, λ_k = Q_k x_k + q_k + A_k' λ_{k+1} - E y_k
  // (E y_k: the bounded states' multipliers placed at their indices).
  Eigen::Map<VecX> lambda(costate_.data(), nx);
  lambda = stage.Q(N) * X(N) + Eigen::Map<const VecX>(qp.q[N].data(), nx);
  for (int k = N - 1; k >= 0; --k) {
    for (int b = 0; b < nbx_; ++b) lambda[idx[b]] -= y_x_[k + 1][b];
    for (int i = 0; i < nu; ++i) {
      if (!fixed_[static_cast<std::size_t>(k * nu + i)]) continue;
      y_u_[k][i] = stage.R(k).col(i).dot(U(k)) + qp.r[k][i] + stage.B(k).col(i).dot(lambda);
    }
    if (k > 0) {
      VecX next = stage.A(k).transpose() * lambda;
      lambda = next + stage.Q(k) * X(k) + Eigen::Map<const VecX>(qp.q[k].data(), nx);
    }
  }
}

void RiccatiQpSolver::ClearActiveSet() { set_.Clear(); }

const OcpQpSummary& RiccatiQpSolver::Fail(QpStatus status) {
  for (auto& u : u_) u.setZero();
  for (auto& x : x_) x.setZero();
  for (auto& y : y_u_) y.setZero();
  for (auto& y : y_x_) y.setZero();
  ClearActiveSet();
  set_.Forget();
  summary_.status = status;
  return summary_;
}

const OcpQpSummary& RiccatiQpSolver::Prepare(const OcpQp& qp) { return Prepare(qp, /*whole=*/true); }

const OcpQpSummary& RiccatiQpSolver::PrepareVectors(const OcpQp& qp) { return Prepare(qp, /*whole=*/!prepared_); }

const OcpQpSummary& RiccatiQpSolver::Prepare(const OcpQp& qp, bool whole) {
  const Stopwatch clock;
  summary_ = OcpQpSummary{};
  RequireSameDims(qp, dims_, "RiccatiQpSolver");
  const int N = dims_.horizon, nu = dims_.nu;
  qp_ = &qp;
  prepared_ = false;
  const auto fail = [&](QpStatus status) -> const OcpQpSummary& {
    summary_.prepare_time_s = clock.seconds();
    return Fail(status);
  };
  // The bounded components' bounds; infinite sides never bind, NaN is rejected, crossed ones
  // make the QP infeasible (reported by the feedback, as an infeasible set of constraints is).
  for (int k = 0; k < N; ++k) {
    lower_.segment(k * nu, nu) = qp.u_lower[k];
    upper_.segment(k * nu, nu) = qp.u_upper[k];
    lower_.segment(N * nu + k * nbx_, nbx_) = qp.x_lower[k + 1];
    upper_.segment(N * nu + k * nbx_, nbx_) = qp.x_upper[k + 1];
  }
  if (lower_.array().isNaN().any() || upper_.array().isNaN().any()) return fail(QpStatus::kNumericalFailure);
  crossed_ = (lower_.array() > upper_.array()).any();
  // Inputs fixed by equal bounds are taken out of the recursion's stages (Factorize): a change of
  // which ones takes a whole preparation, a change of their values only the vectors.
  for (int i = 0; i < N * nu; ++i) pattern_[static_cast<std::size_t>(i)] = lower_[i] == upper_[i];
  if (pattern_ != fixed_) {
    fixed_ = pattern_;
    whole = true;
  }
  if (whole) {
    const bool factorized = nmpc_sizes_ ? Factorize<17, 4>(qp) : Factorize<Eigen::Dynamic, Eigen::Dynamic>(qp);
    if (!factorized) return fail(QpStatus::kNumericalFailure);
    std::fill(have_response_.begin(), have_response_.end(), 0);
  }
  if (nmpc_sizes_) {
    BackwardVectors<17, 4>(qp);
  } else {
    BackwardVectors<Eigen::Dynamic, Eigen::Dynamic>(qp);
  }
  for (const auto& k : kff_) {
    if (!k.allFinite()) return fail(QpStatus::kNumericalFailure);
  }
  // The start of the next feedback. On a new factorisation, the previous solve's active set (its
  // sides with finite bounds and independent normals) is added afresh; with the factorisation
  // kept, the active set and its Schur complement are kept too.
  if (whole) {
    ClearActiveSet();
    start_ = set_.previous().empty() ? QpStart::kCold : QpStart::kWarm;
    for (const Side& c : set_.previous()) {
      if (!std::isfinite(SignedBound(c)) || IsFixed(c.index)) continue;
      SchurComplementRow(c);
      set_.Add(*this, c);  // refused when dependent on those added
    }
  } else {
    start_ = set_.size() > 0 ? QpStart::kHot : QpStart::kCold;
  }
  prepared_ = true;
  summary_.prepare_time_s = clock.seconds();
  return summary_;
}

const OcpQpSummary& RiccatiQpSolver::Feedback(const Eigen::VectorXd& x0) {
  if (qp_ == nullptr) throw std::logic_error("RiccatiQpSolver::Feedback called before Prepare");
  const Stopwatch clock;
  const double prepare_s = summary_.prepare_time_s;
  summary_ = OcpQpSummary{};
  summary_.prepare_time_s = prepare_s;
  const auto finish = [&](QpStatus status) -> const OcpQpSummary& {
    if (status != QpStatus::kSolved && status != QpStatus::kMaxIterations) Fail(status);
    summary_.status = status;
    summary_.feedback_time_s = clock.seconds();
    summary_.total_time_s = summary_.prepare_time_s + summary_.feedback_time_s;
    return summary_;
  };
  if (!prepared_ || x0.size() != dims_.nx || !x0.allFinite()) return finish(QpStatus::kNumericalFailure);
  if (crossed_) return finish(QpStatus::kInfeasible);
  // The unconstrained minimum from the measured state.
  if (nmpc_sizes_) {
    ForwardPass<17, 4>(&x0, kff_, dims_.horizon - 1, w0_);
  } else {
    ForwardPass<Eigen::Dynamic, Eigen::Dynamic>(&x0, kff_, dims_.horizon - 1, w0_);
  }
  if (!w0_.allFinite()) return finish(QpStatus::kNumericalFailure);
  summary_.start = start_;
  set_.ResetIterations();
  // A side whose bound is now infinite binds no more; one whose input is now fixed holds by
  // construction.
  set_.DropWhere(*this, [&](const Side& c) { return !std::isfinite(SignedBound(c)) || IsFixed(c.index); });
  const QpStatus status = Iterate();
  if (status == QpStatus::kNumericalFailure || !w_.allFinite()) return finish(QpStatus::kNumericalFailure);
  if (nmpc_sizes_) {
    ExpandTrajectory<17, 4>(x0);
  } else {
    ExpandTrajectory<Eigen::Dynamic, Eigen::Dynamic>(x0);
  }
  summary_.iterations = set_.iterations();
  summary_.active_constraints = set_.size() + static_cast<int>(std::count(fixed_.begin(), fixed_.end(), 1));
  if (status == QpStatus::kSolved && options_.warm_start) {
    set_.Remember();
    start_ = QpStart::kHot;  // a feedback again on this preparation starts from this set
  } else {
    set_.Forget();
    ClearActiveSet();
    start_ = QpStart::kCold;
  }
  return finish(status);
}

}  // namespace rotorguard::control
