#pragma once
/// Basic types shared by every module: fixed-capacity rotor vectors (no heap allocation on the
/// control path) and integer simulation time.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>

namespace rotorguard {

/// Largest rotor count of any vehicle, assemblies of modular units included (9 units x 4 rotors
/// fits with room). Vectors sized by rotor count use this as a static capacity so that control-rate
/// code never allocates.
inline constexpr int kMaxRotors = 64;

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using Quaternion = Eigen::Quaterniond;
/// Per-rotor quantity (thrust, speed, command), dynamic size up to kMaxRotors, stored inline.
using RotorVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRotors, 1>;
/// Effectiveness matrix: rows [T; tau_x; tau_y; tau_z], one column per rotor (paper 000, eq. 5).
using EffectivenessMatrix = Eigen::Matrix<double, 4, Eigen::Dynamic, 0, 4, kMaxRotors>;
/// Pseudo-inverse of an effectiveness matrix: one row per rotor.
using AllocationMatrix = Eigen::Matrix<double, Eigen::Dynamic, 4, 0, kMaxRotors, 4>;

/// Simulation time in integer nanoseconds: no drift over long runs. Seconds (double) at interfaces.
using TimeNs = std::int64_t;
inline constexpr TimeNs kNanosPerSecond = 1'000'000'000;
inline constexpr double ToSeconds(TimeNs t) { return static_cast<double>(t) * 1e-9; }
/// A time in nanoseconds as TimeNs, truncated toward zero as a cast does: beyond its range (about
/// ±292 years) it saturates, and NaN counts as "never", as converting such a double is undefined.
inline TimeNs SaturatedNs(double ns) {
  if (!(ns < 0x1p63)) return std::numeric_limits<TimeNs>::max();
  if (!(ns >= -0x1p63)) return std::numeric_limits<TimeNs>::min();
  return static_cast<TimeNs>(ns);
}
/// Rounds to the nearest nanosecond (SaturatedNs beyond the range).
inline TimeNs FromSeconds(double s) { return SaturatedNs(s * 1e9 + (s >= 0 ? 0.5 : -0.5)); }
/// Period in nanoseconds of a rate in Hz, rounded to the nearest nanosecond.
inline TimeNs PeriodFromRate(double rate_hz) { return FromSeconds(1.0 / rate_hz); }

/// Standard gravity [m/s^2]; the world z axis points up, gravity is (0, 0, -kGravity).
inline constexpr double kGravity = 9.81;

}  // namespace rotorguard
