#include "rotorguard/stack/flight_stack.h"

#include <cmath>

#include "rotorguard/core/error.h"

namespace rotorguard::stack {

void FlightStackOptions::Validate() const {
  if (!std::isfinite(control_rate_hz) || control_rate_hz <= 0.0 || control_rate_hz > 10000.0) {
    ThrowValidation("FlightStackOptions", "control_rate_hz", control_rate_hz, "a rate in (0, 10000] Hz");
  }
  if (controller != "nominal") {
    ThrowValidation("FlightStackOptions", "controller", controller, "one of: nominal");
  }
  nominal.Validate();
}

FlightStack::FlightStack(const vehicle::VehicleParams& vehicle,
                         std::shared_ptr<const ReferenceTrajectory> reference,
                         const FlightStackOptions& options)
    : model_(vehicle), reference_(std::move(reference)), options_(options) {
  options_.Validate();
  if (!reference_) throw std::invalid_argument("FlightStack: reference is null; expected a trajectory");
  controller_ = std::make_unique<control::NominalController>(model_, options_.nominal);
  control_period_ns_ = PeriodFromRate(options_.control_rate_hz);
  command_.thrust_n = RotorVector::Zero(model_.num_rotors());
}

void FlightStack::OnImu(const ImuSample& imu) { estimator_.OnImu(imu); }

void FlightStack::OnEscTelemetry(const EscTelemetry& /*esc*/) {
  // Consumed by fault detection once it exists; the nominal stack does not use it.
}

void FlightStack::OnOdometry(const OdometrySample& odometry) { estimator_.OnOdometry(odometry); }

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
  controller_->Compute(estimate_, reference_point_, dt, &command_.thrust_n);
  return command_;
}

}  // namespace rotorguard::stack
