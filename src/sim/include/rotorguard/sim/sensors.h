#pragma once
/// Sensor models: IMU, ESC telemetry, odometry. Each owns its random stream (derived from the run
/// seed) so that adding or retuning one sensor does not change the noise of another.
#include <cstdint>
#include <deque>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/core/types.h"
#include "rotorguard/sim/world.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::sim {

struct ImuOptions {
  double rate_hz = 333.0;                    ///< paper 000, Sec. IV-B; (0, physics rate]
  Vector3 position_m = Vector3(0.02, 0.0, 0.03);  ///< mounting point relative to the CoG, body frame
  double accel_noise_density = 2.0e-3;       ///< white noise [m/s^2/sqrt(Hz)], >= 0
  double gyro_noise_density = 1.7e-4;        ///< white noise [rad/s/sqrt(Hz)], >= 0
  double accel_bias_random_walk = 3.0e-3;    ///< bias diffusion [m/s^3/sqrt(Hz)], >= 0
  double gyro_bias_random_walk = 2.0e-5;     ///< bias diffusion [rad/s^2/sqrt(Hz)], >= 0
  double accel_bias_initial = 0.02;          ///< std of the bias at start [m/s^2], >= 0
  double gyro_bias_initial = 2.0e-3;         ///< std of the bias at start [rad/s], >= 0
  double accel_range_m_s2 = 16.0 * kGravity;  ///< each accelerometer axis saturates at ± this, > 0
  double gyro_range_rad_s = 34.906585039886590;  ///< each gyro axis saturates at ± this (2000 °/s), > 0
  /// The airframe's vibration at the accelerometer (truth side: set from the scenario's truth, not
  /// a sensor key). Each rotor's imbalance shakes the body in the rotor plane at the rotor's speed
  /// ω, with amplitude vibration_m_s2 (ω / vibration_reference_speed_rad_s)² (a centrifugal
  /// force), vibration_fault_factor times larger for a rotor whose propeller is lost or damaged.
  double vibration_m_s2 = 0.0;
  double vibration_reference_speed_rad_s = 1.0;
  double vibration_fault_factor = 10.0;
  /// Beyond the in-plane shaking, as the amplitudes above scale: each rotor's force along its
  /// axis at the blade-pass frequency (twice the rotor's, a two-bladed propeller) at the
  /// accelerometer [m/s²].
  double axial_vibration_m_s2 = 0.0;
  /// The airframe's rocking that these forces make, from rigid-body mechanics: each rotor's
  /// imbalance force m a at its hub r_i (rotor_positions_m, from the centre of gravity) turns the
  /// airframe by I⁻¹ (r_i × m a); the gyro reads its integral at the force's frequency, the
  /// accelerometer at `position_m` the tangential acceleration. Times gyro_vibration_gain (>= 0; 0
  /// without rocking), for what a flexing frame adds. Needs airframe_mass_kg and the inverse
  /// inertia (the truth's vehicle); empty rotor positions: no rocking.
  double gyro_vibration_gain = 0.0;
  std::vector<Vector3> rotor_positions_m;
  double airframe_mass_kg = 1.0;
  Matrix3 airframe_inverse_inertia = Matrix3::Identity();
  void Validate(double physics_rate_hz) const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("rate_hz", &rate_hz,
             {.meaning = "sample rate [Hz], at most the physics rate", .min = kMinRateHz, .max = kMaxRateHz});
    a->Visit("position_m", &position_m,
             {.meaning = "mounting point from the centre of gravity, body frame [m]",
              .min = -kMaxBodyOffsetM,
              .max = kMaxBodyOffsetM});
    // The noise bounds are a hundred to a thousand times a consumer MEMS IMU's (an MPU-6000's
    // accelerometer density is 4e-3 m/s²/√Hz, its gyro's 9e-4 rad/s/√Hz).
    a->Visit("accel_noise_density", &accel_noise_density,
             {.meaning = "accelerometer white noise [m/s²/√Hz]", .min = 0.0, .max = 1.0});
    a->Visit("gyro_noise_density", &gyro_noise_density,
             {.meaning = "gyro white noise [rad/s/√Hz]", .min = 0.0, .max = 0.1});
    a->Visit("accel_bias_random_walk", &accel_bias_random_walk,
             {.meaning = "accelerometer bias diffusion [m/s³/√Hz]", .min = 0.0, .max = 1.0});
    a->Visit("gyro_bias_random_walk", &gyro_bias_random_walk,
             {.meaning = "gyro bias diffusion [rad/s²/√Hz]", .min = 0.0, .max = 0.1});
    a->Visit("accel_bias_initial", &accel_bias_initial,
             {.meaning = "std of the accelerometer bias at the start [m/s²]", .min = 0.0, .max = kGravity});
    a->Visit("gyro_bias_initial", &gyro_bias_initial,
             {.meaning = "std of the gyro bias at the start [rad/s]", .min = 0.0, .max = 1.0});
    // Up to the ±200 g of shock accelerometers and ±11 500 °/s.
    a->Visit("accel_range_m_s2", &accel_range_m_s2,
             {.meaning = "each accelerometer axis saturates at ± this [m/s²] (16 g)", .max = 2000.0, .positive = true});
    a->Visit("gyro_range_rad_s", &gyro_range_rad_s,
             {.meaning = "each gyro axis saturates at ± this [rad/s] (2000 °/s)", .max = 200.0, .positive = true});
  }
};

