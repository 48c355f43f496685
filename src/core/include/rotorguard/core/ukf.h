#pragma once
/// The unscented Kalman filter (Julier and Uhlmann, "A new extension of the Kalman filter to
/// nonlinear systems", AeroSense 1997; paper 004's reference [13]) with additive process and
/// measurement noise and the scaled sigma points of Wan and van der Merwe (α, β, κ). Small
/// dynamic-size states: paper 004's loss-of-effectiveness estimator has seven.
#include <functional>

#include <Eigen/Core>

namespace rotorguard {

struct UkfOptions {
  double alpha = 1.0;  ///< spread of the sigma points, in (0, 1]
  double beta = 2.0;   ///< prior knowledge of the distribution (2: Gaussian), >= 0
  double kappa = 0.0;  ///< secondary scaling, n + κ > 0
  void Validate(int n) const;
};

class UnscentedKalmanFilter {
 public:
  using Vector = Eigen::VectorXd;
  using Matrix = Eigen::MatrixXd;
  /// x_{k+1} = f(x_k) + process noise.
  using Transition = std::function<Vector(const Vector&)>;
  /// z = h(x) + measurement noise.
  using Measurement = std::function<Vector(const Vector&)>;

  /// Throws ValidationError for invalid options or a covariance that is not positive definite.
  UnscentedKalmanFilter(const Vector& x0, const Matrix& P0, const UkfOptions& options = {});

  /// Propagates the mean and covariance through f and adds Q. Returns false (and keeps the
  /// previous estimate) when P lost positive definiteness or f returned non-finite values.
  bool Predict(const Transition& f, const Matrix& Q);
  /// Corrects with the measurement z of covariance R. Returns false (state unchanged) on a
  /// non-finite measurement or an innovation covariance that cannot be factorised.
  bool Update(const Measurement& h, const Vector& z, const Matrix& R);

  const Vector& x() const { return x_; }
  const Matrix& P() const { return P_; }
  /// Replaces the state (a clamp to the physical range after an update); P is kept.
  void set_x(const Vector& x) { x_ = x; }

 private:
  /// Sigma points of (x_, P_) as columns; false when P is not positive definite.
  bool SigmaPoints(Matrix* points) const;

  UkfOptions options_;
  Vector x_, wm_, wc_;
  Matrix P_;
  double lambda_ = 0.0;
};

}  // namespace rotorguard
