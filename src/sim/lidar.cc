#include "rotorguard/sim/lidar.h"

#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/core/math.h"

namespace rotorguard::sim {

void LidarOptions::Validate() const {
  CheckDeclaredRanges("LidarOptions", *this);
  // The rules between keys.
  if (!(max_range_m > min_range_m)) {
    ThrowValidation("LidarOptions", "max_range_m", max_range_m,
                    fmt::format("a range above min_range_m = {}", min_range_m));
  }
  if (!(max_elevation_rad > min_elevation_rad)) {
    ThrowValidation("LidarOptions", "max_elevation_rad", max_elevation_rad,
                    fmt::format("an angle above min_elevation_rad = {}", min_elevation_rad));
  }
  // The truth side's: a rotation (any scale) and a clock offset well within a frame.
  if (!rotation.coeffs().allFinite() || rotation.norm() < 1e-6) {
    ThrowValidation("LidarOptions", "rotation", "(zero or non-finite)", "a finite non-zero quaternion");
  }
  if (!std::isfinite(clock_offset_s) || std::abs(clock_offset_s) >= 0.5 / frame_rate_hz) {
    ThrowValidation("LidarOptions", "clock_offset_s", clock_offset_s,
                    fmt::format("an offset of less than half a frame, {:g} s", 0.5 / frame_rate_hz));
  }
}

LidarPattern::LidarPattern(const LidarOptions& o)
    : sin_min_(std::sin(o.min_elevation_rad)), sin_max_(std::sin(o.max_elevation_rad)) {}

Vector3 LidarPattern::Direction(std::uint64_t k) const {
  // R2 sequence: alpha = (1/g, 1/g^2), g the plastic number (the real root of x^3 = x + 1).
  constexpr double g = 1.32471795724474602596;
  constexpr double a1 = 1.0 / g, a2 = 1.0 / (g * g);
  const double kd = static_cast<double>(k);
  // Fractional parts (x - floor(x) equals fmod(x, 1) exactly for x >= 0, and is cheaper).
  const double x = 0.5 + a1 * kd, y = 0.5 + a2 * kd;
  const double u = x - std::floor(x), v = y - std::floor(y);
  double sin_az = 0.0, cos_az = 1.0;
  SinCosOfTurns(u, &sin_az, &cos_az);  // azimuth 2 pi u
  // Uniform in solid angle over the band: sin(elevation) uniform.
  const double sin_el = sin_min_ + v * (sin_max_ - sin_min_);
  const double cos_el = std::sqrt(std::max(0.0, 1.0 - sin_el * sin_el));
  return Vector3(cos_el * cos_az, cos_el * sin_az, sin_el);
}

LidarSimulator::LidarSimulator(const LidarOptions& options, const World& world, std::uint64_t seed)
    : options_(options), pattern_(options), caster_(world, RayCasterOptions{options.grid_cell_m}), rng_(seed) {
  options_.Validate();
  frame_ns_ = PeriodFromRate(options_.frame_rate_hz);
  R_BS_ = options_.rotation.normalized().toRotationMatrix();
  clock_offset_ns_ = FromSeconds(options_.clock_offset_s);
  frame_.t_start_ns = 0;
  frame_.t_end_ns = frame_ns_;
}

TimeNs LidarSimulator::PulseTime(std::uint64_t k) const {
  // Saturated: a pulse beyond the range of TimeNs never comes (found by generating flights: 4.9e-324
  // points per second made the second pulse's time +inf, its integer negative, and Step() loop).
  return SaturatedNs(std::round(static_cast<double>(k) * 1e9 / options_.points_per_s));
}

std::optional<LidarFrame> LidarSimulator::Step(TimeNs t0, const BodyPose& pose0, TimeNs t1, const BodyPose& pose1) {
  if (t1 <= t0) return std::nullopt;
  // Attitude across the step: q(s) = q0 * exp(s * log(q0^-1 q1)), the shortest arc.
  const Quaternion q0 = pose0.q_WB.normalized();
  Quaternion rel = q0.conjugate() * pose1.q_WB.normalized();
  if (rel.w() < 0.0) rel.coeffs() = -rel.coeffs();
  const Eigen::AngleAxisd arc(rel);
  const double span = static_cast<double>(t1 - t0);
  std::optional<LidarFrame> done;
  for (TimeNs t = PulseTime(next_pulse_); t <= t1; t = PulseTime(next_pulse_)) {
    if (t <= t0 && next_pulse_ > 0) {  // pulses at or before t0 belonged to the previous step
      ++next_pulse_;
      continue;
    }
    while (t >= frame_.t_end_ns) {  // the pulse opens a new frame: hand over the finished one
      done = std::move(frame_);
      frame_ = LidarFrame{};
      frame_.t_start_ns = done->t_end_ns;
      frame_.t_end_ns = done->t_end_ns + frame_ns_;
    }
    const double s = std::clamp(static_cast<double>(t - t0) / span, 0.0, 1.0);
    const Vector3 p = pose0.p_W + s * (pose1.p_W - pose0.p_W);
    const Matrix3 R = (q0 * Quaternion(Eigen::AngleAxisd(s * arc.angle(), arc.axis()))).toRotationMatrix();
    const Vector3 dir_S = pattern_.Direction(next_pulse_);
    const Vector3 origin = p + R * options_.position_m;
    const auto hit = caster_.Cast(origin, R * (R_BS_ * dir_S), options_.max_range_m, ToSeconds(t));
    ++next_pulse_;
    if (!hit || hit->distance_m < options_.min_range_m || rng_.Uniform() < options_.dropout_probability) {
      ++frame_.dropped;
      continue;
    }
    const double range = hit->distance_m + options_.range_noise_m * rng_.Normal();
    frame_.points_S.push_back((range * dir_S).cast<float>());
    // Stamped at the resolution the driver publishes (float32 seconds after the frame's start).
    frame_.offset_ns.push_back(LidarOffsetAsOnTheWire(static_cast<std::uint32_t>(t - frame_.t_start_ns)));
  }
  if (done && clock_offset_ns_ != 0) {
    // Stamped by the sensor's clock; delivered once its stamped end has come, never earlier.
    done->t_start_ns += clock_offset_ns_;
    done->t_end_ns += clock_offset_ns_;
  }
  if (done) held_ = std::move(done);
  std::optional<LidarFrame> out;
  if (held_ && held_->t_end_ns <= t1) out.swap(held_);
  return out;
}

}  // namespace rotorguard::sim
