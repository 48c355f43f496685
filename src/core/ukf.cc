#include "rotorguard/core/ukf.h"

#include <cmath>

#include <Eigen/Cholesky>

#include "rotorguard/core/error.h"

namespace rotorguard {

void UkfOptions::Validate(int n) const {
  if (!(alpha > 0.0 && alpha <= 1.0)) ThrowValidation("UkfOptions", "alpha", alpha, "in (0, 1]");
  if (!(beta >= 0.0 && std::isfinite(beta))) ThrowValidation("UkfOptions", "beta", beta, ">= 0");
  if (!(n + kappa > 0.0 && std::isfinite(kappa))) ThrowValidation("UkfOptions", "kappa", kappa, "n + kappa > 0");
}

UnscentedKalmanFilter::UnscentedKalmanFilter(const Vector& x0, const Matrix& P0, const UkfOptions& options)
    : options_(options), x_(x0), P_(P0) {
  const int n = static_cast<int>(x0.size());
  options_.Validate(n);
  if (P0.rows() != n || P0.cols() != n || !P0.allFinite() || Eigen::LLT<Matrix>(P0).info() != Eigen::Success) {
    ThrowValidation("UnscentedKalmanFilter", "P0", "(not an n x n positive definite matrix)", "a covariance > 0");
  }
  lambda_ = options_.alpha * options_.alpha * (n + options_.kappa) - n;
  wm_ = Vector::Constant(2 * n + 1, 0.5 / (n + lambda_));
  wc_ = wm_;
  wm_[0] = lambda_ / (n + lambda_);
  wc_[0] = wm_[0] + (1.0 - options_.alpha * options_.alpha + options_.beta);
}

bool UnscentedKalmanFilter::SigmaPoints(Matrix* points) const {
  const Eigen::Index n = x_.size();
  const Eigen::LLT<Matrix> llt((n + lambda_) * P_);
  if (llt.info() != Eigen::Success) return false;
  const Matrix L = llt.matrixL();
  points->resize(n, 2 * n + 1);
  points->col(0) = x_;
  for (Eigen::Index i = 0; i < n; ++i) {
    points->col(1 + i) = x_ + L.col(i);
    points->col(1 + n + i) = x_ - L.col(i);
  }
  return true;
}

bool UnscentedKalmanFilter::Predict(const Transition& f, const Matrix& Q) {
  Matrix X;
  if (!SigmaPoints(&X)) return false;
  Matrix Y(X.rows(), X.cols());
  for (Eigen::Index i = 0; i < X.cols(); ++i) Y.col(i) = f(X.col(i));
  if (!Y.allFinite()) return false;
  const Vector mean = Y * wm_;
  const Matrix D = Y.colwise() - mean;
  Matrix P = D * wc_.asDiagonal() * D.transpose() + Q;
  x_ = mean;
  P_ = 0.5 * (P + P.transpose());
  return true;
}

bool UnscentedKalmanFilter::Update(const Measurement& h, const Vector& z, const Matrix& R) {
  if (!z.allFinite()) return false;
  Matrix X;
  if (!SigmaPoints(&X)) return false;
  Matrix Z(z.size(), X.cols());
  for (Eigen::Index i = 0; i < X.cols(); ++i) Z.col(i) = h(X.col(i));
  if (!Z.allFinite()) return false;
  const Vector z_hat = Z * wm_;
  const Matrix dZ = Z.colwise() - z_hat, dX = X.colwise() - x_;
  const Matrix Pzz = dZ * wc_.asDiagonal() * dZ.transpose() + R;
  const Matrix Pxz = dX * wc_.asDiagonal() * dZ.transpose();
  const Eigen::LLT<Matrix> llt(Pzz);
  if (llt.info() != Eigen::Success) return false;
  const Matrix K = llt.solve(Pxz.transpose()).transpose();
  x_ += K * (z - z_hat);
  const Matrix P = P_ - K * Pzz * K.transpose();
  P_ = 0.5 * (P + P.transpose());
  return true;
}

}  // namespace rotorguard