struct EscOptions {
  double rate_hz = 1000.0;      ///< telemetry rate; (0, physics rate]
  double noise_rpm = 20.0;      ///< white measurement noise [rpm], >= 0
  double quantization_rpm = 10.0;  ///< reported resolution [rpm], >= 0 (0: none)
  double delay_s = 0.001;       ///< transport delay, >= 0 and < 0.5 s
  /// Truth side (set from the scenario's truth, not sensor keys): each motor's reported speed
  /// relative to its true speed (empty: 1 for every motor), and the probability that a telemetry
  /// frame is lost (a CRC error on the wire), in [0, 1).
  std::vector<double> gain;
  double dropout_probability = 0.0;
  /// Truth side: from a command's arrival at the ESCs to the motors acting on it [s], in [0, 0.5)
  /// (the command protocol's frame, the ESC's own loop; Simulator::Send).
  double command_latency_s = 0.0;
  void Validate(double physics_rate_hz) const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("rate_hz", &rate_hz,
             {.meaning = "telemetry rate [Hz], at most the physics rate", .min = kMinRateHz, .max = kMaxRateHz});
    // A multirotor's motors turn at a few thousand to 30 000 rpm.
    a->Visit("noise_rpm", &noise_rpm, {.meaning = "white measurement noise [rpm]", .min = 0.0, .max = 5000.0});
    a->Visit("quantization_rpm", &quantization_rpm,
             {.meaning = "reported resolution [rpm] (0: none)", .min = 0.0, .max = 5000.0});
    a->Visit("delay_s", &delay_s,
             {.meaning = "transport delay [s], below 0.5 s", .min = 0.0, .max = 0.5, .open_max = true});
  }
};

struct OdometryOptions {
  double rate_hz = 100.0;              ///< (0, physics rate]
  double position_noise_m = 0.005;     ///< std at rest [m], >= 0
  double velocity_noise_m_s = 0.01;    ///< std at rest [m/s], >= 0
  double attitude_noise_rad = 0.002;   ///< std of each small-angle component at rest [rad], >= 0
  /// Noise grows with body rate: std = std_at_rest * (1 + rate_noise_gain * |w_B|) [per rad/s].
  double rate_noise_gain = 0.1;
  /// Intervals [start, start + duration) [s] in which no odometry arrives (the odometry front end
  /// lost track): what the stack's estimator must notice.
  struct Outage {
    double start_s = 0.0;
    double duration_s = 0.0;

    template <typename Archive>
    void Serialize(Archive* a) {
      a->Visit("start_s", &start_s,
               {.meaning = "when the front end loses track [s]", .min = 0.0, .max = kMaxFlightS, .required = true});
      a->Visit("duration_s", &duration_s,
               {.meaning = "for how long [s]", .min = 0.0, .max = kMaxFlightS, .required = true});
    }
  };
  std::vector<Outage> outages;
  /// Truth side (set from the scenario's truth, not sensor keys): how a LiDAR-inertial front end
  /// departs from the truth. Each sample is stamped when its scan was captured and arrives
  /// latency_s later. Its frame drifts from the world's by a random walk in position and yaw.
  /// Noise and drift grow with the body rate (rate_noise_gain) and where the front end sees few
  /// features: by 1 + few_features_gain (1 - n / features_reference) when only n < reference
  /// obstacles lie within feature_range_m. It loses track at random (a Poisson process of
  /// outage_rate_hz), each time for a duration drawn uniformly in [outage_min_s, outage_max_s].
  double latency_s = 0.0;
  double drift_m_per_sqrt_s = 0.0;
  double yaw_drift_rad_per_sqrt_s = 0.0;
  double few_features_gain = 0.0;
  int features_reference = 8;
  double feature_range_m = 20.0;
  double outage_rate_hz = 0.0;
  double outage_min_s = 0.05, outage_max_s = 0.3;
  /// Truth side: where the vehicle file's body frame (the frame whose pose a front end reports)
  /// has its origin, from the true centre of gravity, body frame [m]: minus the drawn offset.
  Vector3 body_origin_m = Vector3::Zero();
  /// Whether time t [s] lies in an outage.
  bool InOutage(double t) const;
  void Validate(double physics_rate_hz) const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("rate_hz", &rate_hz,
             {.meaning = "rate [Hz], at most the physics rate", .min = kMinRateHz, .max = kMaxRateHz});
    // Up to a GNSS fix's metres and a tenth of a radian: the noise of any front end worth flying on.
    a->Visit("position_noise_m", &position_noise_m, {.meaning = "position std at rest [m]", .min = 0.0, .max = 10.0});
    a->Visit("velocity_noise_m_s", &velocity_noise_m_s,
             {.meaning = "velocity std at rest [m/s]", .min = 0.0, .max = 10.0});
    a->Visit("attitude_noise_rad", &attitude_noise_rad,
             {.meaning = "attitude std at rest, per small-angle component [rad]", .min = 0.0, .max = 0.5});
    a->Visit("rate_noise_gain", &rate_noise_gain,
             {.meaning = "the stds grow as (1 + gain·|ω|) [per rad/s]", .min = 0.0, .max = 100.0});
    a->Visit("outages", &outages, {.meaning = "intervals without odometry (the front end lost track)"});
  }
};

