#pragma once
/// The simulator: truth dynamics at the physics rate (RK4), motors and injected faults, wind,
/// ground contact, collisions, and the sensors at their own rates. Bit-for-bit deterministic for
/// a seed; never reads the wall clock.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rotorguard/core/messages.h"
#include "rotorguard/sim/battery.h"
#include "rotorguard/sim/contact.h"
#include "rotorguard/sim/fault_injector.h"
#include "rotorguard/sim/ground_effect.h"
#include "rotorguard/sim/parachute.h"
#include "rotorguard/sim/lidar.h"
#include "rotorguard/sim/sensors.h"
#include "rotorguard/sim/wind.h"
#include "rotorguard/sim/world.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::sim {

/// [Hz]: the fastest physics rate, a 10 µs step, what a motor time constant of 20 µs would need
/// (the step must be at most half of it); every step is one RK4 step of the whole vehicle.
inline constexpr double kMaxPhysicsRateHz = 1e5;

struct SimulatorOptions {
  /// RK4 step rate, in (0, kMaxPhysicsRateHz]; dt must be <= half the fastest motor time constant.
  double physics_rate_hz = 1000.0;
  ImuOptions imu;
  EscOptions esc;
  OdometryOptions odometry;
  LidarOptions lidar;  ///< off by default
  WindOptions wind;
  /// A constant torque on the airframe, body frame [N*m]: a payload or cable the stack is not told
  /// of. Not a scenario key: the scenario's truth draws it (truth.h).
  Vector3 external_torque_n_m = Vector3::Zero();
  /// The ground under the landing gear's feet (contact.h).
  GroundContactOptions ground;
  /// The ground's push on the rotors' wakes (ground_effect.h).
  GroundEffectOptions ground_effect;
  /// A recovery parachute the stack's release signal deploys (parachute.h); none by default.
  ParachuteOptions parachute;
  /// The flight battery, whose sag lowers the rotors' largest thrust (battery.h); none by default.
  BatteryOptions battery;
  /// The ground plane's height [m]; none: where the model's feet reach when its centre of gravity
  /// rests at z = 0. (A drawn truth passes the file's: its body origin rests at z = 0.)
  std::optional<double> ground_z_m;
  /// Touching the ground faster than this (any direction) is a crash [m/s], in (0, kMaxSpeedMS].
  double crash_speed_m_s = 1.0;
  /// Touching the ground tilted more than this is a crash [rad], in (0, pi]: tipped over.
  double crash_tilt_rad = 0.6;
  /// Throws ValidationError whose field is the scenario key path ("sim.physics_rate_hz",
  /// "sensors.esc.rate_hz", "wind.gust_std_m_s"); needs the vehicle for the time-constant rule.
  void Validate(const vehicle::VehicleParams& vehicle) const;
};

/// Sensor messages produced at the end of one physics step.
struct SensorOutputs {
  std::optional<ImuSample> imu;
  std::optional<EscTelemetry> esc;
  std::optional<OdometrySample> odometry;
  std::optional<LidarFrame> lidar;  ///< a frame completed in this step
  /// The battery's voltage and current, with a fitted battery (handed to the stack in lockstep
  /// only; not among count()'s: the onboard runtime does not take it).
  std::optional<BatteryStatus> battery;
  /// The messages of the step (what a stack's intake counts).
  int count() const { return imu.has_value() + esc.has_value() + odometry.has_value() + lidar.has_value(); }
};

class Simulator {
 public:
  /// `initial` is the full truth state; a vehicle at z <= 0, or whose feet reach the ground,
  /// starts standing on them, at rest.
  Simulator(const vehicle::MultirotorModel& model, World world, std::vector<FaultSpec> faults,
            const SimulatorOptions& options, std::uint64_t seed, const vehicle::StateVector& initial);

  /// Commands that can wait for their instant at once (a ring: nothing allocated in flight).
  static constexpr int kCommandQueue = 32;

  /// Hands `command` (thrust per rotor [N]) to the ESCs at time `sent_ns`, at or after the current
  /// time: the motors act on it `sensors.esc` command latency later, switching at that instant
  /// within a physics step (not rounded to the step). Commands act in the order they are sent: one
  /// sent before a queued one's instant waits for it. At most kCommandQueue wait; sending more
  /// makes the oldest act at once (counted by commands_overrun()).
  void Send(const RotorCommand& command, TimeNs sent_ns);
  /// Advances one physics step, each command sent acting from its instant on; returns the sensor
  /// messages due at the new time. Does nothing once crashed.
  const SensorOutputs& Step();
  /// Send(command, time_ns()) and Step(): without an ESC latency, `command` holds over the step.
  const SensorOutputs& Step(const RotorCommand& command);

