#include "rotorguard/control/position_loop.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"

namespace rotorguard::control {

Vector3 PositionLoop::DesiredThrustVector(const vehicle::VehicleParams& vp, const StateEstimate& est,
                                          const ReferencePoint& ref, double dt) {
  const Vector3 e_p = ref.p_W - est.p_W;
  if (dt > 0.0) {
    integral_ = (integral_ + options_.ki_position.cwiseProduct(e_p) * dt)
                    .cwiseMax(-options_.integral_limit_m_s2)
                    .cwiseMin(options_.integral_limit_m_s2);
  }
  const Vector3 a_cmd = ref.a_W + options_.kp_position.cwiseProduct(e_p) +
                        options_.kd_velocity.cwiseProduct(ref.v_W - est.v_W) + integral_;
  // eq. (1) solved for T z_B: m a = T z_B - R D R' v + m g.
  const Matrix3 R = est.q_WB.normalized().toRotationMatrix();
  Vector3 f = vp.mass_kg * (a_cmd + Vector3(0.0, 0.0, kGravity)) +
              R * vp.rotor_drag_kg_s.cwiseProduct(R.transpose() * est.v_W);
  // Tilt limit: shrink the horizontal part so that the angle to vertical stays below max_tilt.
  f.z() = std::max(f.z(), 0.1 * vp.weight_n());
  const double max_horizontal = f.z() * std::tan(options_.max_tilt_rad);
  const double horizontal = f.head<2>().norm();
  if (horizontal > max_horizontal) f.head<2>() *= max_horizontal / horizontal;
  return f;
}

}  // namespace rotorguard::control