/// What a sensor sees of the truth at one instant.
struct TruthSample {
  TimeNs t_ns = 0;
  const vehicle::StateVector* x = nullptr;
  vehicle::Accelerations acc;
  RotorVector motor_speed_rad_s;
  const vehicle::RotorFaults* faults = nullptr;  ///< none: every rotor healthy
};

class ImuModel {
 public:
  ImuModel(const ImuOptions& options, std::uint64_t seed);
  ImuSample Sample(const TruthSample& truth);
  const Vector3& accel_bias() const { return accel_bias_; }
  const Vector3& gyro_bias() const { return gyro_bias_; }

 private:
  /// The airframe's vibration now, added to the accelerometer and the gyro, each rotor's phase
  /// advanced by one sample.
  void AddVibration(const TruthSample& truth, ImuSample* sample);

  ImuOptions options_;
  Rng rng_;
  double dt_;
  Vector3 accel_bias_, gyro_bias_;
  bool vibrates_ = false;
  std::vector<double> rotor_phase_;  ///< each rotor's angle [rad], for the vibration
};

/// ESC telemetry with noise, quantisation and a transport delay (a ring buffer of samples).
class EscModel {
 public:
  EscModel(const EscOptions& options, int num_rotors, std::uint64_t seed);
  /// Takes a measurement now (call at the ESC rate); it is delivered `delay_s` later.
  void Measure(const TruthSample& truth);
  /// The newest measurement whose delay has elapsed at time t, if one is waiting (call every
  /// physics step, so the delay is honoured to the physics step whatever the ESC rate).
  bool Deliver(TimeNs t, EscTelemetry* delivered);

 private:
  EscOptions options_;
  Rng rng_;
  int num_rotors_;
  TimeNs delay_ns_;
  std::vector<EscTelemetry> ring_;
  std::size_t head_ = 0, count_ = 0;
};

/// A LiDAR-inertial front end's odometry: noise, drift, a latency, outages (OdometryOptions).
class OdometryModel {
 public:
  /// Keeps a reference to `world` (its obstacles are the front end's features).
  OdometryModel(const OdometryOptions& options, const World& world, std::uint64_t seed);
  /// Captures a sample now (call at the odometry rate); it is delivered `latency_s` later, unless
  /// the front end has lost track.
  void Measure(const TruthSample& truth);
  /// The oldest captured sample whose latency has elapsed at time t, if one is waiting (call every
  /// physics step).
  bool Deliver(TimeNs t, OdometrySample* delivered);
  /// Whether the front end has lost track at time t: a scheduled outage or a random one.
  bool InOutage(TimeNs t);
  /// The drift of the front end's frame: position [m] and yaw [rad] of the world in it.
  const Vector3& drift_m() const { return drift_p_; }
  double drift_yaw_rad() const { return drift_yaw_; }

 private:
  /// The factor by which noise and drift grow where few obstacles are in view, >= 1.
  double FewFeaturesFactor(const Vector3& p_W, double t) const;

  OdometryOptions options_;
  const World& world_;
  Rng rng_, drift_rng_, outage_rng_;
  double dt_;
  TimeNs latency_ns_;
  Vector3 drift_p_ = Vector3::Zero();
  double drift_yaw_ = 0.0;
  TimeNs random_outage_end_ns_ = -1;
  std::deque<OdometrySample> pending_;
};

/// Fires every `period` on an integer-nanosecond grid; polled at physics steps.
class RateTimer {
 public:
  RateTimer() = default;
  explicit RateTimer(double rate_hz) : period_ns_(PeriodFromRate(rate_hz)) {}
  /// True (once) when t has reached the next tick; the following tick is one period later.
  bool Due(TimeNs t) {
    if (t < next_ns_) return false;
    while (next_ns_ <= t) next_ns_ += period_ns_;
    return true;
  }

 private:
  TimeNs period_ns_ = 1;
  TimeNs next_ns_ = 0;
};

}  // namespace rotorguard::sim
