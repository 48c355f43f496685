#pragma once
/// The truth is not the model: how the simulated vehicle departs from the vehicle file the flight
/// stack reads. A scenario's `truth` block names a preset (`ideal`: the file is exact; `realistic`:
/// the spread a careful experimenter would defend for a 1 kg class quadrotor) and may override any
/// range; each flight draws its own vehicle from the ranges with a seed derived from the scenario's,
/// so every method compared on a trial flies the same draw. docs/truth.md gives each range's reason.
///
/// Only the simulator is built from the draw: the stack keeps the file's vehicle and the file's
/// IMU mounting point, and the `stack` module cannot include this header (it does not link `sim`).
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::sim {

enum class TruthPreset { kIdeal, kRealistic };
inline constexpr EnumName<TruthPreset> kTruthPresetNames[] = {{TruthPreset::kIdeal, "ideal"},
                                                              {TruthPreset::kRealistic, "realistic"}};
constexpr std::span<const EnumName<TruthPreset>> NamesOf(const TruthPreset*) { return kTruthPresetNames; }

/// The half-widths of the uniform draws (relative ones as fractions of the file's value), and the
/// range of the motor-stop time constant. All zero: the file's vehicle exactly.
struct TruthRanges {
  double mass_fraction = 0.0;                 ///< m = m_file (1 + U(-a, a))
  /// Each second moment of mass ∫x² dm, ∫y² dm, ∫z² dm (body frame) independently; the principal
  /// moments follow from them (ScaleMassMoments).
  double inertia_fraction = 0.0;
  double cog_offset_m = 0.0;                  ///< each axis of the centre of gravity's offset, U(-a, a)
  double thrust_coefficient_fraction = 0.0;   ///< each rotor's k_n (thrust per speed squared)
  double yaw_coefficient_fraction = 0.0;      ///< each rotor's κ_t
  double motor_time_constant_fraction = 0.0;  ///< σ of all motors (one ESC firmware, one motor type)
  double rotor_drag_fraction = 0.0;           ///< each axis of D
  double imu_offset_m = 0.0;                  ///< each axis of the IMU's mounting point, U(-a, a)
  double external_torque_n_m = 0.0;           ///< roll and pitch of a constant torque, U(-a, a)
  /// Each healthy rotor's vibration at the accelerometer at hover speed, drawn in [a/2, a] [m/s²]
  /// (ImuOptions::vibration_m_s2; ten times more on a rotor whose propeller is lost or damaged).
  double imu_vibration_m_s2 = 0.0;
  double esc_gain_fraction = 0.0;        ///< each motor's reported speed, ω (1 ± a)
  double esc_dropout_probability = 0.0;  ///< each telemetry frame lost with this probability
  /// Motor-stop time constant drawn log-uniformly in [min, max] [s]; unset: the file's value.
  std::optional<double> motor_stop_time_constant_min_s, motor_stop_time_constant_max_s;
  /// The odometry front end (OdometryOptions): its latency drawn uniformly in [min, max] [s]; the
  /// random walks of its frame's position [m/√s] and yaw [rad/√s] each drawn in [a/2, a]; how much
  /// its noise and drift grow with no obstacle in view; how often it loses track [1/s].
  double odometry_latency_min_s = 0.0, odometry_latency_max_s = 0.0;
  double odometry_drift_m_per_sqrt_s = 0.0;
  double odometry_yaw_drift_rad_per_sqrt_s = 0.0;
  double odometry_few_features_gain = 0.0;
  double odometry_outage_rate_hz = 0.0;
  /// The loop's delays: a control cycle's computation (from the sensor data it starts from to its
  /// command leaving the computer) drawn uniformly in [min, max] per flight, and each cycle's
  /// within (1 ± jitter) of it; the ESCs' command latency (from a command's arrival to the motors
  /// acting on it) drawn uniformly in [min, max] per flight [s].
  double computation_delay_min_s = 0.0, computation_delay_max_s = 0.0;
  double computation_delay_jitter_fraction = 0.0;
  double esc_command_latency_min_s = 0.0, esc_command_latency_max_s = 0.0;
  /// The sensors' own departures: each IMU noise density (accelerometer, gyro) drawn in
  /// (1 ± a) times the scenario's; the LiDAR's axes turned by up to ± a about each body axis
  /// [rad]; its clock offset by ± a [s].
  double imu_noise_fraction = 0.0;
  double lidar_rotation_rad = 0.0;
  double lidar_clock_offset_s = 0.0;
  /// Vibration beyond imu_vibration_m_s2's in-plane one, per healthy rotor at hover speed, drawn
  /// in [a/2, a]: along the rotor axis at the blade-pass frequency (twice the rotor's) at the
  /// accelerometer [m/s²]; and the airframe's rocking these forces make (rigid-body mechanics,
  /// ImuOptions) times a frame's flex, drawn in [1, a] (0: no rocking).
  double imu_axial_vibration_m_s2 = 0.0;
  double gyro_vibration_gain = 0.0;
  /// The ground effect's strength (GroundEffectOptions::strength) drawn in (1 ± a) times the
  /// scenario's.
  double ground_effect_fraction = 0.0;
  /// The battery's capacity drawn in [1 - a, 1] times the scenario's (packs age), its internal
  /// resistance in [1, 1 + 2a] times (and cold or worn cells).
  double battery_fraction = 0.0;
};

/// The ranges of a preset.
TruthRanges RangesOf(TruthPreset preset);

/// The scenario's `truth` block: a preset, and any of its ranges overridden.
struct TruthOptions {
  TruthPreset preset = TruthPreset::kRealistic;  ///< a scenario that names none flies a drawn vehicle
  std::optional<double> mass_fraction, inertia_fraction, cog_offset_m, thrust_coefficient_fraction,
      yaw_coefficient_fraction, motor_time_constant_fraction, rotor_drag_fraction, imu_offset_m, external_torque_n_m,
      motor_stop_time_constant_min_s, motor_stop_time_constant_max_s, imu_vibration_m_s2, esc_gain_fraction,
      esc_dropout_probability, odometry_latency_min_s, odometry_latency_max_s, odometry_drift_m_per_sqrt_s,
      odometry_yaw_drift_rad_per_sqrt_s, odometry_few_features_gain, odometry_outage_rate_hz,
      computation_delay_min_s, computation_delay_max_s, computation_delay_jitter_fraction, esc_command_latency_min_s,
      esc_command_latency_max_s, imu_noise_fraction, lidar_rotation_rad, lidar_clock_offset_s,
      imu_axial_vibration_m_s2, gyro_vibration_gain, ground_effect_fraction, battery_fraction;

  /// The preset's ranges with the overrides applied.
  TruthRanges Ranges() const;
  /// Throws ValidationError naming the key ("motor_stop_time_constant_max_s") and the rule.
  void Validate() const;

  template <typename Archive>
  void Serialize(Archive* a);
};

/// One override of the truth block: its key (the field's name), what it accepts and means, and
/// the range it replaces; none for the two ends of an interval (the stop time constant's, the
/// odometry latency's, the loop's delays'), which replace their interval together
/// (TruthOptions::Ranges). The keys, the loader and Ranges() all follow this list.
struct TruthOverrideKey {
  const char* key;
  std::optional<double> TruthOptions::*override;
  double TruthRanges::*range;
  KeyInfo info;
};

inline constexpr TruthOverrideKey kTruthOverrideKeys[] = {
    {"mass_fraction",
     &TruthOptions::mass_fraction,
     &TruthRanges::mass_fraction,
     {.meaning = "mass drawn in m (1 ± a)", .min = 0, .max = 0.5}},
    {"inertia_fraction",
     &TruthOptions::inertia_fraction,
     &TruthRanges::inertia_fraction,
     {.meaning = "each second moment of mass (∫x² dm, ∫y² dm, ∫z² dm) drawn in (1 ± a); the inertia follows",
      .min = 0,
      .max = 0.5}},
    {"cog_offset_m",
     &TruthOptions::cog_offset_m,
     &TruthRanges::cog_offset_m,
     {.meaning = "each axis of the centre of gravity's offset drawn in ± a [m]", .min = 0, .max = 0.05}},
    {"thrust_coefficient_fraction",
     &TruthOptions::thrust_coefficient_fraction,
     &TruthRanges::thrust_coefficient_fraction,
     {.meaning = "each rotor's k_n drawn in k_n (1 ± a)", .min = 0, .max = 0.5}},
    {"yaw_coefficient_fraction",
     &TruthOptions::yaw_coefficient_fraction,
     &TruthRanges::yaw_coefficient_fraction,
     {.meaning = "each rotor's κ_t drawn in κ_t (1 ± a)", .min = 0, .max = 0.5}},
    {"motor_time_constant_fraction",
     &TruthOptions::motor_time_constant_fraction,
     &TruthRanges::motor_time_constant_fraction,
     {.meaning = "the motors' σ drawn in σ (1 ± a)", .min = 0, .max = 0.5}},
    {"rotor_drag_fraction",
     &TruthOptions::rotor_drag_fraction,
     &TruthRanges::rotor_drag_fraction,
     {.meaning = "each axis of the rotor drag D drawn in D (1 ± a)", .min = 0, .max = 1}},
    {"imu_offset_m",
     &TruthOptions::imu_offset_m,
     &TruthRanges::imu_offset_m,
     {.meaning = "each axis of the IMU's mounting point drawn in ± a about the sensors.imu position [m]",
      .min = 0,
      .max = 0.05}},
    {"external_torque_n_m",
     &TruthOptions::external_torque_n_m,
     &TruthRanges::external_torque_n_m,
     {.meaning = "a constant roll and pitch torque the stack is not told of (payload, cable), each in ± a [N·m]",
      .min = 0,
      .max = 1}},
    {"motor_stop_time_constant_min_s",
     &TruthOptions::motor_stop_time_constant_min_s,
     nullptr,
     {.meaning = "a stopped motor's time constant drawn log-uniformly in [min, max] [s]",
      .max = 10.0,
      .positive = true}},
    {"motor_stop_time_constant_max_s",
     &TruthOptions::motor_stop_time_constant_max_s,
     nullptr,
     {.meaning = "(set both or neither)", .max = 10.0, .positive = true}},
    {"imu_vibration_m_s2",
     &TruthOptions::imu_vibration_m_s2,
     &TruthRanges::imu_vibration_m_s2,
     {.meaning = "each healthy rotor's vibration at the accelerometer at hover speed, drawn in [a/2, a] [m/s²]; ten "
                 "times more after a propeller loss or damage",
      .min = 0,
      .max = 20}},
    {"esc_gain_fraction",
     &TruthOptions::esc_gain_fraction,
     &TruthRanges::esc_gain_fraction,
     {.meaning = "each motor's telemetry reports ω (1 ± a)", .min = 0, .max = 0.2}},
    {"esc_dropout_probability",
     &TruthOptions::esc_dropout_probability,
     &TruthRanges::esc_dropout_probability,
     {.meaning = "each ESC telemetry frame is lost with this probability", .min = 0, .max = 0.5}},
    {"odometry_latency_min_s",
     &TruthOptions::odometry_latency_min_s,
     nullptr,
     {.meaning = "the odometry arrives this much after its capture, drawn uniformly in [min, max] [s]",
      .min = 0,
      .max = 0.4}},
    {"odometry_latency_max_s",
     &TruthOptions::odometry_latency_max_s,
     nullptr,
     {.meaning = "(set both or neither)", .min = 0, .max = 0.4}},
    {"odometry_drift_m_per_sqrt_s",
     &TruthOptions::odometry_drift_m_per_sqrt_s,
     &TruthRanges::odometry_drift_m_per_sqrt_s,
     {.meaning = "the odometry frame's position random walk, each axis, drawn in [a/2, a] [m/√s]", .min = 0, .max = 1}},
    {"odometry_yaw_drift_rad_per_sqrt_s",
     &TruthOptions::odometry_yaw_drift_rad_per_sqrt_s,
     &TruthRanges::odometry_yaw_drift_rad_per_sqrt_s,
     {.meaning = "the odometry frame's yaw random walk, drawn in [a/2, a] [rad/√s]", .min = 0, .max = 0.1}},
    {"odometry_few_features_gain",
     &TruthOptions::odometry_few_features_gain,
     &TruthRanges::odometry_few_features_gain,
     {.meaning = "odometry noise and drift grow by 1 + a (1 - n/8) with n < 8 obstacles within 20 m",
      .min = 0,
      .max = 10}},
    {"odometry_outage_rate_hz",
     &TruthOptions::odometry_outage_rate_hz,
     &TruthRanges::odometry_outage_rate_hz,
     {.meaning = "the odometry loses track for 0.05-0.3 s this often on average [1/s]", .min = 0, .max = 1}},
    {"computation_delay_min_s",
     &TruthOptions::computation_delay_min_s,
     nullptr,
     {.meaning = "a control cycle's command leaves the computer this long after its instant, drawn uniformly in "
                 "[min, max] per flight [s] (sim.computation_delay: measured uses the stack's own time instead)",
      .min = 0,
      .max = 0.1}},
    {"computation_delay_max_s",
     &TruthOptions::computation_delay_max_s,
     nullptr,
     {.meaning = "(set both or neither)", .min = 0, .max = 0.1}},
    {"computation_delay_jitter_fraction",
     &TruthOptions::computation_delay_jitter_fraction,
     &TruthRanges::computation_delay_jitter_fraction,
     {.meaning = "each cycle's computation delay drawn in (1 ± a) times the flight's", .min = 0, .max = 1}},
    {"esc_command_latency_min_s",
     &TruthOptions::esc_command_latency_min_s,
     nullptr,
     {.meaning = "the motors act on a command this long after it reaches the ESCs, drawn uniformly in [min, max] "
                 "per flight [s]",
      .min = 0,
      .max = 0.1}},
    {"esc_command_latency_max_s",
     &TruthOptions::esc_command_latency_max_s,
     nullptr,
     {.meaning = "(set both or neither)", .min = 0, .max = 0.1}},
    {"imu_noise_fraction",
     &TruthOptions::imu_noise_fraction,
     &TruthRanges::imu_noise_fraction,
     {.meaning = "each IMU noise density (accelerometer, gyro) drawn in (1 ± a) times the sensors.imu one",
      .min = 0,
      .max = 0.9}},
    {"lidar_rotation_rad",
     &TruthOptions::lidar_rotation_rad,
     &TruthRanges::lidar_rotation_rad,
     {.meaning = "the LiDAR's axes turned from the body's by ± a about each axis [rad]", .min = 0, .max = 0.2}},
    {"lidar_clock_offset_s",
     &TruthOptions::lidar_clock_offset_s,
     &TruthRanges::lidar_clock_offset_s,
     {.meaning = "the LiDAR's stamps off its capture times by ± a [s]", .min = 0, .max = 0.02}},
    {"imu_axial_vibration_m_s2",
     &TruthOptions::imu_axial_vibration_m_s2,
     &TruthRanges::imu_axial_vibration_m_s2,
     {.meaning = "each healthy rotor's vibration along its axis at the blade-pass frequency, at the accelerometer "
                 "at hover speed, drawn in [a/2, a] [m/s²]; ten times more after a propeller loss or damage",
      .min = 0,
      .max = 20}},
    {"gyro_vibration_gain",
     &TruthOptions::gyro_vibration_gain,
     &TruthRanges::gyro_vibration_gain,
     {.meaning = "the airframe's rocking at the gyro, the vibration forces' rigid-body moment times a frame flex "
                 "drawn in [1, a] (0: none)",
      .min = 0,
      .max = 100}},
    {"ground_effect_fraction",
     &TruthOptions::ground_effect_fraction,
     &TruthRanges::ground_effect_fraction,
     {.meaning = "the ground effect's strength drawn in (1 ± a) times sim.ground_effect.strength", .min = 0, .max = 1}},
    {"battery_fraction",
     &TruthOptions::battery_fraction,
     &TruthRanges::battery_fraction,
     {.meaning = "the battery's capacity drawn in [1 − a, 1] and its internal resistance in [1, 1 + 2a] times "
                 "sim.battery's",
      .min = 0,
      .max = 0.9}},
};

template <typename Archive>
void TruthOptions::Serialize(Archive* a) {
  a->Visit("preset", &preset, {.meaning = "`realistic`: the spread of docs/truth.md; `ideal`: the file is exact"});
  for (const TruthOverrideKey& k : kTruthOverrideKeys) {
    KeyInfo info = k.info;
    info.default_text = "the preset's";
    a->Visit(k.key, &(this->*k.override), info);
  }
}

/// One flight's vehicle as drawn: ratios to the file's values, offsets, the external torque.
struct TruthDraw {
  TruthPreset preset = TruthPreset::kIdeal;
  double mass_ratio = 1.0;
  Vector3 mass_moment_ratio = Vector3::Ones();  ///< of ∫x² dm, ∫y² dm, ∫z² dm in the body frame
  Vector3 cog_offset_m = Vector3::Zero();   ///< the true centre of gravity in the file's body frame
  std::vector<double> thrust_coefficient_ratio, yaw_coefficient_ratio;  ///< per rotor
  double motor_time_constant_ratio = 1.0;
  double motor_stop_time_constant_s = 0.0;  ///< the true value [s]
  Vector3 rotor_drag_ratio = Vector3::Ones();
  Vector3 imu_offset_m = Vector3::Zero();         ///< added to the IMU's mounting point
  Vector3 external_torque_n_m = Vector3::Zero();  ///< body frame
  double imu_vibration_m_s2 = 0.0;                ///< ImuOptions::vibration_m_s2
  std::vector<double> esc_gain;                   ///< per motor: reported / true speed (EscOptions::gain)
  double esc_dropout_probability = 0.0;           ///< EscOptions::dropout_probability
  double odometry_latency_s = 0.0;                ///< OdometryOptions::latency_s
  double odometry_drift_m_per_sqrt_s = 0.0;       ///< OdometryOptions::drift_m_per_sqrt_s
  double odometry_yaw_drift_rad_per_sqrt_s = 0.0;  ///< OdometryOptions::yaw_drift_rad_per_sqrt_s
  double odometry_few_features_gain = 0.0;         ///< OdometryOptions::few_features_gain
  double odometry_outage_rate_hz = 0.0;            ///< OdometryOptions::outage_rate_hz
  double computation_delay_s = 0.0;                ///< a control cycle's computation, the flight's [s]
  double computation_delay_jitter_fraction = 0.0;  ///< each cycle's: (1 ± this) times the flight's
  double esc_command_latency_s = 0.0;              ///< EscOptions::command_latency_s
  double imu_accel_noise_ratio = 1.0;              ///< true / the scenario's accelerometer noise density
  double imu_gyro_noise_ratio = 1.0;               ///< true / the scenario's gyro noise density
  Vector3 lidar_rotation_rad = Vector3::Zero();    ///< the LiDAR's axes: rotation vector from the body's
  double lidar_clock_offset_s = 0.0;               ///< LidarOptions::clock_offset_s
  double imu_axial_vibration_m_s2 = 0.0;           ///< ImuOptions::axial_vibration_m_s2
  double gyro_vibration_gain = 0.0;                ///< ImuOptions::gyro_vibration_gain
  double ground_effect_ratio = 1.0;                ///< true / the scenario's ground effect strength
  double battery_capacity_ratio = 1.0;             ///< true / sim.battery's capacity
  double battery_resistance_ratio = 1.0;           ///< true / sim.battery's internal resistance

  /// summary.json's "truth" object.
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("preset", &preset, {.meaning = "the scenario's truth preset"});
    a->Visit("mass_ratio", &mass_ratio, {.meaning = "true mass / the file's"});
    a->Visit("mass_moment_ratio", &mass_moment_ratio,
             {.meaning = "true second moments of mass ∫x² dm, ∫y² dm, ∫z² dm / the file's, body frame"});
    a->Visit("cog_offset_m", &cog_offset_m, {.meaning = "the true centre of gravity in the file's body frame [m]"});
    a->Visit("thrust_coefficient_ratio", &thrust_coefficient_ratio, {.meaning = "per rotor: true k_n / the file's"});
    a->Visit("yaw_coefficient_ratio", &yaw_coefficient_ratio, {.meaning = "per rotor: true κ_t / the file's"});
    a->Visit("motor_time_constant_ratio", &motor_time_constant_ratio, {.meaning = "true σ / the file's"});
    a->Visit("motor_stop_time_constant_s", &motor_stop_time_constant_s, {.meaning = "the true value [s]"});
    a->Visit("rotor_drag_ratio", &rotor_drag_ratio, {.meaning = "true D / the file's, per axis"});
    a->Visit("imu_offset_m", &imu_offset_m, {.meaning = "the IMU's true mounting point minus sensors.imu's [m]"});
    a->Visit("external_torque_n_m", &external_torque_n_m, {.meaning = "constant torque, body frame [N·m]"});
    a->Visit("imu_vibration_m_s2", &imu_vibration_m_s2,
             {.meaning = "a healthy rotor's vibration at hover speed [m/s²]"});
    a->Visit("esc_gain", &esc_gain, {.meaning = "per motor: reported / true speed"});
    a->Visit("esc_dropout_probability", &esc_dropout_probability, {.meaning = "a telemetry frame's loss probability"});
    a->Visit("odometry_latency_s", &odometry_latency_s,
             {.meaning = "from an odometry sample's capture to its arrival [s]"});
    a->Visit("odometry_drift_m_per_sqrt_s", &odometry_drift_m_per_sqrt_s,
             {.meaning = "the odometry frame's position random walk [m/√s]"});
    a->Visit("odometry_yaw_drift_rad_per_sqrt_s", &odometry_yaw_drift_rad_per_sqrt_s,
             {.meaning = "the odometry frame's yaw random walk [rad/√s]"});
    a->Visit("odometry_few_features_gain", &odometry_few_features_gain,
             {.meaning = "growth of odometry noise and drift with no obstacle in view"});
    a->Visit("odometry_outage_rate_hz", &odometry_outage_rate_hz,
             {.meaning = "how often the odometry loses track [1/s]"});
    a->Visit("computation_delay_s", &computation_delay_s,
             {.meaning = "a control cycle's computation delay, the flight's mean [s]"});
    a->Visit("computation_delay_jitter_fraction", &computation_delay_jitter_fraction,
             {.meaning = "each cycle's computation delay lies within (1 ± this) of the mean"});
    a->Visit("esc_command_latency_s", &esc_command_latency_s,
             {.meaning = "from a command's arrival at the ESCs to the motors acting on it [s]"});
    a->Visit("imu_accel_noise_ratio", &imu_accel_noise_ratio,
             {.meaning = "true accelerometer noise density / the scenario's"});
    a->Visit("imu_gyro_noise_ratio", &imu_gyro_noise_ratio, {.meaning = "true gyro noise density / the scenario's"});
    a->Visit("lidar_rotation_rad", &lidar_rotation_rad,
             {.meaning = "the LiDAR's axes: rotation vector from the body's [rad]"});
    a->Visit("lidar_clock_offset_s", &lidar_clock_offset_s,
             {.meaning = "the LiDAR's stamps minus its capture times [s]"});
    a->Visit("imu_axial_vibration_m_s2", &imu_axial_vibration_m_s2,
             {.meaning = "a healthy rotor's axial vibration at hover speed, blade-pass frequency [m/s²]"});
    a->Visit("gyro_vibration_gain", &gyro_vibration_gain,
             {.meaning = "the airframe's rocking over the vibration forces' rigid-body moment"});
    a->Visit("ground_effect_ratio", &ground_effect_ratio,
             {.meaning = "true ground effect strength / sim.ground_effect.strength"});
    a->Visit("battery_capacity_ratio", &battery_capacity_ratio, {.meaning = "true battery capacity / sim.battery's"});
    a->Visit("battery_resistance_ratio", &battery_resistance_ratio,
             {.meaning = "true battery internal resistance / sim.battery's"});
  }
};

