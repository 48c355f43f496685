#pragma once
/// Simulated Livox MID-360 (paper 000 Sec. IV-B): 360 degrees horizontally, -7..+52 degrees
/// vertically, a non-repetitive pattern, about 200k points/s in 10 Hz frames, 0.1-40 m, range
/// noise and dropouts. Every point is cast from the sensor's pose at its own time (the pose is
/// interpolated across each physics step), so a spinning vehicle gets distorted frames as the
/// real sensor does.
///
/// The pattern: point k points along the k-th element of the R2 low-discrepancy sequence
/// (Roberts 2018; fractional parts of k / g and k / g^2, g the plastic number) mapped to azimuth
/// and to elevation uniformly in solid angle. It never repeats and fills the field of view more
/// densely the longer it integrates, as the MID-360's rosette does; the exact Livox pattern is
/// not public.
#include <cstdint>
#include <numbers>
#include <optional>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/sim/raycast.h"

namespace rotorguard::sim {

struct LidarOptions {
  bool enabled = false;             ///< off by default: ray casting costs time
  double frame_rate_hz = 10.0;      ///< frames per second, in [kMinRateHz, 1000]
  double points_per_s = 200000.0;   ///< pulses per second, in [1, 1e7]
  double min_range_m = 0.1;         ///< closer returns are dropped, >= 0
  double max_range_m = 40.0;        ///< > min_range_m
  double min_elevation_rad = -0.12217304763960307;  ///< -7 degrees, in [-pi/2, max)
  double max_elevation_rad = 0.90757121103705141;   ///< +52 degrees, in (min, pi/2]
  double range_noise_m = 0.02;      ///< 1-sigma range noise [m], >= 0 (MID-360: 2 cm at 10 m)
  double dropout_probability = 0.01;  ///< chance a return is lost, in [0, 1)
  Vector3 position_m = Vector3(0.0, 0.0, 0.06);  ///< mounting point, body frame (axes aligned)
  double grid_cell_m = 1.0;                      ///< the boxes' ray-casting grid cell [m], > 0
  /// Truth side (the scenario's truth, not sensor keys): the sensor's true mounting point from the
  /// true centre of gravity (position_m is from the file's body frame: the simulator moves it by
  /// the drawn offset), its axes' rotation from the body's, and the offset of its clock: a frame
  /// captured over [t0, t1) is stamped [t0, t1) + clock_offset_s.
  Quaternion rotation = Quaternion::Identity();
  double clock_offset_s = 0.0;
  /// Throws ValidationError naming the field (SimulatorOptions prefixes "sensors.lidar.").
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("enabled", &enabled,
             {.meaning = "a lidar block switches the sensor on unless this says false", .default_text = "true"});
    a->Visit("frame_rate_hz", &frame_rate_hz, {.meaning = "frames per second", .min = kMinRateHz, .max = 1000.0});
    // Every pulse is cast: ten million a simulated second is twice the densest scanning LiDAR's.
    a->Visit("points_per_s", &points_per_s, {.meaning = "pulses per second", .min = 1.0, .max = 1e7});
    a->Visit("min_range_m", &min_range_m,
             {.meaning = "closer returns are dropped [m], below max_range_m", .min = 0.0, .max = 100.0});
    a->Visit("max_range_m", &max_range_m, {.meaning = "[m]", .max = 1e4, .positive = true});
    a->Visit("min_elevation_rad", &min_elevation_rad,
             {.meaning = "the field of view's lower edge [rad] (-7°), below max_elevation_rad",
              .min = -std::numbers::pi / 2.0,
              .max = std::numbers::pi / 2.0});
    a->Visit("max_elevation_rad", &max_elevation_rad,
             {.meaning = "its upper edge [rad] (52°)", .min = -std::numbers::pi / 2.0, .max = std::numbers::pi / 2.0});
    a->Visit("range_noise_m", &range_noise_m, {.meaning = "1-σ range noise [m]", .min = 0.0, .max = 1.0});
    a->Visit("dropout_probability", &dropout_probability,
             {.meaning = "chance a return is lost", .min = 0.0, .max = 1.0, .open_max = true});
    a->Visit("position_m", &position_m,
             {.meaning = "mounting point, body frame [m]", .min = -kMaxBodyOffsetM, .max = kMaxBodyOffsetM});
    // The grid has at most 2048 cells a side whatever the cell (RayCaster).
    a->Visit("grid_cell_m", &grid_cell_m,
             {.meaning = "the boxes' ray-casting grid cell [m]", .min = 0.01, .max = 100.0});
  }
};

/// A body pose: position and attitude of the body frame in the world.
struct BodyPose {
  Vector3 p_W = Vector3::Zero();
  Quaternion q_WB = Quaternion::Identity();
};

/// The scan pattern: the unit direction (sensor frame) of each pulse.
class LidarPattern {
 public:
  explicit LidarPattern(const LidarOptions& options);
  Vector3 Direction(std::uint64_t k) const;

 private:
  double sin_min_, sin_max_;  // the band's bounds in sin(elevation), computed once
};

class LidarSimulator {
 public:
  LidarSimulator(const LidarOptions& options, const World& world, std::uint64_t seed);
  /// Casts the pulses due in (t0, t1] from poses interpolated between `pose0` (at t0) and `pose1`
  /// (at t1): position linearly, attitude along the shortest arc. Returns a frame when t1 reaches
  /// the end of one as its stamps say (at most one per call: steps are far shorter than frames).
  std::optional<LidarFrame> Step(TimeNs t0, const BodyPose& pose0, TimeNs t1, const BodyPose& pose1);
  /// Pulses cast so far.
  std::uint64_t pulses() const { return next_pulse_; }

 private:
  TimeNs PulseTime(std::uint64_t k) const;

  LidarOptions options_;
  LidarPattern pattern_;
  RayCaster caster_;
  Rng rng_;
  TimeNs frame_ns_;
  std::uint64_t next_pulse_ = 0;
  LidarFrame frame_;
  Matrix3 R_BS_ = Matrix3::Identity();    // the sensor's axes in the body's
  TimeNs clock_offset_ns_ = 0;
  std::optional<LidarFrame> held_;  // finished, waiting for its stamped end
};

}  // namespace rotorguard::sim
