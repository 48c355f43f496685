
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "rotorguard/control/dense_qp.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/stopwatch.h"

namespace rotorguard::control {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Givens rotation (c, s) with [c s; -s c] (a, b)' = (hypot(a, b), 0)'. sqrt(a² + b²) where the
/// squares neither overflow nor underflow; std::hypot, which scales and is far slower (it was 2 %
/// of a forest flight's time), only where they would.
inline void Givens(double a, double b, double* c, double* s) {
  const double h2 = a * a + b * b;
  const bool squares_representable = h2 > std::numeric_limits<double>::min() && h2 < std::numeric_limits<double>::max();
  const double h = squares_representable ? std::sqrt(h2) : std::hypot(a, b);
  if (h == 0.0) {
    *c = 1.0;
    *s = 0.0;
  } else {
    *c = a / h;
    *s = b / h;
  }
}
}  // namespace

std::string DenseQpSummary::BriefReport() const {
  return fmt::format("QP {}: {} start from {} active, {} iterations, {} active, objective {:.6g}, max violation "
                     "{:.2e}, {:.1f} us",
                     ToString(status), ToString(start), start_active_constraints, iterations, active_constraints,
                     objective, max_violation, solve_time_s * 1e6);
}

DenseQp::DenseQp(int n, int m)
    : H(Eigen::MatrixXd::Identity(n, n)),
      g(Eigen::VectorXd::Zero(n)),
      lb(Eigen::VectorXd::Constant(n, -kInf)),
      ub(Eigen::VectorXd::Constant(n, kInf)),
      C(Eigen::MatrixXd::Zero(m, n)),
      lc(Eigen::VectorXd::Constant(m, -kInf)),
      uc(Eigen::VectorXd::Constant(m, kInf)) {}

DenseQpSolver::DenseQpSolver(int n, int m, const ActiveSetOptions& options)
    : n_(n),
      m_(m),
      options_(options),
      chol_(n, n),
      J0_(n, n),
      order_(static_cast<std::size_t>(std::max(n, 0))),
      placed_mark_(static_cast<std::size_t>(std::max(n, 0)), 0),
      J_(n, n),
      height_(static_cast<std::size_t>(std::max(n, 0)), 0),
      R_(Eigen::MatrixXd::Zero(n, n)),
      z_(n),
      d_(n),
      step_(n),
      r_(n),
      cz_(m),
      y_bound_(n),
      y_constraint_(m),
      set_(n + m, n),  // at most n independent normals
      previous_rows_(n, n) {
  if (n < 1 || m < 0) ThrowInvalidArgument("DenseQpSolver", "n, m", fmt::format("{}, {}", n, m), "n >= 1, m >= 0");
  options_.Validate();
  placed_.reserve(static_cast<std::size_t>(n));
}

double DenseQpSolver::SignedBound(const DenseQp& qp, const Side& c) const {
  if (c.index < n_) return c.sign * (c.sign > 0 ? qp.lb[c.index] : qp.ub[c.index]);
  const int row = c.index - n_;
  return c.sign * (c.sign > 0 ? qp.lc[row] : qp.uc[row]);
}

double DenseQpSolver::Slack(const Side& c) const {
  const double sz = c.index < n_ ? c.sign * z_[c.index] : c.sign * qp_->C.row(c.index - n_).dot(z_);
  return sz - SignedBound(*qp_, c);
}

void DenseQpSolver::ComputeD(const DenseQp& qp, const Side& c) {
  if (c.index < n_) {
    d_ = c.sign * J_.row(c.index).transpose();  // J' e_i: a bound needs no product
  } else {
    d_.noalias() = J_.transpose() * qp.C.row(c.index - n_).transpose();
    d_ *= c.sign;
  }
}

void DenseQpSolver::ScanViolations(internal::ViolationSearch& search) {
  search.Scan(z_, qp_->lb, qp_->ub, 0);
  if (m_ > 0) {
    cz_.noalias() = qp_->C * z_;
    search.Scan(cz_, qp_->lc, qp_->uc, n_);
  }
}

internal::Direction DenseQpSolver::MakeDirection(const Side& p, Eigen::Ref<Eigen::VectorXd> r) {
  // The primal step in the null space of the active normals, J2 J2' n_p, and the dual one,
  // R^-1 J1' n_p.
  const int q = set_.size();
  ComputeD(*qp_, p);
  step_.noalias() = J_.rightCols(n_ - q) * d_.tail(n_ - q);
  r = R_.topLeftCorner(q, q).triangularView<Eigen::Upper>().solve(d_.head(q));
  const double ns = p.index < n_ ? p.sign * step_[p.index] : p.sign * qp_->C.row(p.index - n_).dot(step_);
  return {.independent = step_.norm() > 1e-14 * (1.0 + d_.norm()), .normal_dot_step = ns};
}

