#pragma once
/// The outer position loop shared by the cascaded controllers: a PID on position with the
/// reference's acceleration as feedforward, solved through eq. (1) of paper 000 for the thrust
/// vector (gravity and the model's rotor drag compensated), with its tilt limited.
#include <numbers>
#include <string>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::control {

struct PositionLoopOptions {
  Vector3 kp_position = Vector3(9.0, 9.0, 12.0);  ///< position gain [1/s^2], >= 0
  Vector3 kd_velocity = Vector3(6.0, 6.0, 7.0);   ///< velocity gain [1/s], >= 0
  Vector3 ki_position = Vector3(1.0, 1.0, 2.0);   ///< integral gain [1/s^3], >= 0
  double integral_limit_m_s2 = 2.0;   ///< clamp on the integral's acceleration [m/s^2], >= 0
  double max_tilt_rad = 0.7;          ///< thrust vector tilt limit [rad], in (0, pi/2)
  /// The keys of this struct in config files (core/config_schema.h), within those of the
  /// controller that flies it, whose Validate() checks their ranges (max_tilt_rad below π/2:
  /// tan() of it is infinite).
  template <typename Archive>
  void Serialize(Archive* a) {
    // Gains a hundred times the defaults: beyond them the loop outruns any control rate.
    a->Visit("kp_position", &kp_position, {.meaning = "position gain [1/s²]", .min = 0.0, .max = 1000.0});
    a->Visit("kd_velocity", &kd_velocity, {.meaning = "velocity gain [1/s]", .min = 0.0, .max = 1000.0});
    a->Visit("ki_position", &ki_position, {.meaning = "integral gain [1/s³]", .min = 0.0, .max = 1000.0});
    a->Visit("integral_limit_m_s2", &integral_limit_m_s2,
             {.meaning = "clamp on the integral's acceleration [m/s²]", .min = 0.0, .max = kMaxAccelerationMS2});
    a->Visit("max_tilt_rad", &max_tilt_rad,
             {.meaning = "tilt limit of the thrust vector [rad]",
              .max = std::numbers::pi / 2.0,
              .positive = true,
              .open_max = true});
  }
};

class PositionLoop {
 public:
  explicit PositionLoop(const PositionLoopOptions& options) : options_(options) {}
  /// The desired thrust vector (world frame) for the estimate and reference; `dt` [s] advances the
  /// integral (0 leaves it).
  Vector3 DesiredThrustVector(const vehicle::VehicleParams& vehicle, const StateEstimate& estimate,
                              const ReferencePoint& reference, double dt);
  void Reset() { integral_.setZero(); }

 private:
  PositionLoopOptions options_;
  Vector3 integral_ = Vector3::Zero();
};

}  // namespace rotorguard::control