/// The draw of `ranges` for `vehicle` with `seed`: a pure function of its arguments. Zero ranges
/// give the identity (ratios 1, offsets 0, the file's stop time constant) without drawing.
TruthDraw DrawTruth(const TruthOptions& options, const vehicle::VehicleParams& vehicle, std::uint64_t seed);

/// The inertia of a body whose mass spreads `ratio` times as far (in second moment) along each
/// body axis: ∫x² dm, ∫y² dm, ∫z² dm scale by the ratios. Errors of a CAD or measured inertia are
/// errors in where the mass is; scaling the principal moments independently instead can turn a
/// flat vehicle (I_zz the largest moment) into a tall one, and that changes the physics of the
/// spin after a rotor failure, which balances tilting torques gyroscopically through I_zz − I_xx.
Matrix3 ScaleMassMoments(const Matrix3& inertia, const Vector3& ratio);

/// The simulated vehicle of `draw`: the file's with its mass, moments, drag, yaw coefficients and
/// time constants scaled, and its rotors placed about the true centre of gravity. The per-rotor
/// thrust coefficients are not a vehicle-file quantity: they go to the model (ThrustRatios).
vehicle::VehicleParams TruthVehicle(const vehicle::VehicleParams& file, const TruthDraw& draw);

/// The per-rotor thrust of the simulated motors relative to what the file's k_n gives for the
/// same speed (MultirotorModel's thrust_ratio).
RotorVector ThrustRatios(const TruthDraw& draw);

/// The scenario's simulator options with the sensors and disturbances of `draw`: the IMU and the
/// LiDAR where they really are about the true centre of gravity (the LiDAR turned and its clock
/// off), the IMU's noise and vibration (given at `file`'s hover speed), the external torque, the
/// ESC's gains, lost frames and command latency, the odometry's latency, drift and outages and the
/// frame whose pose it reports (the file's body frame).
SimulatorOptions TruthSimulatorOptions(const SimulatorOptions& scenario, const vehicle::VehicleParams& file,
                                       const TruthDraw& draw);

}  // namespace rotorguard::sim
