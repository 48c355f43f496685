#pragma once
/// FlightStack: what flies on the vehicle. Sensor messages in, rotor commands out. It is built from
/// its own copy of the vehicle parameters (the stack's model, not the simulator's truth) and a
/// mission reference.
#include <memory>
#include <string>

#include "rotorguard/control/controller.h"
#include "rotorguard/control/nominal_controller.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/stack/estimator.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::stack {

struct FlightStackOptions {
  double control_rate_hz = 200.0;    ///< controller rate (paper 000: 200 Hz), in (0, 10000]
  std::string controller = "nominal";  ///< controller name; one of: nominal
  control::NominalControllerOptions nominal;
  /// Throws ValidationError naming the field.
  void Validate() const;
};

class FlightStack {
 public:
  FlightStack(const vehicle::VehicleParams& vehicle, std::shared_ptr<const ReferenceTrajectory> reference,
              const FlightStackOptions& options);

  void OnImu(const ImuSample& imu);
  void OnEscTelemetry(const EscTelemetry& esc);
  void OnOdometry(const OdometrySample& odometry);
  /// One control cycle at time t: estimate, reference, controller. Call every control_period_ns().
  const RotorCommand& Update(TimeNs t);

  TimeNs control_period_ns() const { return control_period_ns_; }
  const StateEstimate& estimate() const { return estimate_; }
  const ReferencePoint& reference_point() const { return reference_point_; }
  const RotorCommand& command() const { return command_; }
  const vehicle::MultirotorModel& model() const { return model_; }

 private:
  vehicle::MultirotorModel model_;
  std::shared_ptr<const ReferenceTrajectory> reference_;
  FlightStackOptions options_;
  OdometryPassThroughEstimator estimator_;
  std::unique_ptr<control::Controller> controller_;
  TimeNs control_period_ns_;
  std::optional<TimeNs> last_update_ns_;
  StateEstimate estimate_;
  ReferencePoint reference_point_;
  RotorCommand command_;
};

}  // namespace rotorguard::stack
