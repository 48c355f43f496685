#pragma once
/// The reference interface every trajectory implements (simple references, planned trajectories).
#include "rotorguard/core/types.h"

namespace rotorguard {

/// Flat outputs and their derivatives at one instant.
struct ReferencePoint {
  Vector3 p_W = Vector3::Zero();
  Vector3 v_W = Vector3::Zero();
  Vector3 a_W = Vector3::Zero();
  Vector3 j_W = Vector3::Zero();  ///< jerk
  double yaw = 0.0;               ///< [rad]
  double yaw_rate = 0.0;          ///< [rad/s]
  /// Snap (the fourth derivative): the tilt's angular acceleration follows from it. Zero where a
  /// reference does not define it (piecewise-constant accelerations, fixed points).
  Vector3 s_W = Vector3::Zero();
};

/// A reference defined for all t >= 0 (it holds its final point after `duration()`).
class ReferenceTrajectory {
 public:
  virtual ~ReferenceTrajectory() = default;
  /// Reference at time t [s] since the start of the mission.
  [[nodiscard]] virtual ReferencePoint Evaluate(double t) const = 0;
  /// Time after which the reference is constant [s] (infinity for periodic references).
  [[nodiscard]] virtual double duration() const = 0;
};

/// A reference started at `t0`: Evaluate(t) is the inner reference's Evaluate(t - t0).
class TimeShiftedReference final : public ReferenceTrajectory {
 public:
  TimeShiftedReference(const ReferenceTrajectory& inner, double t0) : inner_(inner), t0_(t0) {}
  [[nodiscard]] ReferencePoint Evaluate(double t) const override { return inner_.Evaluate(t - t0_); }
  [[nodiscard]] double duration() const override { return t0_ + inner_.duration(); }

 private:
  const ReferenceTrajectory& inner_;
  double t0_;
};

}  // namespace rotorguard
