#include "rotorguard/stack/flight_stack.h"

#include <cmath>

#include <fmt/format.h>

#include "rotorguard/core/error.h"

namespace rotorguard::stack {

control::IndiControllerOptions IndiOptionsInStack(const FlightStackOptions& o) {
  control::IndiControllerOptions indi = o.indi;
  indi.sample_hz = o.control_rate_hz;
  indi.nominal = o.nominal;
  return indi;
}

void FlightStackOptions::Validate() const {
  if (!std::isfinite(control_rate_hz) || control_rate_hz <= 0.0 || control_rate_hz > 10000.0) {
    ThrowValidation("FlightStackOptions", "control_rate_hz", control_rate_hz, "a rate in (0, 10000] Hz");
  }
  if (controller != "nominal" && controller != "nmpc" && controller != "passive" && controller != "indi") {
    ThrowValidation("FlightStackOptions", "controller", controller, "one of: nominal, nmpc, passive, indi");
  }
  nominal.Validate();
  passive.Validate();
  nmpc.Validate();
  if (controller == "indi") IndiOptionsInStack(*this).Validate();  // its filters depend on the rate
  for (std::size_t i = 0; i < known_faults.size(); ++i) {
    if (!std::isfinite(known_faults[i].at_time_s) || known_faults[i].at_time_s < 0.0) {
      ThrowValidation("FlightStackOptions", fmt::format("known_faults.{}.at_time_s", i), known_faults[i].at_time_s,
                      "a time >= 0 s");
    }
  }
  if (fdd != "none" && fdd != "composite" && fdd != "fixedtime") {
    ThrowValidation("FlightStackOptions", "fdd", fdd, "one of: none, composite, fixedtime");
  }
  composite_fdd.Validate();
  fixed_time_fdd.Validate();
  lidar.Validate();
  if (!known_faults.empty() && controller != "nmpc" && controller != "indi") {
    ThrowValidation("FlightStackOptions", "known_faults", controller,
                    "controller nmpc or indi (the controllers that reconfigure)");
  }
}

FlightStack::FlightStack(const vehicle::VehicleParams& vehicle,
                         std::shared_ptr<const ReferenceTrajectory> reference,
                         const FlightStackOptions& options)
    : model_(vehicle),
      reference_(std::move(reference)),
      options_(options),
      estimator_(model_.params().thrust_coefficient_n_s2),
      mapper_(options.lidar) {
  options_.Validate();
  if (!reference_) throw std::invalid_argument("FlightStack: reference is null; expected a trajectory");
  if (options_.controller == "nmpc") {
    auto nmpc = std::make_unique<control::NmpcController>(model_.params(), options_.nmpc);
    nmpc_ = nmpc.get();
    controller_ = std::move(nmpc);
  } else if (options_.controller == "indi") {
    controller_ = std::make_unique<control::IndiController>(model_, IndiOptionsInStack(options_));
  } else if (options_.controller == "passive") {
    controller_ = std::make_unique<control::PassiveController>(model_, options_.passive);
  } else {
    controller_ = std::make_unique<control::NominalController>(model_, options_.nominal);
  }
  for (std::size_t i = 0; i < options_.known_faults.size(); ++i) {
    const int rotor = options_.known_faults[i].rotor;
    if (rotor < 0 || rotor >= model_.num_rotors()) {
      ThrowValidation("FlightStackOptions", fmt::format("known_faults.{}.rotor", i), rotor,
                      fmt::format("a rotor index in [0, {}]", model_.num_rotors() - 1));
    }
  }
  known_fault_applied_.assign(options_.known_faults.size(), false);
  if (options_.fdd == "composite") fdd_ = std::make_unique<fdd::CompositeFdd>(model_.params(), options_.composite_fdd);
  if (options_.fdd == "fixedtime") fdd_ = std::make_unique<fdd::FixedTimeFdd>(model_.params(), options_.fixed_time_fdd);
  control_period_ns_ = PeriodFromRate(options_.control_rate_hz);
  command_.thrust_n = RotorVector::Zero(model_.num_rotors());
}

void FlightStack::OnImu(const ImuSample& imu) {
  estimator_.OnImu(imu);
  mapper_.OnImu(imu);
  if (fdd_) fdd_->OnImu(imu);
}

void FlightStack::OnEscTelemetry(const EscTelemetry& esc) {
  estimator_.OnEscTelemetry(esc);
  if (fdd_) fdd_->OnEscTelemetry(esc);
}

void FlightStack::OnOdometry(const OdometrySample& odometry) { estimator_.OnOdometry(odometry); }

void FlightStack::OnLidar(const LidarFrame& frame) {
  lidar_points_dropped_ += mapper_.OnFrame(frame, estimator_.Estimate(frame.t_end_ns)).points_dropped;
}

const RotorCommand& FlightStack::Update(TimeNs t) {
  const double dt = last_update_ns_ ? ToSeconds(t - *last_update_ns_) : 0.0;
  last_update_ns_ = t;
  estimate_ = estimator_.Estimate(t);
  reference_point_ = reference_->Evaluate(ToSeconds(t));
  command_.t_ns = t;
  if (!estimate_.valid) {
    // Nothing to act on yet: motors idle (a vehicle on the ground stays there).
    command_.thrust_n.setZero();
    return command_;
  }
  for (std::size_t i = 0; i < options_.known_faults.size(); ++i) {
    if (!known_fault_applied_[i] && ToSeconds(t) >= options_.known_faults[i].at_time_s) {
      controller_->SetRotorFailed(options_.known_faults[i].rotor);
      known_fault_applied_[i] = true;
    }
  }
  if (fdd_) {
    fdd_->SetEstimate(estimate_);
    // Isolation reconfigures the controller (the NMPC: u_bar_i = 0, yaw given up, post-failure
    // thrust reference); controllers that cannot reconfigure ignore it.
    for (int rotor : fdd_->TakeNewIsolations()) controller_->SetRotorFailed(rotor);
  }
  controller_->Compute(estimate_, *reference_, ToSeconds(t), dt, &command_.thrust_n);
  if (fdd_) fdd_->SetCommand(command_.thrust_n);
  return command_;
}

}  // namespace rotorguard::stack
