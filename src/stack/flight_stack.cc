
#include "rotorguard/stack/flight_stack.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "rotorguard/control/allocation.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/core/stopwatch.h"

namespace rotorguard::stack {

namespace {

/// Adds the wall-clock time of its scope to *total [s].
class ScopedCost {
 public:
  explicit ScopedCost(double* total) : total_(total) {}
  ScopedCost(const ScopedCost&) = delete;
  ScopedCost& operator=(const ScopedCost&) = delete;
  ~ScopedCost() { *total_ += clock_.seconds(); }

 private:
  double* total_;
  Stopwatch clock_;
};

}  // namespace

control::IndiControllerOptions IndiOptionsInStack(const FlightStackOptions& o) {
  control::IndiControllerOptions indi = o.indi;
  indi.sample_hz = o.control_rate_hz;
  indi.nominal = o.nominal;
  return indi;
}

void FlightStackOptions::Validate() const {
  if (!std::isfinite(control_rate_hz) || control_rate_hz < kMinRateHz || control_rate_hz > kMaxRateHz) {
    ThrowValidation("FlightStackOptions", "control_rate_hz", control_rate_hz,
                    fmt::format("a rate in [{:g}, {:g}] Hz", kMinRateHz, kMaxRateHz));
  }
  nominal.Validate();
  passive.Validate();
  nmpc.Validate();
  if (controller == ControllerKind::kIndi) IndiOptionsInStack(*this).Validate();  // its filters depend on the rate
  lqr.Validate();
  for (std::size_t i = 0; i < known_faults.size(); ++i) {
    CheckDeclaredRanges("FlightStackOptions", known_faults[i], fmt::format("known_faults.{}.", i));
    if (known_faults[i].loss < 1.0 && controller != ControllerKind::kAssembly) {
      ThrowValidation("FlightStackOptions", fmt::format("known_faults.{}.loss", i), known_faults[i].loss,
                      "1 unless the controller is assembly (the one that reallocates a partial loss)");
    }
  }
  composite_fdd.Validate();
  fixed_time_fdd.Validate();
  ukf_fdd.Validate();
  lidar.Validate();
  estimator.Validate();
  supervisor.Validate();
  if (!navigation.waypoints.empty()) {
    navigation.Validate();
    if (navigation.planner_rate_hz > control_rate_hz) {
      ThrowValidation("FlightStackOptions", "navigation.planner_rate_hz", navigation.planner_rate_hz,
                      "a rate in (0, control_rate_hz]");
    }
    // The planner asks the map for each penalty sample's nearest obstacle within plane_search_m,
    // widened to the clearances it keeps (ReplannerOptions::WidenPlaneSearch); beyond the map's
    // fast search radius every query scans a cube. Found by generating flights (tests/fuzz):
    // clearance_m 10 made a 2.6-s forest flight plan for minutes.
    const planning::ReplannerOptions& r = navigation.replanner;
    const double resolution_m = lidar.map.resolution_m;
    const double fast_m = perception::VoxelMap::FastNearestRadiusM(resolution_m);
    for (const auto& [field, clearance] :
         {std::pair{"planner.clearance_m", r.planner.optimizer.clearance_m},
          std::pair{"planner.post_failure_clearance_m", r.post_failure_clearance_m.value_or(0.0)}}) {
      if (clearance > fast_m) {
        ThrowValidation("FlightStackOptions", field, clearance,
                        fmt::format("a distance of at most {:.3g} m: the planner's obstacle search reaches 12 "
                                    "voxels less half a diagonal (map.resolution_m = {:g} m)",
                                    fast_m, resolution_m));
      }
    }
    // plane_search_m is no key: beyond the clearances, it is the map that is too fine for it.
    if (const double search_m = r.planner.plane_search_m; search_m > fast_m) {
      ThrowValidation("FlightStackOptions", "map.resolution_m", resolution_m,
                      fmt::format("a voxel edge of at least {:.3g} m: the planner searches {:g} m around each "
                                  "sample, within 12 voxels less half a diagonal",
                                  resolution_m * search_m / fast_m, search_m));
    }
  }
  if (!known_faults.empty() && controller != ControllerKind::kNmpc && controller != ControllerKind::kIndi &&
      controller != ControllerKind::kAssembly) {
    ThrowValidation("FlightStackOptions", "known_faults", ToName(controller),
                    "controller nmpc, indi or assembly (the controllers that reconfigure)");
  }
}

FlightStack::FlightStack(const vehicle::VehicleParams& vehicle, std::shared_ptr<const ReferenceTrajectory> reference,
                         const FlightStackOptions& options, std::unique_ptr<control::Controller> controller)
    : model_(vehicle),
      reference_(std::move(reference)),
      options_(options),
      supervisor_(options.supervisor),
      imu_filter_(vehicle.num_rotors(), options.imu_notch) {
  options_.Validate();
  if (!reference_) throw std::invalid_argument("FlightStack: reference is null; expected a trajectory");
  {
    // The stack starts where its mission does, at rest: the LiDAR-inertial odometry's frame.
    const ReferencePoint start = reference_->Evaluate(0.0);
    const double k_n = model_.params().thrust_coefficient_n_s2;
    estimator_ = MakeControlEstimator(k_n, options_.estimator);
    lio_head_ = dynamic_cast<LioHeadEstimator*>(estimator_.get());
    perception_ = std::make_unique<PerceptionTask>(k_n, options_.estimator, options_.lidar, start.p_W, start.yaw);
  }
  if (controller) {
    if (controller->name() != ToName(options_.controller)) {
      ThrowValidation("FlightStackOptions", "controller", ToName(options_.controller),
                      fmt::format("the name of the controller handed in ({})", controller->name()));
    }
    controller_ = std::move(controller);
  } else {
    // One case per kind, no default: a kind added to ControllerKind without its construction here
    // fails to compile (-Wswitch).
    switch (options_.controller) {
      case ControllerKind::kAssembly:
        ThrowValidation("FlightStackOptions", "controller", ToName(options_.controller),
                        "a controller built by the caller (the assembly controller lives in the modular module)");
      case ControllerKind::kNmpc: {
        control::NmpcOptions nmpc_options = options_.nmpc;
        nmpc_options.expected_delay_s = options_.command_delay_s;
        auto nmpc = std::make_unique<control::NmpcController>(model_.params(), nmpc_options);
        nmpc_ = nmpc.get();
        controller_ = std::move(nmpc);
        break;
      }
      case ControllerKind::kIndi:
        controller_ = std::make_unique<control::IndiController>(model_, IndiOptionsInStack(options_));
        break;
      case ControllerKind::kLqr: {
        control::LqrControllerOptions lqr = options_.lqr;
        lqr.sample_hz = options_.control_rate_hz;
        controller_ =
            std::make_unique<control::LqrController>(vehicle::PwmQuadModel::FromVehicle(model_.params()), lqr);
        break;
      }
      case ControllerKind::kPassive:
        controller_ = std::make_unique<control::PassiveController>(model_, options_.passive);
        break;
      case ControllerKind::kNominal:
        controller_ = std::make_unique<control::NominalController>(model_, options_.nominal);
        break;
    }
  }
  for (std::size_t i = 0; i < options_.known_faults.size(); ++i) {
    const int rotor = options_.known_faults[i].rotor;
    if (rotor < 0 || rotor >= model_.num_rotors()) {
      ThrowValidation("FlightStackOptions", fmt::format("known_faults.{}.rotor", i), rotor,
                      fmt::format("a rotor index in [0, {}]", model_.num_rotors() - 1));
    }
  }
  known_fault_applied_.assign(options_.known_faults.size(), false);
  planning_events_.reserve(2 * kMaxRotors);  // the cycle raises them without allocating
  degraded_told_.assign(static_cast<std::size_t>(model_.num_rotors()), false);
  effectiveness_.assign(static_cast<std::size_t>(model_.num_rotors()), 1.0);
  for (const vehicle::Rotor& r : model_.params().rotors) rotor_max_thrust_n_.push_back(r.max_thrust_n);
  // Every detector models the motors as acting on a command after the delay the stack expects.
  const auto delayed = [this](auto detector_options) {
    detector_options.command_delay_s = options_.command_delay_s;
    return detector_options;
  };
  switch (options_.fdd) {
    case FddKind::kComposite: {
      // It compares the notched IMU with its telemetry's wrench, which it notches alike.
      fdd::CompositeFddOptions o = delayed(options_.composite_fdd);
      o.imu_notch = options_.imu_notch;
      fdd_ = std::make_unique<fdd::CompositeFdd>(model_.params(), o);
      break;
    }
    case FddKind::kFixedTime:
      fdd_ = std::make_unique<fdd::FixedTimeFdd>(model_.params(), delayed(options_.fixed_time_fdd));
      break;
    case FddKind::kUkf:
      fdd_ = std::make_unique<fdd::UkfFdd>(model_.params(), delayed(options_.ukf_fdd));
      break;
    case FddKind::kNone:
      break;
  }
  control_period_ns_ = PeriodFromRate(options_.control_rate_hz);
  command_.thrust_n = RotorVector::Zero(model_.num_rotors());
  planning_ = PlanningTask::Make(model_.params(), options_.navigation, reference_->Evaluate(0.0));
  if (planning_) plan_ = planning_->followed();
}

FlightStack::Tasks FlightStack::DetachTasks() {
  tasks_detached_ = true;
  return {perception_.get(), planning_.get()};
}

void FlightStack::OnImu(const ImuSample& raw) {
  // The odometry (both its frames' side and the controller's head) and the mapper integrate the
  // raw samples (PerceptionTask::OnImu says why). What reads rates and accelerations sample by
  // sample, the fault detection and the controller's body rates, reads them notched.
  Eigen::Matrix<double, 6, 1> x;
  x << raw.specific_force_B, raw.w_B;
  const Eigen::Matrix<double, 6, 1> y = imu_filter_.Filter(x);
  ImuSample filtered = raw;
  filtered.specific_force_B = y.head<3>();
  filtered.w_B = y.tail<3>();
  if (!tasks_detached_) perception_->OnImu(raw);
  estimator_->OnImu(raw);
  if (!tasks_detached_) TakeOdometryUpdate();
  if (fdd_) fdd_->OnImu(filtered);
  if (raw.w_B.allFinite() && filtered.w_B.allFinite()) rate_notch_correction_ = filtered.w_B - raw.w_B;
}

void FlightStack::OnEscTelemetry(const EscTelemetry& esc) {
  imu_filter_.OnRotorSpeeds(esc.t_ns, esc.motor_speed_rad_s);
  estimator_->OnEscTelemetry(esc);
  if (!tasks_detached_) perception_->OnEscTelemetry(esc);
  if (fdd_) fdd_->OnEscTelemetry(esc);
}

void FlightStack::OnOdometry(const OdometrySample& odometry) { estimator_->OnOdometry(odometry); }

void FlightStack::OnBattery(const BatteryStatus& battery) {
  if (!std::isfinite(battery.voltage_v)) return;  // a power module's glitch: the last good one stays
  battery_ = battery;
  battery_min_voltage_v_ = std::min(battery_min_voltage_v_.value_or(battery.voltage_v), battery.voltage_v);
}

void FlightStack::OnLidar(const LidarFrame& frame) {
  RG_INVARIANT(!tasks_detached_, "FlightStack::OnLidar: the perception task runs elsewhere (DetachTasks)");
  perception_->OnFrame(frame, FrameEstimate(frame));
  TakeOdometryUpdate();
}

void FlightStack::TakeOdometryUpdate() {
  // In one thread the controller's estimate takes each update as it is made: it is then the
  // odometry's own (an onboard executor hands it over when the perception task publishes it).
  if (!lio_head_) return;
  if (const std::optional<LioUpdate> u = perception_->update()) OnLioUpdate(*u);
}

std::uint64_t FlightStack::lio_serial() const { return lio_head_ ? lio_head_->serial() : 0; }

void FlightStack::OnLioUpdate(const LioUpdate& update) {
  if (lio_head_ && update.posterior.serial > lio_head_->serial()) lio_head_->OnLioUpdate(update);
}

void FlightStack::OnRotorFailed(int rotor, double t, double onset) {
  if (std::any_of(reconfigurations_.begin(), reconfigurations_.end(),
                  [rotor](const RotorReconfiguration& r) { return r.rotor == rotor; })) {
    return;
  }
  reconfigurations_.push_back({rotor, t});
  // Can the rotors left hold the vehicle? The supervisor acts on the answer.
  std::vector<bool> failed(static_cast<std::size_t>(model_.num_rotors()), false);
  std::vector<int> failed_rotors;
  for (const RotorReconfiguration& r : reconfigurations_) {
    failed[static_cast<std::size_t>(r.rotor)] = true;
    failed_rotors.push_back(r.rotor);
  }
  if (!control::HoverThrustSplit(model_.params(), failed)) {
    std::sort(failed_rotors.begin(), failed_rotors.end());
    cannot_hover_ = fmt::format(
        "rotors {} failed: no thrusts within the limits of the others hold the weight with zero roll and pitch torque",
        fmt::join(failed_rotors, ", "));
  }
  if (nmpc_) nmpc_->RewindDisturbance(onset);
  if (fallback_nmpc_) fallback_nmpc_->RewindDisturbance(onset);
  controller_->SetRotorFailed(rotor);
  if (fallback_) fallback_->SetRotorFailed(rotor);
  planning_events_.push_back({PlanningEvent::Kind::kFailure, 0.0});
}

void FlightStack::OnRotorDegraded(int rotor, double effectiveness, double onset) {
  // The FDD's estimate improves sample by sample: changes below a percent are its noise, and each
  // one the NMPC takes costs it a re-linearisation and the planner a new limit.
  constexpr double kChange = 0.01;
  const double eta = std::clamp(effectiveness, 0.0, 1.0);
  const auto i = static_cast<std::size_t>(rotor);
  // A detector's estimate may come back to 1 (the UKF's): "told" is its own flag.
  if (degraded_told_[i] && std::abs(eta - effectiveness_[i]) < kChange) return;
  if (!degraded_told_[i] && nmpc_) nmpc_->RewindDisturbance(onset);
  if (!degraded_told_[i] && fallback_nmpc_) fallback_nmpc_->RewindDisturbance(onset);
  degraded_told_[i] = true;
  effectiveness_[i] = eta;
  controller_->SetRotorEffectiveness(rotor, eta);
  if (fallback_) fallback_->SetRotorEffectiveness(rotor, eta);
  // The planner keeps to what the weakened vehicle can still accelerate (failure-aware only).
  planning_events_.push_back(
      {PlanningEvent::Kind::kAccelerationLimit,
       std::max(0.05, planning::DegradedAccelerationLimit(options_.navigation.replanner.nominal.a_max,
                                                          model_.params().weight_n(), rotor_max_thrust_n_,
                                                          effectiveness_))});
}

FaultEstimates FlightStack::PlanningFaults() const {
  // Only the flatness navigator reads them. Any detection starts the flatness navigator's hold; the UKF's losses and settling drive its
  // re-plan (other detectors give their eta and are taken as settled).
  FaultEstimates f;
  if (!fdd_ || !planning_ || !planning_->flatness()) return f;
  for (int i = 0; i < std::min(4, model_.num_rotors()); ++i) {
    const fdd::RotorStatus& r = fdd_->rotors()[static_cast<std::size_t>(i)];
    f.w_hat[i] = std::clamp(r.eta, 0.0, 0.99);
    f.detected = f.detected || r.detected_s.has_value();
  }
  if (const auto* ukf = dynamic_cast<const fdd::UkfFdd*>(fdd_.get())) f.settled = ukf->settled();
  return f;
}

const RotorCommand& FlightStack::Update(TimeNs t) {
  RG_INVARIANT(!tasks_detached_, "FlightStack::Update: the tasks run elsewhere (DetachTasks); use BeginCycle, EndCycle");
  // Lockstep: the planning task runs between the cycle's halves, on what they hand it at once.
  const FlightMode mode = BeginCycle(t, planning_ ? planning_->status() : PlanStatus{});
  if (planning_) {
    for (const PlanningEvent& e : planning_events_) planning_->OnEvent(e);
  }
  if (!landing_ && planning_) {
    const ScopedCost cost(&cost_.planner_s);
    planning_->Update(ToSeconds(t), mode, map(), PlanningFaults());
  }
  return EndCycle(t, mode, planning_ ? planning_->followed() : nullptr);
}

FlightMode FlightStack::BeginCycle(TimeNs t, const PlanStatus& plan) {
  planning_events_.clear();
  cycle_dt_s_ = last_update_ns_ ? ToSeconds(t - *last_update_ns_) : 0.0;
  last_update_ns_ = t;
  estimate_ = estimator_->Estimate(t);
  estimate_.w_B += rate_notch_correction_;  // the controller's rates: the estimator's, notched
  const double ts = ToSeconds(t);
  command_.t_ns = t;
  if (estimate_.valid) {
    for (std::size_t i = 0; i < options_.known_faults.size(); ++i) {
      if (!known_fault_applied_[i] && ts >= options_.known_faults[i].at_time_s) {
        const KnownFault& k = options_.known_faults[i];
        if (k.loss >= 1.0) {
          OnRotorFailed(k.rotor, ts, k.at_time_s);
        } else {
          OnRotorDegraded(k.rotor, 1.0 - k.loss, k.at_time_s);
        }
        known_fault_applied_[i] = true;
      }
    }
    if (fdd_) {
      fdd_->SetEstimate(estimate_);
      // Isolation reconfigures the controller (the NMPC: u_bar_i = 0, yaw given up, post-failure
      // thrust reference; controllers that cannot reconfigure ignore it) and the planner.
      const std::vector<fdd::RotorStatus>& rotors = fdd_->rotors();
      for (int rotor : fdd_->TakeNewIsolations()) OnRotorFailed(rotor, ts, rotors[rotor].onset_s.value_or(ts));
      // A partial loss reaches the controller as the rotor's effectiveness, 1 - eta, updated as
      // the FDD's estimate of eta improves.
      for (std::size_t i = 0; i < rotors.size(); ++i) {
        if (rotors[i].health == fdd::RotorHealth::kDegraded) {
          OnRotorDegraded(static_cast<int>(i), 1.0 - rotors[i].eta, rotors[i].onset_s.value_or(ts));
        }
      }
    }
  }
  SupervisorInputs in;
  in.t = ts;
  in.estimate = estimate_;
  in.odometry_age_s = estimator_->odometry_age_s(t);
  in.isolated_rotors = isolated_rotors();
  in.navigating = plan.navigating;
  in.since_last_plan_s = ts - plan.last_plan_ok_s;
  in.thrust_ratio = command_.thrust_n.sum() / model_.params().weight_n();
  in.cannot_hover = cannot_hover_;
  in.landing = !landing_ && reference().Evaluate(ts).p_W.z() <= 0.0;  // a mission that lands
  if (plan.land_request) in.land_request = "re-planning decided to land: " + *plan.land_request;
  const FlightMode mode = supervisor_.Update(in);

  if (mode == FlightMode::kEmergencyLanding && !landing_) {
    // Straight down from where the vehicle is, aiming below the ground (z = 0) so that it gets
    // there even with a drifted estimate, keeping the heading.
    planning::TakeoffOptions o;
    o.start_m = supervisor_.landing_start();
    o.altitude_m = -(std::max(0.0, o.start_m.z()) + options_.supervisor.landing_depth_m);
    o.max_speed_m_s = options_.supervisor.landing_speed_m_s;
    o.yaw_rad = reference_point_.yaw;
    landing_.emplace(o);
    descent_.emplace(*landing_, supervisor_.landing_start_s());
  }
  return mode;
}

const RotorCommand& FlightStack::EndCycle(TimeNs t, FlightMode mode, std::shared_ptr<const ReferenceTrajectory> plan) {
  const double ts = ToSeconds(t);
  const double dt = cycle_dt_s_;
  if (plan) plan_ = std::move(plan);
  const ReferenceTrajectory& followed = descent_ ? *descent_ : plan_ ? *plan_ : *reference_;
  reference_point_ = followed.Evaluate(ts);
  // The vehicle cannot hover: the parachute's release goes out with the stopped motors' command,
  // and with every command after it (an output that stays set, as a flight controller's does).
  command_.release_parachute = command_.release_parachute || mode == FlightMode::kFlightTermination;
  if (!estimate_.valid || mode == FlightMode::kLanded || mode == FlightMode::kFlightTermination) {
    // Nothing to act on yet, on the ground after a landing, or a vehicle that cannot hover: motors
    // off, and the fault detection told so (it stays armed: a motor that keeps turning after the
    // landing is still a fault, and one spinning down as commanded is none).
    command_.thrust_n.setZero();
    if (fdd_) fdd_->SetCommand(command_);
    return command_;
  }
  {
    const ScopedCost cost(&cost_.controller_s);
    // The fallback runs every cycle, so that its filters are warm when it takes over; once it
    // has, the controller that was too slow no longer runs.
    if (fallback_) fallback_->Compute(estimate_, followed, ts, dt, &fallback_command_);
    if (fallback_flying_ && fallback_) {
      command_.thrust_n = fallback_command_;
    } else {
      controller_->Compute(estimate_, followed, ts, dt, &command_.thrust_n);
    }
  }
  if (fdd_) fdd_->SetCommand(command_);
  return command_;
}

RotorVector FlightStack::HeldCommand(TimeNs t) const {
  RotorVector u = command_.thrust_n;
  if (command_.thrust_n.isZero()) return u;  // motors stopped (landed, terminated, not flying yet)
  flying_controller().PlannedCommand(ToSeconds(t), &u);
  return u;
}

void FlightStack::PrepareFallback() {
  RG_INVARIANT(!last_update_ns_, "FlightStack::PrepareFallback: before the first cycle");
  if (fallback_ || !nmpc_) return;
  // The same NMPC, fault-aware as the flown one, at a fraction of its cost: half the horizon and
  // a mixed-level iteration (Jacobians and the condensed factorisation reused between
  // re-linearisations). The INDI controller would cost less still, but taking over from the NMPC
  // in the spin of a failed rotor it tumbles (tilt about 1 rad, docs/runtime.md).
  control::NmpcOptions reduced = nmpc_->options();
  reduced.horizon_steps = std::max(1, reduced.horizon_steps / 2);
  reduced.relinearise_every = std::max(reduced.relinearise_every, 4);
  auto nmpc = std::make_unique<control::NmpcController>(model_.params(), reduced);
  fallback_nmpc_ = nmpc.get();
  fallback_ = std::move(nmpc);
  fallback_command_ = RotorVector::Zero(model_.num_rotors());
}

void FlightStack::OnDeadline(const DeadlineEvent& e) {
  if (e.step == DeadlineStep::kFallback) fallback_flying_ = true;
  supervisor_.OnDeadline(e, flying_controller().name());
}

const RotorCommand& FlightStack::OverrideCommand(const RotorVector& thrust_n) {
  RG_INVARIANT(thrust_n.size() == model_.num_rotors() && thrust_n.allFinite(),
               "OverrideCommand: one finite thrust per rotor");
  command_.thrust_n = thrust_n;
  if (fdd_) fdd_->SetCommand(command_);
  return command_;
}

const LioEstimator* FlightStack::lio() const { return perception_->lio(); }

StackCost FlightStack::cost() const {
  StackCost c = cost_;
  c.estimator_s = perception_->odometry_s();
  c.mapper_s = perception_->mapper_s();
  return c;
}

FlightStackSummary FlightStack::Summarize() const {
  FlightStackSummary s;
  if (planning_) s.navigation = planning_->Summarize();
  if (const planning::FlatnessNavigator* f = flatness()) s.flatness_decisions = f->decisions();
  if (const auto* ukf = dynamic_cast<const fdd::UkfFdd*>(fdd_.get())) {
    const Eigen::VectorXd w = ukf->loss();
    s.ukf = UkfSummary{std::vector<double>(w.data(), w.data() + w.size()), ukf->settled_after_detection_s()};
  }
  s.final_mode = supervisor_.mode();
  s.transitions = supervisor_.transitions();
  if (const perception::VoxelMap* m = map()) s.map_voxels_occupied = m->occupied_count();
  s.lidar_points_dropped = lidar_points_dropped();
  s.battery_min_voltage_v = battery_min_voltage_v_;
  if (const LioEstimator* odometry = lio()) s.odometry = odometry->Summarize();
  s.reconfigurations = reconfigurations_;
  s.deadline_events = supervisor_.deadline_events();
  return s;
}

}  // namespace rotorguard::stack
