#include "rotorguard/planning/minco.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rotorguard::planning {

namespace {

constexpr int kC = MinimumJerkTrajectory::kCoefficients;

}  // namespace

namespace {

constexpr auto& kFactor = MinimumJerkTrajectory::kDerivativeFactor;

}  // namespace

Eigen::Matrix<double, 1, kC> MinimumJerkTrajectory::Basis(double t, int order) {
  Eigen::Matrix<double, 1, kC> b = Eigen::Matrix<double, 1, kC>::Zero();
  double power = 1.0;
  for (int k = order; k < kC; ++k) {
    b(k) = kFactor[order][k] * power;
    power *= t;
  }
  return b;
}

Eigen::Matrix<double, 5, kC> MinimumJerkTrajectory::BasisRows(double t) {
  double power[kC];
  power[0] = 1.0;
  for (int k = 1; k < kC; ++k) power[k] = power[k - 1] * t;
  Eigen::Matrix<double, 5, kC> b = Eigen::Matrix<double, 5, kC>::Zero();
  for (int order = 0; order < 5; ++order) {
    for (int k = order; k < kC; ++k) b(order, k) = kFactor[order][k] * power[k - order];
  }
  return b;
}

void MinimumJerkTrajectory::Clear() {
  durations_.resize(0);
  coefficients_.resize(0, 3);
}

bool MinimumJerkTrajectory::Build(const PvaState& head, const PvaState& tail, const Eigen::Matrix3Xd& waypoints,
                                  const Eigen::VectorXd& durations) {
  const int m = static_cast<int>(durations.size());
  if (m < 1 || waypoints.cols() != m - 1 || !head.allFinite() || !tail.allFinite() || !waypoints.allFinite() ||
      !durations.allFinite() || (durations.array() <= 0.0).any()) {
    Clear();
    return false;
  }
  // Rows, ordered so that the matrix has 4 sub- and 3 super-diagonals and factors without
  // pivoting (every leading block is nonsingular for positive durations): the head (p, v, a of
  // piece 0 at 0); per junction i, piece i's position at T_i equals q_i, continuity of the first
  // and second derivatives (piece i at T_i minus piece i + 1 at 0), piece i + 1's position at 0
  // equals q_i, continuity of the third and fourth; the tail (p, v, a of the last piece at its
  // end). Columns: coefficient k of piece i at 6i + k.
  // The system and its right-hand side (solved in place into the coefficients) reuse the last
  // build's storage: an optimiser rebuilds the same size hundreds of times a solve.
  const int n = kC * m;
  BandedMatrix& a = system_;
  a.Reset(n, 4, 3);
  Eigen::MatrixX3d& b = coefficients_;
  b.setZero(n, 3);
  const double factorial[] = {1.0, 1.0, 2.0, 6.0, 24.0};
  for (int d = 0; d < 3; ++d) {
    a(d, d) = factorial[d];
    b.row(d) = head.col(d).transpose();
  }
  for (int i = 0; i + 1 < m; ++i) {
    const int r = kC * i + 3, c = kC * i;
    const double t = durations(i);
    const Eigen::Matrix<double, 1, kC> position = Basis(t, 0);
    for (int k = 0; k < kC; ++k) a(r, c + k) = position(k);
    b.row(r) = waypoints.col(i).transpose();
    a(r + 3, c + kC) = 1.0;
    b.row(r + 3) = waypoints.col(i).transpose();
    for (int d = 1; d < 5; ++d) {
      const int row = r + (d < 3 ? d : d + 1);
      const Eigen::Matrix<double, 1, kC> basis = Basis(t, d);
      for (int k = d; k < kC; ++k) a(row, c + k) = basis(k);
      a(row, c + kC + d) = -factorial[d];
    }
  }
  const int last = kC * (m - 1);
  for (int d = 0; d < 3; ++d) {
    const Eigen::Matrix<double, 1, kC> row = Basis(durations(m - 1), d);
    for (int k = d; k < kC; ++k) a(n - 3 + d, last + k) = row(k);
    b.row(n - 3 + d) = tail.col(d).transpose();
  }
  if (!a.Factorize()) {
    Clear();
    return false;
  }
  a.Solve(b);
  if (!b.allFinite()) {
    Clear();
    return false;
  }
  durations_ = durations;
  total_duration_ = durations.sum();
  return true;
}

bool MinimumJerkTrajectory::BuildRestToRest(const Eigen::Ref<const Eigen::Matrix3Xd>& points,
                                            const Eigen::VectorXd& durations) {
  durations_.resize(0);
  coefficients_.resize(0, 3);
  system_ = BandedMatrix(0, 4, 3);  // no system: the pieces do not come from Build's
  const int m = static_cast<int>(durations.size());
  if (m < 1 || points.cols() != m + 1 || !points.allFinite() || !durations.allFinite() || (durations.array() <= 0.0).any()) {
    return false;
  }
  // p(t) = a + (b - a) (10 s^3 - 15 s^4 + 6 s^5), s = t / T: in powers of t, c3 = 10 d / T^3,
  // c4 = -15 d / T^4, c5 = 6 d / T^5 with d = b - a.
  coefficients_.setZero(kC * m, 3);
  for (int i = 0; i < m; ++i) {
    const double t = durations(i);
    const Eigen::RowVector3d d = (points.col(i + 1) - points.col(i)).transpose();
    coefficients_.row(kC * i) = points.col(i).transpose();
    coefficients_.row(kC * i + 3) = (10.0 / (t * t * t)) * d;
    coefficients_.row(kC * i + 4) = (-15.0 / (t * t * t * t)) * d;
    coefficients_.row(kC * i + 5) = (6.0 / (t * t * t * t * t)) * d;
  }
  durations_ = durations;
  total_duration_ = durations.sum();
  return true;
}

