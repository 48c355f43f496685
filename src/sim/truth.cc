#include "rotorguard/sim/truth.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/core/rng.h"

namespace rotorguard::sim {

TruthRanges RangesOf(TruthPreset preset) {
  TruthRanges r;
  if (preset == TruthPreset::kIdeal) return r;
  // docs/truth.md gives the reason for each.
  r.mass_fraction = 0.07;
  r.inertia_fraction = 0.15;
  r.cog_offset_m = 0.007;  // per axis: at most 1 cm horizontally
  r.thrust_coefficient_fraction = 0.05;
  r.yaw_coefficient_fraction = 0.10;
  r.motor_time_constant_fraction = 0.20;
  r.rotor_drag_fraction = 0.30;
  r.imu_offset_m = 0.005;
  r.external_torque_n_m = 0.01;
  r.motor_stop_time_constant_min_s = 0.005;
  r.motor_stop_time_constant_max_s = 0.050;
  r.imu_vibration_m_s2 = 0.8;
  r.esc_gain_fraction = 0.01;
  r.esc_dropout_probability = 0.01;
  r.odometry_latency_min_s = 0.010;
  r.odometry_latency_max_s = 0.030;
  r.odometry_drift_m_per_sqrt_s = 0.01;
  r.odometry_yaw_drift_rad_per_sqrt_s = 0.001;
  r.odometry_few_features_gain = 1.0;
  r.odometry_outage_rate_hz = 1.0 / 60.0;
  r.computation_delay_min_s = 0.001;
  r.computation_delay_max_s = 0.004;
  r.computation_delay_jitter_fraction = 0.25;
  r.esc_command_latency_min_s = 0.0005;
  r.esc_command_latency_max_s = 0.002;
  r.imu_noise_fraction = 0.5;
  r.lidar_rotation_rad = 0.0087266462599716;  // 0.5°
  r.lidar_clock_offset_s = 0.002;
  r.imu_axial_vibration_m_s2 = 0.8;
  r.gyro_vibration_gain = 3.0;
  r.ground_effect_fraction = 0.5;
  r.battery_fraction = 0.3;
  return r;
}

TruthRanges TruthOptions::Ranges() const {
  TruthRanges r = RangesOf(preset);
  for (const TruthOverrideKey& k : kTruthOverrideKeys) {
    if (k.range != nullptr && this->*k.override) r.*k.range = *(this->*k.override);
  }
  if (motor_stop_time_constant_min_s) {
    r.motor_stop_time_constant_min_s = motor_stop_time_constant_min_s;
    r.motor_stop_time_constant_max_s = motor_stop_time_constant_max_s;
  }
  if (odometry_latency_min_s) {
    r.odometry_latency_min_s = *odometry_latency_min_s;
    r.odometry_latency_max_s = *odometry_latency_max_s;
  }
  if (computation_delay_min_s) {
    r.computation_delay_min_s = *computation_delay_min_s;
    r.computation_delay_max_s = *computation_delay_max_s;
  }
  if (esc_command_latency_min_s) {
    r.esc_command_latency_min_s = *esc_command_latency_min_s;
    r.esc_command_latency_max_s = *esc_command_latency_max_s;
  }
  return r;
}

namespace {

/// An interval given by two keys must be given whole and in order.
void ValidateInterval(const std::optional<double>& min, const char* min_key, const std::optional<double>& max,
                      const char* max_key) {
  if (min.has_value() != max.has_value()) {
    const char* missing = min ? max_key : min_key;
    throw ValidationError(missing,
                          fmt::format("{} is missing; expected both {} and {} or neither", missing, min_key, max_key));
  }
  if (min && *max < *min)
    ThrowValidation("TruthOptions", max_key, *max, fmt::format("at least {} = {}", min_key, *min));
}

}  // namespace

void TruthOptions::Validate() const {
  CheckDeclaredRanges("TruthOptions", *this);
  ValidateInterval(motor_stop_time_constant_min_s, "motor_stop_time_constant_min_s", motor_stop_time_constant_max_s,
                   "motor_stop_time_constant_max_s");
  ValidateInterval(odometry_latency_min_s, "odometry_latency_min_s", odometry_latency_max_s, "odometry_latency_max_s");
  ValidateInterval(computation_delay_min_s, "computation_delay_min_s", computation_delay_max_s,
                   "computation_delay_max_s");
  ValidateInterval(esc_command_latency_min_s, "esc_command_latency_min_s", esc_command_latency_max_s,
                   "esc_command_latency_max_s");
}

namespace {

/// 1 + U(-a, a), or exactly 1 without drawing when a = 0.
double Ratio(double a, Rng* rng) { return a > 0.0 ? 1.0 + rng->Uniform(-a, a) : 1.0; }

Vector3 Ratios(double a, Rng* rng) {
  const double x = Ratio(a, rng), y = Ratio(a, rng), z = Ratio(a, rng);
  return {x, y, z};
}

Vector3 Offset(double a, Rng* rng) { return Ratios(a, rng) - Vector3::Ones(); }

/// Uniform in [lo, hi], or lo without drawing when the interval is a point.
double Between(double lo, double hi, Rng* rng) { return hi > lo ? rng->Uniform(lo, hi) : lo; }

}  // namespace

TruthDraw DrawTruth(const TruthOptions& options, const vehicle::VehicleParams& vehicle, std::uint64_t seed) {
  const TruthRanges r = options.Ranges();
  // The draw's own stream: what it draws never shifts the sensors' or the wind's noise.
  Rng rng(DeriveSeed(seed, 0x7472757468ULL));  // "truth"
  TruthDraw d;
  d.preset = options.preset;
  d.mass_ratio = Ratio(r.mass_fraction, &rng);
  d.mass_moment_ratio = Ratios(r.inertia_fraction, &rng);
  d.cog_offset_m = Offset(r.cog_offset_m, &rng);
  for (int i = 0; i < vehicle.num_rotors(); ++i) {
    d.thrust_coefficient_ratio.push_back(Ratio(r.thrust_coefficient_fraction, &rng));
    d.yaw_coefficient_ratio.push_back(Ratio(r.yaw_coefficient_fraction, &rng));
  }
  d.motor_time_constant_ratio = Ratio(r.motor_time_constant_fraction, &rng);
  d.motor_stop_time_constant_s = vehicle.motor_stop_time_constant_s;
  if (r.motor_stop_time_constant_min_s) {
    const double lo = std::log(*r.motor_stop_time_constant_min_s), hi = std::log(*r.motor_stop_time_constant_max_s);
    d.motor_stop_time_constant_s = hi > lo ? std::exp(rng.Uniform(lo, hi)) : *r.motor_stop_time_constant_min_s;
  }
  d.rotor_drag_ratio = Ratios(r.rotor_drag_fraction, &rng);
  d.imu_offset_m = Offset(r.imu_offset_m, &rng);
  const Vector3 torque = Offset(r.external_torque_n_m, &rng);
  d.external_torque_n_m = Vector3(torque.x(), torque.y(), 0.0);
  // Drawn last, so that the draws above keep their values when this range changes.
  if (r.imu_vibration_m_s2 > 0.0) d.imu_vibration_m_s2 = rng.Uniform(0.5, 1.0) * r.imu_vibration_m_s2;
  for (int i = 0; i < vehicle.num_rotors(); ++i) d.esc_gain.push_back(Ratio(r.esc_gain_fraction, &rng));
  d.esc_dropout_probability = r.esc_dropout_probability;
  if (r.odometry_latency_max_s > 0.0)
    d.odometry_latency_s = rng.Uniform(r.odometry_latency_min_s, r.odometry_latency_max_s);
  if (r.odometry_drift_m_per_sqrt_s > 0.0)
    d.odometry_drift_m_per_sqrt_s = rng.Uniform(0.5, 1.0) * r.odometry_drift_m_per_sqrt_s;
  if (r.odometry_yaw_drift_rad_per_sqrt_s > 0.0) {
    d.odometry_yaw_drift_rad_per_sqrt_s = rng.Uniform(0.5, 1.0) * r.odometry_yaw_drift_rad_per_sqrt_s;
  }
  d.odometry_few_features_gain = r.odometry_few_features_gain;
  d.odometry_outage_rate_hz = r.odometry_outage_rate_hz;
  // Drawn after everything above (whose values stay those of the releases before the delays).
  d.computation_delay_s = Between(r.computation_delay_min_s, r.computation_delay_max_s, &rng);
  d.computation_delay_jitter_fraction = r.computation_delay_jitter_fraction;
  d.esc_command_latency_s = Between(r.esc_command_latency_min_s, r.esc_command_latency_max_s, &rng);
  d.imu_accel_noise_ratio = Ratio(r.imu_noise_fraction, &rng);
  d.imu_gyro_noise_ratio = Ratio(r.imu_noise_fraction, &rng);
  d.lidar_rotation_rad = Offset(r.lidar_rotation_rad, &rng);
  if (r.lidar_clock_offset_s > 0.0) d.lidar_clock_offset_s = rng.Uniform(-r.lidar_clock_offset_s, r.lidar_clock_offset_s);
  if (r.imu_axial_vibration_m_s2 > 0.0) d.imu_axial_vibration_m_s2 = rng.Uniform(0.5, 1.0) * r.imu_axial_vibration_m_s2;
  if (r.gyro_vibration_gain > 0.0) d.gyro_vibration_gain = rng.Uniform(std::min(1.0, r.gyro_vibration_gain), r.gyro_vibration_gain);
  d.ground_effect_ratio = Ratio(r.ground_effect_fraction, &rng);
  if (r.battery_fraction > 0.0) {
    d.battery_capacity_ratio = rng.Uniform(1.0 - r.battery_fraction, 1.0);
    d.battery_resistance_ratio = rng.Uniform(1.0, 1.0 + 2.0 * r.battery_fraction);
  }
  return d;
}

Matrix3 ScaleMassMoments(const Matrix3& inertia, const Vector3& ratio) {
  // The mass's second moment Σ = ∫ r rᵀ dm = ½ tr(I) 1 − I, and back I = tr(Σ) 1 − Σ. Σ' = S Σ S
  // with S = diag(√ratio) scales ∫x² dm, ∫y² dm, ∫z² dm by the ratios and stays positive
  // semidefinite, so I' is a rigid body's inertia whenever I is (VehicleParams::Validate).
  if (ratio == Vector3::Ones()) return inertia;  // the file bit for bit: the ideal world's flights
  const Matrix3 sigma = 0.5 * inertia.trace() * Matrix3::Identity() - inertia;
  const Vector3 s = ratio.cwiseSqrt();
  const Matrix3 scaled = s.asDiagonal() * sigma * s.asDiagonal();
  return scaled.trace() * Matrix3::Identity() - scaled;
}

namespace {
// A point of the file's body moved by the drawn CoG offset, kept within the range of a body point:
// a file at the range's edge must describe a simulated vehicle the simulator accepts. (Found by
// generating flights: an IMU at 50 m flew as 50.01 m and the run stopped with an unlocated error.)
Vector3 MovedBodyPoint(const Vector3& p) {
  return p.cwiseMax(Vector3::Constant(-kMaxBodyOffsetM)).cwiseMin(Vector3::Constant(kMaxBodyOffsetM));
}
}  // namespace

vehicle::VehicleParams TruthVehicle(const vehicle::VehicleParams& file, const TruthDraw& d) {
  vehicle::VehicleParams v = file;
  v.mass_kg = file.mass_kg * d.mass_ratio;
  v.inertia_kg_m2 = ScaleMassMoments(file.inertia_kg_m2, d.mass_moment_ratio);
  v.rotor_drag_kg_s = file.rotor_drag_kg_s.cwiseProduct(d.rotor_drag_ratio);
  v.motor_time_constant_s = file.motor_time_constant_s * d.motor_time_constant_ratio;
  v.motor_stop_time_constant_s = d.motor_stop_time_constant_s;
  // Rotor positions are relative to the centre of gravity: a CoG at c moves every hub by -c.
  for (std::size_t i = 0; i < v.rotors.size(); ++i) {
    v.rotors[i].p_B = MovedBodyPoint(file.rotors[i].p_B - d.cog_offset_m);
    if (i < d.yaw_coefficient_ratio.size()) v.rotors[i].yaw_coefficient_m *= d.yaw_coefficient_ratio[i];
  }
  for (vehicle::CollisionSphere& c : v.collision_spheres) c.centre_B = MovedBodyPoint(c.centre_B - d.cog_offset_m);
  // The feet, as the hubs (the file's, or its default under the file's hubs).
  v.landing_gear_B.clear();
  for (const Vector3& f : file.LandingGear()) v.landing_gear_B.push_back(MovedBodyPoint(f - d.cog_offset_m));
  // The spheres, moved, stay within the bound about the true CoG only if it grows by the offset. A
  // body of one sphere keeps it centred on the CoG (off by the offset, at most 12 mm).
  if (!v.collision_spheres.empty()) {
    v.collision_radius_m = std::min(file.collision_radius_m + d.cog_offset_m.norm(), kMaxBodyOffsetM);
  }
  return v;
}

RotorVector ThrustRatios(const TruthDraw& draw) {
  const std::vector<double>& r = draw.thrust_coefficient_ratio;
  return Eigen::Map<const RotorVector>(r.data(), static_cast<Eigen::Index>(r.size()));
}

SimulatorOptions TruthSimulatorOptions(const SimulatorOptions& scenario, const vehicle::VehicleParams& file,
                                       const TruthDraw& draw) {
  SimulatorOptions o = scenario;
  o.imu.position_m = MovedBodyPoint(scenario.imu.position_m - draw.cog_offset_m + draw.imu_offset_m);
  o.imu.vibration_m_s2 = draw.imu_vibration_m_s2;
  // The vibration's amplitude is given at the file's hover speed: T = m g / n = k_n ω².
  o.imu.vibration_reference_speed_rad_s = std::sqrt(file.weight_n() / file.num_rotors() / file.thrust_coefficient_n_s2);
  o.external_torque_n_m = draw.external_torque_n_m;
  o.esc.gain = draw.esc_gain;
  o.esc.dropout_probability = draw.esc_dropout_probability;
  o.odometry.latency_s = draw.odometry_latency_s;
  o.odometry.drift_m_per_sqrt_s = draw.odometry_drift_m_per_sqrt_s;
  o.odometry.yaw_drift_rad_per_sqrt_s = draw.odometry_yaw_drift_rad_per_sqrt_s;
  o.odometry.few_features_gain = draw.odometry_few_features_gain;
  o.odometry.outage_rate_hz = draw.odometry_outage_rate_hz;
  o.esc.command_latency_s = draw.esc_command_latency_s;
  // The front end reports the file's body frame, whose origin lies at -c from the true CoG; the
  // LiDAR is mounted on that body, so it moves by -c too, and is turned and its clock off.
  o.odometry.body_origin_m = -draw.cog_offset_m;
  // The world's frame is the file's: its body origin rests at z = 0, the ground its gear below.
  o.ground_z_m = -file.RestingHeight();
  o.lidar.position_m = MovedBodyPoint(scenario.lidar.position_m - draw.cog_offset_m);
  const double angle = draw.lidar_rotation_rad.norm();
  if (angle > 0.0) o.lidar.rotation = Quaternion(Eigen::AngleAxisd(angle, draw.lidar_rotation_rad / angle));
  o.lidar.clock_offset_s = draw.lidar_clock_offset_s;
  o.imu.accel_noise_density = scenario.imu.accel_noise_density * draw.imu_accel_noise_ratio;
  o.imu.gyro_noise_density = scenario.imu.gyro_noise_density * draw.imu_gyro_noise_ratio;
  o.imu.axial_vibration_m_s2 = draw.imu_axial_vibration_m_s2;
  o.imu.gyro_vibration_gain = draw.gyro_vibration_gain;
  o.ground_effect.strength = std::min(scenario.ground_effect.strength * draw.ground_effect_ratio, kMaxGroundEffectStrength);
  o.battery.capacity_mah = scenario.battery.capacity_mah * draw.battery_capacity_ratio;
  o.battery.internal_resistance_ohm = scenario.battery.internal_resistance_ohm * draw.battery_resistance_ratio;
  if (draw.gyro_vibration_gain > 0.0) {
    const vehicle::VehicleParams v = TruthVehicle(file, draw);
    for (const vehicle::Rotor& r : v.rotors) o.imu.rotor_positions_m.push_back(r.p_B);
    o.imu.airframe_mass_kg = v.mass_kg;
    o.imu.airframe_inverse_inertia = v.inertia_kg_m2.inverse();
  }
  return o;
}

}  // namespace rotorguard::sim
