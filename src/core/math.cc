#include "rotorguard/core/math.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rotorguard {

Matrix3 ExpSO3(const Vector3& theta) {
  // R = I + a K + b K^2, K = Skew(theta).
  double a, b;
  internal::RodriguesCoefficients(theta.squaredNorm(), &a, &b);
  const Matrix3 K = Skew(theta);
  return Matrix3::Identity() + a * K + b * (K * K);
}

Vector3 LogSO3(const Quaternion& q) {
  // q = (cos(θ/2), sin(θ/2) u): θ u = 2 atan2(|v|, w) v / |v|, with w >= 0 for the shortest arc.
  const double sign = q.w() < 0.0 ? -1.0 : 1.0;
  const Vector3 v = sign * q.vec();
  const double s = v.norm(), w = sign * q.w();
  // Below 1e-6 rad atan2(s, w) / s = 1 / w to double precision.
  const double scale = s < 1e-6 ? 2.0 / w : 2.0 * std::atan2(s, w) / s;
  return scale * v;
}

Matrix3 InverseRightJacobianSO3(const Vector3& theta) {
  // J_r⁻¹ = I + ½ [θ]× + (1/t² − (1 + cos t) / (2 t sin t)) [θ]×², t = |θ|; below 0.05 rad the
  // coefficient's series 1/12 + t²/720 + t⁴/30240 (the next term is below 1e-14).
  const double t2 = theta.squaredNorm();
  double c;
  if (t2 < 0.05 * 0.05) {
    c = 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0;
  } else {
    const double t = std::sqrt(t2);
    c = 1.0 / t2 - (1.0 + std::cos(t)) / (2.0 * t * std::sin(t));
  }
  const Matrix3 K = Skew(theta);
  return Matrix3::Identity() + 0.5 * K + c * K * K;
}

void SinCosOfTurns(double u, double* sin_out, double* cos_out) {
  // u = j / 4 + f with j the nearest quarter and |f| <= 1/8 (both exact: 4 u - j is a difference
  // of nearby doubles), so the angle is j quarter turns plus r = 2 pi f, |r| <= pi / 4, where
  // the series below stop at r^17 and r^18 (the next terms are below 1e-19).
  const double turns4 = 4.0 * (u - std::floor(u));
  const double quarters = std::nearbyint(turns4);
  const double r = (0.5 * std::numbers::pi) * (turns4 - quarters);
  const double r2 = r * r;
  // Horner in r^2 with coefficients (-1)^k / (2k+1)! and (-1)^k / (2k)!.
  double sp = 1.0 / 355687428096000.0;  // 1/17!
  for (const double c : {-1.0 / 1307674368000.0, 1.0 / 6227020800.0, -1.0 / 39916800.0, 1.0 / 362880.0, -1.0 / 5040.0,
                         1.0 / 120.0, -1.0 / 6.0, 1.0}) {
    sp = sp * r2 + c;
  }
  double cp = -1.0 / 6402373705728000.0;  // -1/18!
  for (const double c : {1.0 / 20922789888000.0, -1.0 / 87178291200.0, 1.0 / 479001600.0, -1.0 / 3628800.0,
                         1.0 / 40320.0, -1.0 / 720.0, 1.0 / 24.0, -0.5, 1.0}) {
    cp = cp * r2 + c;
  }
  const double sr = sp * r;
  // Add j quarter turns: (sin, cos) -> (cos, -sin) per quarter, selected without branches (the
  // quadrant of successive pulses is what a branch predictor cannot guess).
  const int j = static_cast<int>(quarters) & 3;
  const bool odd = (j & 1) != 0, back = (j & 2) != 0;
  const double s = odd ? cp : sr, c = odd ? -sr : cp;
  *sin_out = back ? -s : s;
  *cos_out = back ? -c : c;
}

Matrix3 Skew(const Vector3& a) {
  Matrix3 s;
  s << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return s;
}

Eigen::Vector4d QuaternionDerivative(const Quaternion& q, const Vector3& w) {
  // 0.5 * q (x) [0, w], written out (Hamilton product), as (w, x, y, z).
  return 0.5 * Eigen::Vector4d(-q.x() * w.x() - q.y() * w.y() - q.z() * w.z(),
                               q.w() * w.x() + q.y() * w.z() - q.z() * w.y(),
                               q.w() * w.y() - q.x() * w.z() + q.z() * w.x(),
                               q.w() * w.z() + q.x() * w.y() - q.y() * w.x());
}

double YawOf(const Quaternion& q) {
  const Vector3 x_W = q * Vector3::UnitX();
  return std::atan2(x_W.y(), x_W.x());
}

double TiltOf(const Quaternion& q) {
  const Vector3 z_W = q * Vector3::UnitZ();
  return std::acos(std::clamp(z_W.z(), -1.0, 1.0));
}

Quaternion QuaternionFromYaw(double yaw) {
  return Quaternion(std::cos(0.5 * yaw), 0.0, 0.0, std::sin(0.5 * yaw));
}

double WrapAngle(double a) {
  a = std::remainder(a, 2.0 * std::numbers::pi);
  return a <= -std::numbers::pi ? a + 2.0 * std::numbers::pi : a;
}

}  // namespace rotorguard