double MinimumJerkTrajectory::Energy() const {
  // The integral over [0, T] of |6 c3 + 24 c4 t + 60 c5 t^2|^2.
  double e = 0.0;
  for (int i = 0; i < pieces(); ++i) {
    const double t = durations_(i), t2 = t * t, t3 = t2 * t, t4 = t3 * t, t5 = t4 * t;
    const auto c3 = coefficients_.row(kC * i + 3), c4 = coefficients_.row(kC * i + 4), c5 = coefficients_.row(kC * i + 5);
    e += 36.0 * c3.squaredNorm() * t + 144.0 * c3.dot(c4) * t2 + 192.0 * c4.squaredNorm() * t3 +
         240.0 * c3.dot(c5) * t3 + 720.0 * c4.dot(c5) * t4 + 720.0 * c5.squaredNorm() * t5;
  }
  return e;
}

void MinimumJerkTrajectory::EnergyPartials(Eigen::MatrixX3d* d_coefficients, Eigen::VectorXd* d_durations) const {
  d_coefficients->setZero(coefficients_.rows(), 3);
  d_durations->resize(pieces());
  for (int i = 0; i < pieces(); ++i) {
    const double t = durations_(i), t2 = t * t, t3 = t2 * t, t4 = t3 * t, t5 = t4 * t;
    const auto c3 = coefficients_.row(kC * i + 3), c4 = coefficients_.row(kC * i + 4), c5 = coefficients_.row(kC * i + 5);
    d_coefficients->row(kC * i + 3) = 72.0 * c3 * t + 144.0 * c4 * t2 + 240.0 * c5 * t3;
    d_coefficients->row(kC * i + 4) = 144.0 * c3 * t2 + 384.0 * c4 * t3 + 720.0 * c5 * t4;
    d_coefficients->row(kC * i + 5) = 240.0 * c3 * t3 + 720.0 * c4 * t4 + 1440.0 * c5 * t5;
    (*d_durations)(i) = PieceDerivative(i, t, 3).squaredNorm();  // d/dT of the integral up to T
  }
}

void MinimumJerkTrajectory::PropagateGradient(Eigen::MatrixX3d* d_coefficients,
                                              const Eigen::VectorXd& d_durations_partial, Eigen::Matrix3Xd* d_waypoints,
                                              Eigen::VectorXd* d_durations) const {
  // A c = b(q): dJ/db = A^-T dJ/dc (the adjoint, G), and b holds q_i in rows 6i + 3 and 6i + 6. A depends on
  // T_i through piece i's rows at its end: dc/dT_i = -A^-1 (dA/dT_i) c, so dJ/dT_i loses
  // G . (dA/dT_i c), where (dA/dT_i c) in a row that evaluates derivative d of piece i at T_i is
  // derivative d + 1 there.
  const int m = pieces();
  if (system_.size() != kC * m) {
    throw std::logic_error("MinimumJerkTrajectory::PropagateGradient: the trajectory does not come from Build");
  }
  Eigen::MatrixX3d& g = *d_coefficients;
  system_.SolveTransposed(g);
  d_waypoints->resize(3, m - 1);
  *d_durations = d_durations_partial;
  for (int i = 0; i + 1 < m; ++i) {
    const int r = kC * i + 3;
    d_waypoints->col(i) = (g.row(r) + g.row(r + 3)).transpose();  // q_i enters two rows
    const double t = durations_(i);
    double dt = g.row(r).dot(PieceDerivative(i, t, 1).transpose());
    for (int d = 1; d < 5; ++d) dt += g.row(r + (d < 3 ? d : d + 1)).dot(PieceDerivative(i, t, d + 1).transpose());
    (*d_durations)(i) -= dt;
  }
  const int n = kC * m;
  double dt = 0.0;
  for (int d = 0; d < 3; ++d) dt += g.row(n - 3 + d).dot(PieceDerivative(m - 1, durations_(m - 1), d + 1).transpose());
  (*d_durations)(m - 1) -= dt;
}

Vector3 MinimumJerkTrajectory::PieceDerivative(int piece, double t, int order) const {
  return (Basis(t, order) * coefficients_.middleRows<kC>(kC * piece)).transpose();
}

double MinimumJerkTrajectory::MaxNorm(int order, int samples_per_piece) const {
  double m = 0.0;
  for (int i = 0; i < pieces(); ++i) {
    for (int j = 0; j <= samples_per_piece; ++j) {
      m = std::max(m, PieceDerivative(i, durations_(i) * j / samples_per_piece, order).norm());
    }
  }
  return m;
}

ReferencePoint MinimumJerkTrajectory::Evaluate(double t) const {
  ReferencePoint r;
  r.yaw = yaw_;
  if (empty()) return r;
  double local = t - start_time_;
  if (local >= total_duration_) {  // the final position, at rest
    r.p_W = PieceDerivative(pieces() - 1, durations_(pieces() - 1), 0);
    return r;
  }
  local = std::max(local, 0.0);
  int i = 0;
  while (i + 1 < pieces() && local > durations_(i)) local -= durations_(i++);
  local = std::min(local, durations_(i));
  r.p_W = PieceDerivative(i, local, 0);
  r.v_W = PieceDerivative(i, local, 1);
  r.a_W = PieceDerivative(i, local, 2);
  r.j_W = PieceDerivative(i, local, 3);
  r.s_W = PieceDerivative(i, local, 4);
  return r;
}

}  // namespace rotorguard::planning
