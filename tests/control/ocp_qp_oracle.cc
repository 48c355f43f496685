#include "ocp_qp_oracle.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

namespace rotorguard::control {

Eigen::MatrixXd RandomMatrix(int r, int c, Rng& rng, double scale) {
  Eigen::MatrixXd m(r, c);
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < c; ++j) m(i, j) = scale * rng.Normal();
  return m;
}

OcpQp RandomOcp(int N, int nx, int nu, std::vector<int> bounded, Rng& rng) {
  OcpQpDims dims{N, nx, nu, bounded};
  OcpQp qp(dims);
  qp.x0 = RandomMatrix(nx, 1, rng, 2.0);
  for (int k = 0; k < N; ++k) {
    qp.A[k] = Eigen::MatrixXd::Identity(nx, nx) + RandomMatrix(nx, nx, rng, 0.15);
    qp.B[k] = RandomMatrix(nx, nu, rng, 0.5);
    qp.c[k] = RandomMatrix(nx, 1, rng, 0.1);
    const Eigen::MatrixXd M = RandomMatrix(nu, nu, rng);
    qp.R[k] = M * M.transpose() + 0.2 * Eigen::MatrixXd::Identity(nu, nu);
    qp.r[k] = RandomMatrix(nu, 1, rng, 0.3);
    qp.u_lower[k].setConstant(-0.6);
    qp.u_upper[k].setConstant(0.6);
  }
  for (int k = 0; k <= N; ++k) {
    const Eigen::MatrixXd M = RandomMatrix(nx, nx, rng);
    qp.Q[k] = M * M.transpose() + 0.1 * Eigen::MatrixXd::Identity(nx, nx);
    qp.q[k] = RandomMatrix(nx, 1, rng, 0.3);
    qp.x_lower[k].setConstant(-1.5);
    qp.x_upper[k].setConstant(1.5);
  }
  return qp;
}

OcpQp OcpPulledAgainstItsStateBounds(int N, int nx, int nu, std::vector<int> bounded, Rng& rng) {
  OcpQp qp = RandomOcp(N, nx, nu, std::move(bounded), rng);
  qp.x0 *= 0.1;
  Eigen::VectorXd target = Eigen::VectorXd::Zero(nx);
  target[0] = 4.0;
  target[3] = -4.0;
  for (int k = 0; k < N; ++k) {
    qp.A[k] = Eigen::MatrixXd::Identity(nx, nx) + 0.02 * (qp.A[k] - Eigen::MatrixXd::Identity(nx, nx));
    qp.B[k] *= 4.0;
    qp.c[k].setZero();
  }
  for (int k = 0; k <= N; ++k) qp.q[k] = -qp.Q[k] * target;
  return qp;
}

int StateBoundsAtTheirLimit(const std::vector<Eigen::VectorXd>& x, const std::vector<int>& bounded) {
  int binding = 0;
  for (std::size_t k = 1; k < x.size(); ++k) {
    for (int b : bounded) binding += std::abs(std::abs(x[k][b]) - 1.5) < 1e-7;
  }
  return binding;
}

void NaiveCondense(const OcpQp& qp, Eigen::MatrixXd* H, Eigen::VectorXd* g, Eigen::MatrixXd* C, Eigen::VectorXd* lc,
                   Eigen::VectorXd* uc) {
  const int N = qp.dims.horizon, nx = qp.dims.nx, nu = qp.dims.nu;
  const int nbx = static_cast<int>(qp.dims.state_bound_index.size());
  Eigen::MatrixXd gamma = Eigen::MatrixXd::Zero(N * nx, N * nu);  // rows: x_1 .. x_N
  Eigen::VectorXd free = Eigen::VectorXd::Zero(N * nx);
  Eigen::VectorXd x = qp.x0;
  for (int k = 0; k < N; ++k) {
    x = qp.A[k] * x + qp.c[k];
    free.segment(k * nx, nx) = x;
    for (int j = 0; j <= k; ++j) {
      Eigen::MatrixXd phi = Eigen::MatrixXd::Identity(nx, nx);
      for (int m = j + 1; m <= k; ++m) phi = qp.A[m] * phi;
      gamma.block(k * nx, j * nu, nx, nu) = phi * qp.B[j];
    }
  }
  Eigen::MatrixXd qbig = Eigen::MatrixXd::Zero(N * nx, N * nx), rbig = Eigen::MatrixXd::Zero(N * nu, N * nu);
  Eigen::VectorXd qvec(N * nx), rvec(N * nu);
  for (int k = 0; k < N; ++k) {
    qbig.block(k * nx, k * nx, nx, nx) = qp.Q[k + 1];
    qvec.segment(k * nx, nx) = qp.q[k + 1];
    rbig.block(k * nu, k * nu, nu, nu) = qp.R[k];
    rvec.segment(k * nu, nu) = qp.r[k];
  }
  *H = gamma.transpose() * qbig * gamma + rbig;
  *g = gamma.transpose() * (qbig * free + qvec) + rvec;
  C->resize(N * nbx, N * nu);
  lc->resize(N * nbx);
  uc->resize(N * nbx);
  for (int k = 0; k < N; ++k) {
    for (int b = 0; b < nbx; ++b) {
      const int i = qp.dims.state_bound_index[b];
      C->row(k * nbx + b) = gamma.row(k * nx + i);
      (*lc)[k * nbx + b] = qp.x_lower[k + 1][b] - free[k * nx + i];
      (*uc)[k * nbx + b] = qp.x_upper[k + 1][b] - free[k * nx + i];
    }
  }
}

int ExpectKktOfTheNaiveCondensing(const OcpQp& qp, const Eigen::VectorXd& u, const Eigen::VectorXd& yu,
                                  const Eigen::VectorXd& yx) {
  const int N = qp.dims.horizon, nu = qp.dims.nu, nbx = static_cast<int>(qp.dims.state_bound_index.size());
  Eigen::MatrixXd H, C;
  Eigen::VectorXd g, lc, uc;
  NaiveCondense(qp, &H, &g, &C, &lc, &uc);
  const Eigen::VectorXd residual = H * u + g - yu - C.transpose() * yx;
  EXPECT_LE(residual.cwiseAbs().maxCoeff(), 1e-8 * (1.0 + g.cwiseAbs().maxCoeff())) << "stationarity";
  const Eigen::VectorXd cu = C * u;
  int active = 0;
  // A side is "at" its bound within kAt; a multiplier above kZero must sit on its side's bound.
  constexpr double kAt = 1e-8, kZero = 1e-9;
  const auto check = [&](double value, double lower, double upper, double y, const std::string& what) {
    EXPECT_GE(value, lower - kAt) << what;
    EXPECT_LE(value, upper + kAt) << what;
    if (y > kZero) {
      EXPECT_NEAR(value, lower, kAt) << what << ": a positive multiplier off the lower bound";
    }
    if (y < -kZero) {
      EXPECT_NEAR(value, upper, kAt) << what << ": a negative multiplier off the upper bound";
    }
    active += std::abs(value - lower) < kAt || std::abs(value - upper) < kAt;
  };
  for (int k = 0; k < N; ++k) {
    for (int i = 0; i < nu; ++i) {
      check(u[k * nu + i], qp.u_lower[k][i], qp.u_upper[k][i], yu[k * nu + i], fmt::format("u_{}[{}]", k, i));
    }
  }
  for (int r = 0; r < N * nbx; ++r) check(cu[r], lc[r], uc[r], yx[r], fmt::format("state bound row {}", r));
  return active;
}

}  // namespace rotorguard::control
