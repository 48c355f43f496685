#include "rotorguard/core/ukf.h"

#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "rotorguard/core/error.h"

namespace rotorguard {
namespace {

// On a linear system the unscented transform is exact: the UKF must reproduce the Kalman filter
// (the independent truth, written out here) step for step, for any admissible scaling.
TEST(UnscentedKalmanFilter, EqualsTheKalmanFilterOnALinearSystem) {
  std::mt19937 rng(5);
  std::normal_distribution<double> N(0.0, 1.0);
  const int n = 5, m = 3;
  Eigen::MatrixXd A(n, n), H(m, n), Cq(n, n), Cr(m, m);
  for (int i = 0; i < n * n; ++i) A(i) = 0.3 * N(rng);
  A += Eigen::MatrixXd::Identity(n, n);
  for (int i = 0; i < m * n; ++i) H(i) = N(rng);
  for (int i = 0; i < n * n; ++i) Cq(i) = 0.1 * N(rng);
  for (int i = 0; i < m * m; ++i) Cr(i) = 0.2 * N(rng);
  const Eigen::MatrixXd Q = Cq * Cq.transpose() + 1e-3 * Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd R = Cr * Cr.transpose() + 1e-2 * Eigen::MatrixXd::Identity(m, m);
  for (const UkfOptions& o : {UkfOptions{1.0, 2.0, 0.0}, UkfOptions{0.5, 2.0, 1.0}, UkfOptions{1.0, 0.0, 3.0 - n + 0.5}}) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    Eigen::MatrixXd P = Eigen::MatrixXd::Identity(n, n);
    UnscentedKalmanFilter ukf(x, P, o);
    for (int k = 0; k < 20; ++k) {
      Eigen::VectorXd z(m);
      for (int i = 0; i < m; ++i) z[i] = N(rng);
      // Kalman filter.
      x = A * x;
      P = A * P * A.transpose() + Q;
      const Eigen::MatrixXd S = H * P * H.transpose() + R;
      const Eigen::MatrixXd K = P * H.transpose() * S.inverse();
      x += K * (z - H * x);
      P = (Eigen::MatrixXd::Identity(n, n) - K * H) * P;
      // UKF.
      ASSERT_TRUE(ukf.Predict([&](const Eigen::VectorXd& s) { return Eigen::VectorXd(A * s); }, Q));
      ASSERT_TRUE(ukf.Update([&](const Eigen::VectorXd& s) { return Eigen::VectorXd(H * s); }, z, R));
      EXPECT_LT((ukf.x() - x).cwiseAbs().maxCoeff(), 1e-9) << k;
      EXPECT_LT((ukf.P() - P).cwiseAbs().maxCoeff(), 1e-9) << k;
    }
  }
}

TEST(UnscentedKalmanFilter, RejectsBadInputsAndKeepsItsState) {
  EXPECT_THROW(UnscentedKalmanFilter(Eigen::VectorXd::Zero(2), -Eigen::MatrixXd::Identity(2, 2)), ValidationError);
  EXPECT_THROW(UnscentedKalmanFilter(Eigen::VectorXd::Zero(2), Eigen::MatrixXd::Identity(2, 2), UkfOptions{0.0, 2.0, 0.0}),
               ValidationError);
  UnscentedKalmanFilter ukf(Eigen::VectorXd::Ones(2), Eigen::MatrixXd::Identity(2, 2));
  const auto id = [](const Eigen::VectorXd& s) { return s; };
  Eigen::VectorXd z(2);
  z << std::nan(""), 0.0;
  EXPECT_FALSE(ukf.Update(id, z, Eigen::MatrixXd::Identity(2, 2)));
  EXPECT_FALSE(ukf.Predict([](const Eigen::VectorXd& s) { return Eigen::VectorXd(s * std::nan("")); },
                           Eigen::MatrixXd::Identity(2, 2)));
  EXPECT_EQ(ukf.x(), Eigen::VectorXd::Ones(2));
}

}  // namespace
}  // namespace rotorguard