  /// Sensor messages of the latest step (at construction: those sampled at t = 0).
  const SensorOutputs& outputs() const { return outputs_; }
  TimeNs time_ns() const { return t_ns_; }
  double time_s() const { return ToSeconds(t_ns_); }
  TimeNs step_ns() const { return dt_ns_; }
  const vehicle::MultirotorModel& model() const { return model_; }
  const vehicle::StateVector& state() const { return x_; }
  const vehicle::RotorFaults& faults() const { return faults_; }
  const std::vector<FaultEvent>& fault_events() const { return injector_.events(); }
  /// Thrust each rotor applies now out of ground effect [N], and each motor's speed [rad/s].
  const RotorVector& rotor_thrusts() const { return thrust_; }
  const RotorVector& motor_speeds() const { return speed_; }
  /// Commands after saturation to [0, T_bar], as the motors see them (the one acting now).
  const RotorVector& applied_command() const { return command_; }
  /// Commands that had to act early because kCommandQueue were waiting.
  std::uint64_t commands_overrun() const { return commands_overrun_; }
  const Vector3& wind() const { return wind_.velocity(); }
  const World& world() const { return world_; }
  /// A foot touches the ground.
  bool landed() const { return landed_; }
  const GroundContact& contact() const { return contact_; }
  const GroundEffect& ground_effect() const { return ground_effect_; }
  /// The parachute (RotorCommand::release_parachute; fitted or not, it records the release).
  const Parachute& parachute() const { return parachute_; }
  /// The flight battery (fitted or not).
  const Battery& battery() const { return battery_; }
  /// The battery's thrust_limit_ratio() at the first fault's onset (the margin the failure meets);
  /// none before a fault.
  std::optional<double> thrust_limit_at_first_fault() const { return thrust_limit_at_first_fault_; }
  bool crashed() const { return crash_reason_.has_value(); }
  const std::optional<std::string>& crash_reason() const { return crash_reason_; }
  /// The speed [m/s] at the crash's ground contact; none without a crash.
  std::optional<double> crash_speed_m_s() const { return crash_speed_m_s_; }

 private:
  void ResolveGroundContact();
  void UpdateOutputs();
  void SampleSensors(const vehicle::Disturbance& disturbance);
  void DeliverTelemetry();
  /// Validates before any member is built from the options (throws ValidationError).
  static const SimulatorOptions& Validated(const SimulatorOptions& options,
                                           const vehicle::VehicleParams& vehicle);
  /// The waiting commands whose instant has come (at or before t) act, in order.
  void ActivateCommands(TimeNs t);

  struct SentCommand {
    TimeNs acts_ns = 0;
    RotorVector thrust_n;
    bool release_parachute = false;
  };
  /// A sent command acts from t: the motors take its thrusts; its release reaches the parachute.
  void Act(const SentCommand& c, TimeNs t);
  std::array<SentCommand, kCommandQueue> queue_;
  int queue_head_ = 0, queue_size_ = 0;
  TimeNs command_latency_ns_ = 0;
  std::uint64_t commands_overrun_ = 0;

  const vehicle::MultirotorModel& model_;
  World world_;
  SimulatorOptions options_;
  FaultInjector injector_;
  vehicle::Rk4Integrator integrator_;
  GroundContact contact_;
  GroundEffect ground_effect_;
  Parachute parachute_;
  Battery battery_;
  std::optional<double> thrust_limit_at_first_fault_;
  ImuModel imu_;
  EscModel esc_;
  OdometryModel odometry_;
  WindModel wind_;
  std::optional<LidarSimulator> lidar_;
  RateTimer imu_timer_, esc_timer_, odometry_timer_, battery_timer_;
  TimeNs t_ns_ = 0;
  TimeNs dt_ns_;
  vehicle::StateVector x_, x_before_;
  vehicle::RotorFaults faults_;
  RotorVector thrust_, speed_, command_;
  bool landed_ = false;
  std::optional<std::string> crash_reason_;
  std::optional<double> crash_speed_m_s_;
  SensorOutputs outputs_;
};

}  // namespace rotorguard::sim
