#include "rotorguard/sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"

namespace rotorguard::sim {

namespace {
using vehicle::StateIndex;
using vehicle::StateView;

// Independent random streams of one run.
enum Stream : std::uint64_t { kImuStream = 1, kEscStream = 2, kOdometryStream = 3, kWindStream = 4, kLidarStream = 5 };

// What the world does at a state besides the air on the rotors, for the integrator's every
// stage: the ground pushes on the feet that touch it and on the rotors' wakes, an open parachute
// drags. Built where it is used (it points into the simulator).
class ExternalWrench final : public vehicle::StateWrench {
 public:
  ExternalWrench(const GroundContact& contact, const GroundEffect& effect, const vehicle::RotorFaults& faults,
                 const Parachute& parachute)
      : contact_(contact), effect_(effect), faults_(faults), parachute_(parachute) {}
  void AddTo(const vehicle::StateVector& x, vehicle::Disturbance* d) const override {
    contact_.AddTo(x, d);
    effect_.AddTo(x, faults_, d);
    parachute_.AddTo(x, d);
  }

 private:
  const GroundContact& contact_;
  const GroundEffect& effect_;
  const vehicle::RotorFaults& faults_;
  const Parachute& parachute_;
};
// The power module's message, when its time has come (a fitted battery only).
void SampleBattery(const Battery& battery, TimeNs t_ns, RateTimer* timer, SensorOutputs* outputs) {
  if (battery.options().fitted && timer->Due(t_ns)) outputs->battery = battery.Status(t_ns);
}
}  // namespace

const SimulatorOptions& Simulator::Validated(const SimulatorOptions& options,
                                             const vehicle::VehicleParams& vehicle) {
  options.Validate(vehicle);
  return options;
}

void SimulatorOptions::Validate(const vehicle::VehicleParams& vehicle) const {
  if (!std::isfinite(physics_rate_hz) || physics_rate_hz <= 0.0 || physics_rate_hz > kMaxPhysicsRateHz) {
    ThrowValidation("SimulatorOptions", "sim.physics_rate_hz", physics_rate_hz,
                    fmt::format("a rate in (0, {:g}] Hz", kMaxPhysicsRateHz));
  }
  // RK4 on a first-order lag is stable for dt < 2.78 sigma and accurate for dt well below sigma:
  // require dt <= sigma / 2 for the fastest motor time constant.
  const double fastest = std::min(vehicle.motor_time_constant_s, vehicle.motor_stop_time_constant_s);
  if (1.0 / physics_rate_hz > 0.5 * fastest) {
    ThrowValidation("SimulatorOptions", "sim.physics_rate_hz", physics_rate_hz,
                    fmt::format("a rate >= {:g} Hz: the step must be at most half the fastest motor "
                                "time constant ({:g} s)",
                                2.0 / fastest, fastest));
  }
  // Sub-options report their fields under the scenario keys they come from.
  const auto prefixed = [](const std::string& prefix, const auto& validate) {
    try {
      validate();
    } catch (const ValidationError& e) {
      throw ValidationError(prefix + e.field(), e.what());
    }
  };
  prefixed("sensors.imu.", [&] { imu.Validate(physics_rate_hz); });
  prefixed("sensors.esc.", [&] { esc.Validate(physics_rate_hz); });
  prefixed("sensors.odometry.", [&] { odometry.Validate(physics_rate_hz); });
  prefixed("wind.", [&] { wind.Validate(); });
  if (lidar.enabled) {
    prefixed("sensors.lidar.", [&] { lidar.Validate(); });
    if (lidar.frame_rate_hz > 0.5 * physics_rate_hz) {
      ThrowValidation("SimulatorOptions", "sensors.lidar.frame_rate_hz", lidar.frame_rate_hz,
                      fmt::format("a rate of at most {:g} Hz (half the physics rate)", 0.5 * physics_rate_hz));
    }
  }
  if (!std::isfinite(crash_speed_m_s) || crash_speed_m_s <= 0.0 || crash_speed_m_s > kMaxSpeedMS) {
    ThrowValidation("SimulatorOptions", "sim.crash_speed_m_s", crash_speed_m_s,
                    fmt::format("a speed in (0, {:g}] m/s", kMaxSpeedMS));
  }
  if (!std::isfinite(crash_tilt_rad) || crash_tilt_rad <= 0.0 || crash_tilt_rad > std::numbers::pi) {
    ThrowValidation("SimulatorOptions", "sim.crash_tilt_rad", crash_tilt_rad, "an angle in (0, pi]");
  }
  prefixed("sim.ground.", [&] { ground.Validate(); });
  prefixed("sim.ground_effect.", [&] { ground_effect.Validate(); });
  prefixed("sim.parachute.", [&] { parachute.Validate(); });
  prefixed("sim.battery.", [&] { battery.Validate(); });
  if (ground_z_m && !(std::abs(*ground_z_m) <= kMaxCoordinateM)) {
    ThrowValidation("SimulatorOptions", "ground_z_m", *ground_z_m, fmt::format("a height within ±{:g} m", kMaxCoordinateM));
  }
}

namespace {

World OnGround(World world, double ground_z_m) {
  world.ground_z_m = ground_z_m;
  return world;
}

}  // namespace

Simulator::Simulator(const vehicle::MultirotorModel& model, World world, std::vector<FaultSpec> faults,
                     const SimulatorOptions& options, std::uint64_t seed, const vehicle::StateVector& initial)
    : model_(model),
      world_(OnGround(std::move(world), options.ground_z_m.value_or(-model.params().RestingHeight()))),
      options_(Validated(options, model.params())),
      injector_(std::move(faults), model.num_rotors()),
      integrator_(model),
      contact_(model.params().LandingGear(), model.params().mass_kg, options_.ground,
               GroundPlane{.normal_W = Vector3::UnitZ(), .offset_m = world_.ground_z_m}),
      ground_effect_(model, options_.ground_effect, contact_.plane()),
      parachute_(options_.parachute),
      battery_(options_.battery, model.params()),
      imu_(options_.imu, DeriveSeed(seed, kImuStream)),
      esc_(options_.esc, model.num_rotors(), DeriveSeed(seed, kEscStream)),
      odometry_(options_.odometry, world_, DeriveSeed(seed, kOdometryStream)),
      wind_(options_.wind, DeriveSeed(seed, kWindStream)),
      imu_timer_(options_.imu.rate_hz),
      esc_timer_(options_.esc.rate_hz),
      odometry_timer_(options_.odometry.rate_hz),
      battery_timer_(options_.battery.rate_hz),
      dt_ns_(PeriodFromRate(options_.physics_rate_hz)),
      x_(initial),
      faults_(model.num_rotors()) {
  if (options_.lidar.enabled) lidar_.emplace(options_.lidar, world_, DeriveSeed(seed, kLidarStream));
  if (initial.size() != model.state_size() || !initial.allFinite()) {
    throw std::invalid_argument(fmt::format(
        "Simulator: initial state has size {} or non-finite entries; expected {} finite values",
        initial.size(), model.state_size()));
  }
  x_.segment<4>(StateIndex::kQuaternion).normalize();
  // A start at z <= 0 (the file's body origin at rest), or feet at or below the ground: the
  // vehicle stands on them, at rest, its lowest feet sunk as far as its weight presses them (all
  // of them, on a level start). A drawn centre of gravity above the file's stands higher.
  if (const double depth = contact_.Depth(x_); x_[StateIndex::kPosition + 2] <= 0.0 || depth >= 0.0) {
    x_[StateIndex::kPosition + 2] += depth - contact_.standing_sink_m();
    x_.segment<3>(StateIndex::kVelocity).setZero();
    x_.segment<3>(StateIndex::kBodyRate).setZero();
  }
  contact_.Update(x_);
  landed_ = contact_.points_in_contact() > 0;
  // Before the first command acts, the ESCs hold what the motors do (a flight that starts in the
  // air has been commanded its hover before).
  command_ = x_.tail(model.num_rotors()).cwiseMax(0.0).cwiseMin(model.max_thrust());
  command_latency_ns_ = FromSeconds(options_.esc.command_latency_s);
  UpdateOutputs();
  vehicle::Disturbance still_air;
  still_air.wind_W = wind_.velocity();
  still_air.torque_B = options_.external_torque_n_m;
  SampleSensors(still_air);
  SampleBattery(battery_, t_ns_, &battery_timer_, &outputs_);
}

void Simulator::SampleSensors(const vehicle::Disturbance& disturbance) {
  // Sensors sample the state at the current time (the end of a step).
  const bool imu_due = imu_timer_.Due(t_ns_);
  const bool esc_due = esc_timer_.Due(t_ns_);
  const bool odom_due = odometry_timer_.Due(t_ns_);
  if (!(imu_due || esc_due || odom_due)) {
    DeliverTelemetry();
    return;
  }
  TruthSample truth;
  truth.t_ns = t_ns_;
  truth.x = &x_;
  // The ground's push on the feet and the wakes, and a parachute's drag, are felt as any other force.
  vehicle::Disturbance external = disturbance;
  ExternalWrench(contact_, ground_effect_, faults_, parachute_).AddTo(x_, &external);
  truth.acc = model_.ComputeAccelerations(x_, faults_, external);
  truth.motor_speed_rad_s = speed_;
  truth.faults = &faults_;
  if (imu_due) outputs_.imu = imu_.Sample(truth);
  if (esc_due) esc_.Measure(truth);
  if (odom_due && !odometry_.InOutage(t_ns_)) odometry_.Measure(truth);
  DeliverTelemetry();
}

void Simulator::DeliverTelemetry() {
  EscTelemetry telemetry;
  if (esc_.Deliver(t_ns_, &telemetry)) outputs_.esc = telemetry;
  OdometrySample odometry;
  if (odometry_.Deliver(t_ns_, &odometry)) outputs_.odometry = odometry;
}

void Simulator::UpdateOutputs() {
  model_.RotorThrusts(x_, faults_, &thrust_);
  model_.MotorSpeeds(x_, faults_, &speed_);
}

void Simulator::ResolveGroundContact() {
  const bool was_touching = landed_;
  contact_.Update(x_);
  landed_ = contact_.points_in_contact() > 0;
  if (!landed_) return;
  const StateView s(x_);
  const double speed = s.v_W().norm();
  const double tilt = TiltOf(s.q_WB());
  if (!was_touching && speed > options_.crash_speed_m_s) {
    crash_reason_ = fmt::format("ground impact at {:.2f} m/s", speed);
  } else if (tilt > options_.crash_tilt_rad) {
    // Tipped over its feet: the propellers strike the ground.
    crash_reason_ = fmt::format("ground contact tilted {:.0f} deg", tilt * 180.0 / std::numbers::pi);
  } else if (s.p_W().z() <= world_.ground_z_m) {
    crash_reason_ = "the body on the ground";
  }
  if (crash_reason_) crash_speed_m_s_ = speed;
}

void Simulator::Send(const RotorCommand& command, TimeNs sent_ns) {
  if (sent_ns < t_ns_) {
    ThrowInvalidArgument("Simulator::Send", "sent_ns", static_cast<double>(sent_ns),
                         fmt::format("a time at or after the simulator's, {} ns", t_ns_));
  }
  TimeNs acts = sent_ns + command_latency_ns_;
  if (queue_size_ > 0) {
    // In the order sent: never before the command queued last.
    acts = std::max(acts, queue_[static_cast<std::size_t>((queue_head_ + queue_size_ - 1) % kCommandQueue)].acts_ns);
  }
  if (queue_size_ == kCommandQueue) {  // full: the oldest acts now
    Act(queue_[static_cast<std::size_t>(queue_head_)], t_ns_);
    queue_head_ = (queue_head_ + 1) % kCommandQueue;
    --queue_size_;
    ++commands_overrun_;
  }
  SentCommand& slot = queue_[static_cast<std::size_t>((queue_head_ + queue_size_) % kCommandQueue)];
  slot.acts_ns = acts;
  slot.release_parachute = command.release_parachute;
  // A non-finite command reaches the motors as zero thrust (a real ESC would reject the frame).
  slot.thrust_n.resize(model_.num_rotors());
  for (int i = 0; i < model_.num_rotors(); ++i) {
    const double u = i < command.thrust_n.size() ? command.thrust_n[i] : 0.0;
    slot.thrust_n[i] = std::isfinite(u) ? std::clamp(u, 0.0, model_.max_thrust()[i]) : 0.0;
  }
  ++queue_size_;
}

void Simulator::Act(const SentCommand& c, TimeNs t) {
  command_ = c.thrust_n;
  if (c.release_parachute) parachute_.Release(t);
}

void Simulator::ActivateCommands(TimeNs t) {
  while (queue_size_ > 0 && queue_[static_cast<std::size_t>(queue_head_)].acts_ns <= t) {
    const SentCommand& c = queue_[static_cast<std::size_t>(queue_head_)];
    Act(c, c.acts_ns);
    queue_head_ = (queue_head_ + 1) % kCommandQueue;
    --queue_size_;
  }
}

const SensorOutputs& Simulator::Step(const RotorCommand& command) {
  if (!crashed()) Send(command, t_ns_);
  return Step();
}

const SensorOutputs& Simulator::Step() {
  outputs_ = SensorOutputs{};
  if (crashed()) return outputs_;
  const double dt = ToSeconds(dt_ns_);
  injector_.Update(t_ns_, x_[StateIndex::kPosition + 2], !landed_, &faults_);
  if (!thrust_limit_at_first_fault_ && !injector_.events().empty()) {
    thrust_limit_at_first_fault_ = battery_.thrust_limit_ratio();
  }
  vehicle::Disturbance disturbance;
  disturbance.wind_W = wind_.Step(dt);
  disturbance.torque_B = options_.external_torque_n_m;
  x_before_ = x_;
  // The step in pieces where a command starts acting within it (a delayed command acts from its
  // own instant, not from the next step's).
  const TimeNs end = t_ns_ + dt_ns_;
  TimeNs t = t_ns_;
  ActivateCommands(t);
  parachute_.Update(t);
  const ExternalWrench external(contact_, ground_effect_, faults_, parachute_);
  // The battery's sag over the step lowers every rotor's largest thrust (its voltage at the step's
  // start: the load changes over the motors' time constant, tens of steps).
  const double limit = battery_.thrust_limit_ratio();
  const auto acting = [&] {
    return limit < 1.0 ? RotorVector(command_.cwiseMin(limit * model_.max_thrust())) : command_;
  };
  while (queue_size_ > 0 && queue_[static_cast<std::size_t>(queue_head_)].acts_ns < end) {
    const TimeNs next = queue_[static_cast<std::size_t>(queue_head_)].acts_ns;
    integrator_.Step(acting(), faults_, disturbance, ToSeconds(next - t), &x_, &external);
    t = next;
    ActivateCommands(t);
  }
  integrator_.Step(acting(), faults_, disturbance, t == t_ns_ ? dt : ToSeconds(end - t), &x_, &external);
  t_ns_ = end;
  ActivateCommands(t_ns_);  // applied_command(): the one acting at the new time
  UpdateOutputs();
  if (!x_.allFinite()) {
    crash_reason_ = "state diverged (non-finite)";
    x_ = x_before_;
    return outputs_;
  }
  battery_.Step(thrust_, speed_, dt);
  SampleBattery(battery_, t_ns_, &battery_timer_, &outputs_);
  ResolveGroundContact();
  if (!crash_reason_ && !landed_) {
    const StateView s(x_);
    const vehicle::VehicleParams& v = model_.params();
    if (v.collision_spheres.empty()) {
      if (auto hit = world_.SphereCollision(s.p_W(), v.collision_radius_m, time_s())) crash_reason_ = "collision with " + *hit;
    } else {
      const Matrix3 R = s.q_WB().toRotationMatrix();
      for (const vehicle::CollisionSphere& c : v.collision_spheres) {
        if (auto hit = world_.SphereCollision(s.p_W() + R * c.centre_B, c.radius_m, time_s())) {
          crash_reason_ = "collision with " + *hit;
          break;
        }
      }
    }
  }

  if (lidar_) {
    // Each pulse is cast from the pose at its own time within this step.
    const StateView before(x_before_), after(x_);
    outputs_.lidar = lidar_->Step(t_ns_ - dt_ns_, BodyPose{before.p_W(), before.q_WB()}, t_ns_,
                                  BodyPose{after.p_W(), after.q_WB()});
  }
  SampleSensors(disturbance);
  return outputs_;
}

}  // namespace rotorguard::sim
