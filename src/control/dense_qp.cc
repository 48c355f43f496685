
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

std::string_view ToString(QpStatus status) {
  switch (status) {
    case QpStatus::kNotSolved: return "not solved (Solve() was not called)";
    case QpStatus::kSolved: return "solved";
    case QpStatus::kMaxIterations: return "max iterations reached";
    case QpStatus::kInfeasible: return "infeasible";
    case QpStatus::kNumericalFailure: return "numerical failure";
  }
  return "unknown";
}

std::string_view ToString(QpStart start) {
  switch (start) {
    case QpStart::kCold: return "cold";
    case QpStart::kWarm: return "warm";
    case QpStart::kHot: return "hot";
  }
  return "unknown";
}

std::string DenseQpSummary::BriefReport() const {
  return fmt::format("QP {}: {} start from {} active, {} iterations, {} active, objective {:.6g}, max violation "
                     "{:.2e}, {:.1f} us",
                     ToString(status), ToString(start), start_active_constraints, iterations, active_constraints,
                     objective, max_violation, solve_time_s * 1e6);
}

void DenseQpOptions::Validate() const {
  if (!(feasibility_tolerance > 0.0) || !std::isfinite(feasibility_tolerance)) {
    ThrowValidation("DenseQpOptions", "feasibility_tolerance", feasibility_tolerance, "a finite value > 0");
  }
  if (max_iterations < 1) ThrowValidation("DenseQpOptions", "max_iterations", max_iterations, "a count >= 1");
}

DenseQp::DenseQp(int n, int m)
    : H(Eigen::MatrixXd::Identity(n, n)),
      g(Eigen::VectorXd::Zero(n)),
      lb(Eigen::VectorXd::Constant(n, -kInf)),
      ub(Eigen::VectorXd::Constant(n, kInf)),
      C(Eigen::MatrixXd::Zero(m, n)),
      lc(Eigen::VectorXd::Constant(m, -kInf)),
      uc(Eigen::VectorXd::Constant(m, kInf)) {}

DenseQpSolver::DenseQpSolver(int n, int m, const DenseQpOptions& options)
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
      u_(n),
      cz_(m),
      y_bound_(n),
      y_constraint_(m),
      is_active_(2 * static_cast<std::size_t>(n + m), 0),
      previous_rows_(n, n) {
  if (n < 1 || m < 0) ThrowInvalidArgument("DenseQpSolver", "n, m", fmt::format("{}, {}", n, m), "n >= 1, m >= 0");
  options_.Validate();
  active_.reserve(static_cast<std::size_t>(n));
  previous_.reserve(static_cast<std::size_t>(n));
  placed_.reserve(static_cast<std::size_t>(n));
}

double DenseQpSolver::SignedBound(const DenseQp& qp, const Side& c) const {
  if (c.index < n_) return c.sign * (c.sign > 0 ? qp.lb[c.index] : qp.ub[c.index]);
  const int row = c.index - n_;
  return c.sign * (c.sign > 0 ? qp.lc[row] : qp.uc[row]);
}

double DenseQpSolver::Slack(const DenseQp& qp, const Side& c) const {
  const double sz = c.index < n_ ? c.sign * z_[c.index] : c.sign * qp.C.row(c.index - n_).dot(z_);
  return sz - SignedBound(qp, c);
}

void DenseQpSolver::ComputeD(const DenseQp& qp, const Side& c) {
  if (c.index < n_) {
    d_ = c.sign * J_.row(c.index).transpose();  // J' e_i: a bound needs no product
  } else {
    d_.noalias() = J_.transpose() * qp.C.row(c.index - n_).transpose();
    d_ *= c.sign;
  }
}