void DenseQpSolver::RotateColumns(int j, double cs, double sn) {
  const int rows = std::max(height_[static_cast<std::size_t>(j)], height_[static_cast<std::size_t>(j) + 1]);
  height_[static_cast<std::size_t>(j)] = height_[static_cast<std::size_t>(j) + 1] = rows;
  double* const left = J_.col(j).data();
  double* const right = J_.col(j + 1).data();
  for (int i = 0; i < rows; ++i) {
    const double a = left[i], b = right[i];
    left[i] = cs * a + sn * b;
    right[i] = -sn * a + cs * b;
  }
}

bool DenseQpSolver::AddToFactor(const Side&) {
  // Rotate d so that only d[0..q] is non-zero; apply the same rotations to the columns of J.
  const int q = set_.size();
  for (int j = n_ - 1; j > q; --j) {
    if (d_[j] == 0.0) continue;  // Givens would give sn = 0: nothing to rotate
    double cs, sn;
    Givens(d_[j - 1], d_[j], &cs, &sn);
    if (sn == 0.0) continue;
    d_[j - 1] = cs * d_[j - 1] + sn * d_[j];
    d_[j] = 0.0;
    RotateColumns(j - 1, cs, sn);
  }
  R_.col(q).head(q + 1) = d_.head(q + 1);
  return true;
}

void DenseQpSolver::DropFromFactor(int position) {
  // Remove column `position` of R; the upper-Hessenberg rest is made triangular by rotations on
  // rows (col, col + 1), mirrored on the columns of J.
  const int q = set_.size();
  for (int col = position; col < q - 1; ++col) R_.col(col).head(q) = R_.col(col + 1).head(q);
  R_.col(q - 1).setZero();
  for (int col = position; col < q - 1; ++col) {
    double cs, sn;
    Givens(R_(col, col), R_(col + 1, col), &cs, &sn);
    if (sn == 0.0) continue;
    for (int k = col; k < q - 1; ++k) {
      const double a = R_(col, k), b = R_(col + 1, k);
      R_(col, k) = cs * a + sn * b;
      R_(col + 1, k) = -sn * a + cs * b;
    }
    R_(col + 1, col) = 0.0;
    RotateColumns(col, cs, sn);
  }
}

void DenseQpSolver::OrderVariables() {
  // The bounds active at the last solve go last, in reverse order of activation, so that J0's
  // trailing columns factorise them as they stand (StartActiveSet); the other variables keep
  // their order.
  placed_.clear();
  for (const Side& c : set_.previous()) {
    if (c.index < n_) placed_.push_back(c);
  }
  std::fill(placed_mark_.begin(), placed_mark_.end(), 0);
  for (const Side& c : placed_) {
    // Both sides of one variable are never active together (their normals are dependent).
    assert(!placed_mark_[static_cast<std::size_t>(c.index)]);
    placed_mark_[static_cast<std::size_t>(c.index)] = 1;
  }
  int k = 0;
  for (int i = 0; i < n_; ++i) {
    if (!placed_mark_[static_cast<std::size_t>(i)]) order_[static_cast<std::size_t>(k++)] = i;
  }
  for (auto c = placed_.rbegin(); c != placed_.rend(); ++c) order_[static_cast<std::size_t>(k++)] = c->index;
}

bool DenseQpSolver::Factorize(const Eigen::MatrixXd& H) {
  factorized_ = false;
  hot_startable_ = false;  // J and R were built on the previous factorisation
  if (H.rows() != n_ || H.cols() != n_ || !H.allFinite()) return false;
  OrderVariables();
  const IndexList order(order_.data(), n_);
  if (permuted()) {
    chol_ = H(order, order);  // P H P', the variables in order_
  } else {
    chol_ = H;
  }
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(chol_);
  if (llt.info() != Eigen::Success) return false;
  // L^-T of the ordered Hessian, upper triangular: column j solves L' x = e_j and needs only the
  // leading (j+1) x (j+1) block, so the columns are solved in panels against growing leading
  // blocks. That is a third of the work of solving against the whole identity (measured:
  // CHANGELOG.md). J_ is free to serve as scratch: a new factorisation ends the hot starts.
  Eigen::MatrixXd& ordered = permuted() ? J_ : J0_;
  constexpr int kPanel = 8;
  ordered.setZero();
  for (int j0 = 0; j0 < n_; j0 += kPanel) {
    const int j1 = std::min(n_, j0 + kPanel), w = j1 - j0;
    ordered.block(j0, j0, w, w).setIdentity();
    chol_.topLeftCorner(j1, j1).triangularView<Eigen::Lower>().transpose().solveInPlace(ordered.block(0, j0, j1, w));
  }
  // J0 = P' L^-T factorises H^-1 = J0 J0' in the variables' own order; the rows move back to it.
  if (permuted()) J0_(order, Eigen::all) = J_;
  factorized_ = true;
  return true;
}

