#pragma once
/// Rotation helpers. Quaternions are Hamilton, body-to-world (q_WB), stored w,x,y,z.
#include <cmath>

#include "rotorguard/core/types.h"

namespace rotorguard {

/// Skew-symmetric matrix: Skew(a) * b == a.cross(b).
Matrix3 Skew(const Vector3& a);

/// The rotation matrix of a rotation vector (SO(3) exponential, Rodrigues). Below 0.05 rad it
/// takes a series instead of trigonometric calls, exact to double precision there.
Matrix3 ExpSO3(const Vector3& theta);
/// The rotation vector of a unit quaternion (SO(3) logarithm), the shortest arc: |result| <= pi.
Vector3 LogSO3(const Quaternion& q);
/// The inverse of SO(3)'s right Jacobian at θ: Log(Exp(θ) Exp(δ)) ≈ θ + J_r⁻¹(θ) δ for a small δ
/// (|θ| < π). A manifold filter's prior term on x ⊟ x̂ needs it when the iterate x has moved.
Matrix3 InverseRightJacobianSO3(const Vector3& theta);
namespace internal {
/// a = sin|θ| / |θ| and b = (1 - cos|θ|) / |θ|^2 of Rodrigues' formula from t2 = |θ|^2; below
/// 0.05 rad the series to |θ|^6, which leaves terms below 1e-16.
inline void RodriguesCoefficients(double t2, double* a, double* b) {
  if (t2 < 0.05 * 0.05) {
    *a = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0));
    *b = 0.5 * (1.0 - t2 / 12.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0)));
  } else {
    const double angle = std::sqrt(t2);
    *a = std::sin(angle) / angle;
    *b = (1.0 - std::cos(angle)) / t2;
  }
}
}  // namespace internal

/// ExpSO3(theta) * v, without forming the matrix (Rodrigues' formula on the vector): the deskewer
/// rotates every LiDAR point by one, over at most an IMU period (within the series). Inline: in
/// the deskewer's loop over a frame's points the calls' series then overlap.
inline Vector3 ExpSO3Times(const Vector3& theta, const Vector3& v) {
  // R v = v + a θ x v + b θ x (θ x v).
  double a, b;
  internal::RodriguesCoefficients(theta.squaredNorm(), &a, &b);
  const Vector3 c = theta.cross(v);
  return v + a * c + b * theta.cross(c);
}

/// sin and cos of the angle 2 pi u, u in turns, finite (any value; exact reduction to [0, 1)).
/// Reduced to a quarter turn exactly in turns, then Taylor series: within 2 eps max(1, 2 pi u)
/// of std::sin and std::cos of 2 pi u (absolute), and cheaper than the C library's sincos, which
/// switches the rounding mode on every call (the LiDAR simulator evaluates one per pulse).
void SinCosOfTurns(double u, double* sin_out, double* cos_out);

/// Time derivative of q_WB for body rates w_B: q_dot = 0.5 * q (x) [0, w_B] (paper 000, eq. 2).
Eigen::Vector4d QuaternionDerivative(const Quaternion& q_WB, const Vector3& w_B);

/// Yaw angle of the body x axis projected on the world xy plane [rad].
double YawOf(const Quaternion& q_WB);

/// Angle between the body z axis and the world z axis [rad] (0 when level).
double TiltOf(const Quaternion& q_WB);

/// Rotation about the world z axis by `yaw` [rad].
Quaternion QuaternionFromYaw(double yaw);

/// Wraps an angle to (-pi, pi].
double WrapAngle(double a);

/// True when every coefficient is finite.
template <typename Derived>
bool AllFinite(const Eigen::MatrixBase<Derived>& m) {
  return m.allFinite();
}

}  // namespace rotorguard