double DenseQpSolver::NormalDotStep(const DenseQp& qp, const Side& c) const {
  if (c.index < n_) return c.sign * step_[c.index];
  return c.sign * qp.C.row(c.index - n_).dot(step_);
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

void DenseQpSolver::AddToActiveSet(const Side& c) {
  // Rotate d so that only d[0..q] is non-zero; apply the same rotations to the columns of J.
  for (int j = n_ - 1; j > q_; --j) {
    if (d_[j] == 0.0) continue;  // Givens would give sn = 0: nothing to rotate
    double cs, sn;
    Givens(d_[j - 1], d_[j], &cs, &sn);
    if (sn == 0.0) continue;
    d_[j - 1] = cs * d_[j - 1] + sn * d_[j];
    d_[j] = 0.0;
    RotateColumns(j - 1, cs, sn);
  }
  R_.col(q_).head(q_ + 1) = d_.head(q_ + 1);
  active_.push_back(c);
  is_active_[2 * c.index + (c.sign < 0)] = 1;
  ++q_;
}

void DenseQpSolver::DropFromActiveSet(int position) {
  const Side c = active_[position];
  is_active_[2 * c.index + (c.sign < 0)] = 0;
  active_.erase(active_.begin() + position);
  for (int j = position; j < q_ - 1; ++j) u_[j] = u_[j + 1];
  // Remove column `position` of R; the upper-Hessenberg rest is made triangular by rotations on
  // rows (col, col + 1), mirrored on the columns of J.
  for (int col = position; col < q_ - 1; ++col) R_.col(col).head(q_) = R_.col(col + 1).head(q_);
  R_.col(q_ - 1).setZero();
  for (int col = position; col < q_ - 1; ++col) {
    double cs, sn;
    Givens(R_(col, col), R_(col + 1, col), &cs, &sn);
    if (sn == 0.0) continue;
    for (int k = col; k < q_ - 1; ++k) {
      const double a = R_(col, k), b = R_(col + 1, k);
      R_(col, k) = cs * a + sn * b;
      R_(col + 1, k) = -sn * a + cs * b;
    }
    R_(col + 1, col) = 0.0;
    RotateColumns(col, cs, sn);
  }
  --q_;
}

void DenseQpSolver::OrderVariables() {
  // The bounds active at the last solve go last, in reverse order of activation, so that J0's
  // trailing columns factorise them as they stand (StartActiveSet); the other variables keep
  // their order.
  placed_.clear();
  for (const Side& c : previous_) {
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
  q_ = 0;
  active_.clear();
  std::fill(is_active_.begin(), is_active_.end(), 0);
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
  for (int j = 0; hot && j < q_; ++j) {
    const Side& c = active_[j];
    hot = c.index < n_ || qp.C.row(c.index - n_) == previous_rows_.row(j);
  }
  hot_startable_ = false;  // until this solve succeeds
  QpStart start = QpStart::kHot;
  if (hot) {
    ++hot_starts_in_a_row_;
  } else {
    hot_starts_in_a_row_ = 0;
    ClearActiveSet();
    start = !placed_.empty() || !previous_.empty() ? QpStart::kWarm : QpStart::kCold;
  }
  if (start == QpStart::kWarm) {
    PlaceOrderedBounds();
    for (const Side& c : previous_) {
      if (is_active_[2 * c.index + (c.sign < 0)] || !std::isfinite(SignedBound(qp, c))) continue;
      ComputeD(qp, c);
      // A normal (nearly) in the span of those already added would make R singular: left to the
      // iterations, which add it only if it is violated and independent.
      constexpr double kIndependence = 1e-8;
      if (d_.tail(n_ - q_).norm() <= kIndependence * d_.norm()) continue;
      AddToActiveSet(c);
    }
  }
  // A side whose bound is now infinite binds no more.
  for (int j = q_ - 1; j >= 0; --j) {
    if (!std::isfinite(SignedBound(qp, active_[j]))) DropFromActiveSet(j);
  }
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
    active_.push_back(side);
    is_active_[2 * side.index + (side.sign < 0)] = 1;
  }
  q_ = k;
}

void DenseQpSolver::MinimiseOnActiveSet(const DenseQp& qp) {
  // With J' N = [R; 0] for the active normals N and J J' = H^-1, the minimum on N' z = b is
  // z = J1 R^-T b - J2 J2' g, and its multipliers (H z + g = N u) u = R^-1 (R^-T b + J1' g).
  while (true) {
    for (int j = 0; j < q_; ++j) r_[j] = SignedBound(qp, active_[j]);
    auto R = R_.topLeftCorner(q_, q_).triangularView<Eigen::Upper>();
    R.transpose().solveInPlace(r_.head(q_));  // R^-T b
    d_.noalias() = J_.transpose() * qp.g;       // [J1' g; J2' g]
    u_.head(q_) = r_.head(q_) + d_.head(q_);
    R.solveInPlace(u_.head(q_));
    d_.head(q_) = r_.head(q_);
    d_.tail(n_ - q_) *= -1.0;
    z_.noalias() = J_ * d_;
    // Drop the most negative multiplier and minimise again; at most q rounds.
    int most_negative = -1;
    for (int j = 0; j < q_; ++j) {
      if (u_[j] < 0.0 && (most_negative < 0 || u_[j] < u_[most_negative])) most_negative = j;
    }
    if (most_negative < 0) return;
    DropFromActiveSet(most_negative);
  }
}

void DenseQpSolver::KeepForWarmStart(const DenseQp& qp) {
  if (!options_.warm_start) return;
  previous_.assign(active_.begin(), active_.end());
  for (int j = 0; j < q_; ++j) {
    if (active_[j].index >= n_) previous_rows_.row(j) = qp.C.row(active_[j].index - n_);
  }
  hot_startable_ = true;
}

const DenseQpSummary& DenseQpSolver::SolveFactorized(const DenseQp& qp) {
  const Stopwatch clock;
  summary_ = DenseQpSummary{};
  const auto finish = [&](QpStatus status) -> const DenseQpSummary& {
    summary_.status = status;
    summary_.active_constraints = q_;
    y_bound_.setZero();
    y_constraint_.setZero();
    for (int j = 0; j < q_; ++j) {
      const Side& c = active_[j];
      if (c.index < n_) {
        y_bound_[c.index] += c.sign * u_[j];
      } else {
        y_constraint_[c.index - n_] += c.sign * u_[j];
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
      previous_.clear();
    }
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
  MinimiseOnActiveSet(qp);
  summary_.start_active_constraints = q_;
  // A start on a nearly dependent set with huge finite bounds could overflow.
  if (!z_.allFinite()) return reject(QpStatus::kNumericalFailure);

  const double tol = options_.feasibility_tolerance;
  while (true) {
    // The most violated constraint side that is not active.
    Side p{-1, 0.0};
    double worst = -tol;
    for (int i = 0; i < n_; ++i) {
      if (z_[i] - qp.lb[i] < worst && !is_active_[2 * i]) {
        worst = z_[i] - qp.lb[i];
        p = {i, 1.0};
      }
      if (qp.ub[i] - z_[i] < worst && !is_active_[2 * i + 1]) {
        worst = qp.ub[i] - z_[i];
        p = {i, -1.0};
      }
    }
    if (m_ > 0) {
      cz_.noalias() = qp.C * z_;
      for (int i = 0; i < m_; ++i) {
        if (cz_[i] - qp.lc[i] < worst && !is_active_[2 * (n_ + i)]) {
          worst = cz_[i] - qp.lc[i];
          p = {n_ + i, 1.0};
        }
        if (qp.uc[i] - cz_[i] < worst && !is_active_[2 * (n_ + i) + 1]) {
          worst = qp.uc[i] - cz_[i];
          p = {n_ + i, -1.0};
        }
      }
    }
    if (p.index < 0) return finish(QpStatus::kSolved);

    double slack = worst;
    double u_p = 0.0;
    while (true) {
      if (summary_.iterations >= options_.max_iterations) return finish(QpStatus::kMaxIterations);
      ComputeD(qp, p);
      // Primal step direction in the null space of the active constraints, and the dual one.
      step_.noalias() = J_.rightCols(n_ - q_) * d_.tail(n_ - q_);
      r_.head(q_) = R_.topLeftCorner(q_, q_).triangularView<Eigen::Upper>().solve(d_.head(q_));
      double t1 = kInf;
      int drop = -1;
      for (int j = 0; j < q_; ++j) {
        if (r_[j] > 0.0 && u_[j] / r_[j] < t1) {
          t1 = u_[j] / r_[j];
          drop = j;
        }
      }
      const double ns = NormalDotStep(qp, p);
      const bool primal_step = step_.norm() > 1e-14 * (1.0 + d_.norm()) && ns > 0.0;
      const double t2 = primal_step ? -slack / ns : kInf;
      const double t = std::min(t1, t2);
      if (!std::isfinite(t)) return finish(QpStatus::kInfeasible);
      ++summary_.iterations;
      u_.head(q_) -= t * r_.head(q_);
      u_p += t;
      if (!primal_step) {
        DropFromActiveSet(drop);  // dual step only: make room for p
        continue;
      }
      z_ += t * step_;
      if (t2 <= t1) {
        AddToActiveSet(p);
        u_[q_ - 1] = u_p;
        break;
      }
      DropFromActiveSet(drop);
      slack = Slack(qp, p);
    }
    if (!z_.allFinite()) return finish(QpStatus::kNumericalFailure);
  }
}

}  // namespace rotorguard::control