const DenseQpSummary& DenseQpSolver::Solve(const DenseQp& qp) {
  const Stopwatch clock;
  Factorize(qp.H);  // when it fails, SolveFactorized reports the numerical failure
  const double factorize_s = clock.seconds();
  SolveFactorized(qp);
  summary_.solve_time_s += factorize_s;
  return summary_;
}

void DenseQpSolver::ResetActiveSet() {
  hot_startable_ = false;
  set_.Clear();
}

void DenseQpSolver::ClearActiveSet() {
  ResetActiveSet();
  J_ = J0_;
  // Column j of L^-T is zero below row j; with the rows moved back to the variables' order the
  // zeros are scattered, and the rotations run over whole columns.
  for (int j = 0; j < n_; ++j) height_[static_cast<std::size_t>(j)] = permuted() ? n_ : j + 1;
  R_.setZero();
}

QpStart DenseQpSolver::StartActiveSet(const DenseQp& qp) {
  // A hot start needs J, R to factorise the same normals in the same metric: no Factorize since
  // (hot_startable_), the active rows of C as they were, and a bounded number of hot starts in a
  // row, since each adds its rotations' rounding to J and R (a rebuild from J0 every
  // kMaxHotStartsInARow solves costs one warm start).
  // (With warm_start off nothing is ever kept: KeepForWarmStart is where the option acts.)
  constexpr int kMaxHotStartsInARow = 50;
  bool hot = hot_startable_ && hot_starts_in_a_row_ < kMaxHotStartsInARow;
  for (int j = 0; hot && j < set_.size(); ++j) {
    const Side& c = set_[j];
    hot = c.index < n_ || qp.C.row(c.index - n_) == previous_rows_.row(j);
  }
  hot_startable_ = false;  // until this solve succeeds
  QpStart start = QpStart::kHot;
  if (hot) {
    ++hot_starts_in_a_row_;
  } else {
    hot_starts_in_a_row_ = 0;
    ClearActiveSet();
    start = !placed_.empty() || !set_.previous().empty() ? QpStart::kWarm : QpStart::kCold;
  }
  if (start == QpStart::kWarm) {
    PlaceOrderedBounds();
    for (const Side& c : set_.previous()) {
      if (set_.IsActive(c) || !std::isfinite(SignedBound(qp, c))) continue;
      ComputeD(qp, c);
      // A normal (nearly) in the span of those already added would make R singular: left to the
      // iterations, which add it only if it is violated and independent.
      constexpr double kIndependence = 1e-8;
      if (d_.tail(n_ - set_.size()).norm() <= kIndependence * d_.norm()) continue;
      set_.Add(*this, c);
    }
  }
  // A side whose bound is now infinite binds no more.
  set_.DropWhere(*this, [&](const Side& c) { return !std::isfinite(SignedBound(qp, c)); });
  return start;
}

void DenseQpSolver::PlaceOrderedBounds() {
  // Factorize put the k placed bounds' variables last, the c-th at position n - 1 - c, so J0 = P'
  // L^-T with L^-T upper triangular: for the normals N = [s_c e_(variable c)], J0's column n - 1
  // - a has N' J0[:, n - 1 - a] = 0 for a > c, and its first n - k columns are orthogonal to all of
  // N. J = [J0's columns n - 1, ..., n - k, then 0, ..., n - k - 1] and R(a, c) = s_c J0(variable c,
  // n - 1 - a) are therefore the factorisation of the active set N: no rotation is needed.
  const int k = static_cast<int>(placed_.size());
  if (k == 0) return;
  for (int a = 0; a < k; ++a) J_.col(a) = J0_.col(n_ - 1 - a);
  J_.rightCols(n_ - k) = J0_.leftCols(n_ - k);
  for (int c = 0; c < k; ++c) {
    const Side& side = placed_[static_cast<std::size_t>(c)];
    for (int a = 0; a <= c; ++a) R_(a, c) = side.sign * J0_(side.index, n_ - 1 - a);
    set_.Push(side);
  }
}

void DenseQpSolver::MinimiseOnFactor(Eigen::Ref<Eigen::VectorXd> u) {
  const int q = set_.size();
  for (int j = 0; j < q; ++j) r_[j] = SignedBound(*qp_, set_[j]);
  auto R = R_.topLeftCorner(q, q).triangularView<Eigen::Upper>();
  R.transpose().solveInPlace(r_.head(q));  // R^-T b
  d_.noalias() = J_.transpose() * qp_->g;   // [J1' g; J2' g]
  u = r_.head(q) + d_.head(q);
  R.solveInPlace(u);
  d_.head(q) = r_.head(q);
  d_.tail(n_ - q) *= -1.0;
  z_.noalias() = J_ * d_;
}

void DenseQpSolver::KeepForWarmStart(const DenseQp& qp) {
  if (!options_.warm_start) return;
  set_.Remember();
  for (int j = 0; j < set_.size(); ++j) {
    if (set_[j].index >= n_) previous_rows_.row(j) = qp.C.row(set_[j].index - n_);
  }
  hot_startable_ = true;
}

const DenseQpSummary& DenseQpSolver::SolveFactorized(const DenseQp& qp) {
  const Stopwatch clock;
  summary_ = DenseQpSummary{};
  qp_ = &qp;
  const auto finish = [&](QpStatus status) -> const DenseQpSummary& {
    summary_.status = status;
    summary_.iterations = set_.iterations();
    summary_.active_constraints = set_.size();
    y_bound_.setZero();
    y_constraint_.setZero();
    for (int j = 0; j < set_.size(); ++j) {
      const Side& c = set_[j];
      if (c.index < n_) {
        y_bound_[c.index] += c.sign * set_.multipliers()[j];
      } else {
        y_constraint_[c.index - n_] += c.sign * set_.multipliers()[j];
      }
    }
    if (status != QpStatus::kNumericalFailure && z_.allFinite()) {  // the data may hold NaN
      step_.noalias() = qp.H * z_;
      summary_.objective = 0.5 * z_.dot(step_) + qp.g.dot(z_);
      double violation = ((qp.lb - z_).cwiseMax(z_ - qp.ub)).maxCoeff();
      if (m_ > 0) {
        cz_.noalias() = qp.C * z_;
        violation = std::max(violation, ((qp.lc - cz_).cwiseMax(cz_ - qp.uc)).maxCoeff());
      }
      summary_.max_violation = std::max(0.0, violation);
    }
    if (status == QpStatus::kSolved) {
      KeepForWarmStart(qp);
    } else {
      // The next solve starts without this one's set: from the bounds the factorisation placed
      // last (still a valid start), or cold.
      set_.Forget();
    }
    qp_ = nullptr;
    summary_.solve_time_s = clock.seconds();
    return summary_;
  };

  // Data the method cannot start from (or a start that overflowed): no active set and no
  // multipliers are returned, z is zero for a numerical failure, and finish forgets the guess.
  const auto reject = [&](QpStatus status) -> const DenseQpSummary& {
    ResetActiveSet();
    if (status == QpStatus::kNumericalFailure) z_.setZero();
    return finish(status);
  };
  set_.ResetIterations();
  // Bounds may be infinite but never NaN (a NaN bound would be silently ignored by comparisons).
  const bool nan_bound = qp.lb.array().isNaN().any() || qp.ub.array().isNaN().any() ||
                         qp.lc.array().isNaN().any() || qp.uc.array().isNaN().any();
  if (!factorized_ || qp.num_variables() != n_ || qp.num_constraints() != m_ || !qp.g.allFinite() ||
      (m_ > 0 && !qp.C.allFinite()) || nan_bound) {
    return reject(QpStatus::kNumericalFailure);
  }
  if ((qp.lb.array() > qp.ub.array()).any() || (m_ > 0 && (qp.lc.array() > qp.uc.array()).any())) {
    return reject(QpStatus::kInfeasible);
  }

  // The start: the minimum on the kept or rebuilt active set, or the unconstrained minimum
  // z = -J J' g (H = L L', J = L^-T) when the set is empty.
  summary_.start = StartActiveSet(qp);
  set_.MinimiseOnActiveSet(*this);
  summary_.start_active_constraints = set_.size();
  // A start on a nearly dependent set with huge finite bounds could overflow.
  if (!z_.allFinite()) return reject(QpStatus::kNumericalFailure);
  return finish(set_.Iterate(*this, options_));
}

}  // namespace rotorguard::control
