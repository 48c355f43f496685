#pragma once
/// Continuous multirotor dynamics with first-order motors (paper 000, eqs. 1-3 and 6) and an RK4
/// step. The model is immutable after construction; scratch memory lives in Rk4Integrator.
#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/faults.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::vehicle {

/// Full state x = [p_W (3), q_WB (4: w, x, y, z), v_W (3), w_B (3), motor states (n)], the
/// NMPC's state for n = 4. A motor state is the thrust the motor currently drives [N] (T_i of
/// eq. 6); what reaches the airframe depends on the rotor's fault.
using StateVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 13 + kMaxRotors, 1>;

/// Named offsets into StateVector.
struct StateIndex {
  static constexpr int kPosition = 0;
  static constexpr int kQuaternion = 3;
  static constexpr int kVelocity = 7;
  static constexpr int kBodyRate = 10;
  static constexpr int kMotor = 13;
};

/// Typed read-only view of a StateVector.
struct StateView {
  explicit StateView(const StateVector& x) : x_(x) {}
  Vector3 p_W() const { return x_.segment<3>(StateIndex::kPosition); }
  Quaternion q_WB() const {
    const auto q = x_.segment<4>(StateIndex::kQuaternion);
    return Quaternion(q[0], q[1], q[2], q[3]);
  }
  Vector3 v_W() const { return x_.segment<3>(StateIndex::kVelocity); }
  Vector3 w_B() const { return x_.segment<3>(StateIndex::kBodyRate); }
  double motor(int i) const { return x_[StateIndex::kMotor + i]; }

 private:
  const StateVector& x_;
};

/// External influences on the airframe (truth side only).
struct Disturbance {
  Vector3 wind_W = Vector3::Zero();    ///< air velocity; rotor drag acts on v - wind
  Vector3 force_W = Vector3::Zero();   ///< additional force [N]
  Vector3 torque_B = Vector3::Zero();  ///< additional torque [N*m]
};

/// A force and torque that depend on the state (the ground's contact on the landing gear): an
/// integrator evaluates it at every stage of a step, as it does the dynamics' own terms, so that a
/// stiff contact stays stable and accurate.
class StateWrench {
 public:
  virtual ~StateWrench() = default;
  /// Adds its force (world frame, at the centre of gravity) and torque (body frame) at x to `d`.
  virtual void AddTo(const StateVector& x, Disturbance* d) const = 0;
};

/// Accelerations at a state, as an accelerometer and the FDD observers see them.
struct Accelerations {
  Vector3 a_W = Vector3::Zero();      ///< acceleration of the centre of gravity
  Vector3 alpha_B = Vector3::Zero();  ///< angular acceleration
};

class MultirotorModel {
 public:
  /// Validates `params` (throws ValidationError). `thrust_ratio` (simulated vehicles only): each
  /// rotor's thrust relative to what params' k_n gives at the same motor speed, a propeller's
  /// spread that the vehicle file does not know; empty: 1 for every rotor.
  explicit MultirotorModel(VehicleParams params, RotorVector thrust_ratio = {});

  const VehicleParams& params() const { return params_; }
  int num_rotors() const { return params_.num_rotors(); }
  int state_size() const { return 13 + num_rotors(); }
  const EffectivenessMatrix& effectiveness() const { return effectiveness_; }
  const RotorVector& max_thrust() const { return max_thrust_; }

  /// Minimum-norm rotor thrusts that hold hover (total thrust m*g, zero torque), as motor states
  /// (commands): the thrust each applies is thrust_ratio times it.
  RotorVector HoverThrusts() const;
  const RotorVector& thrust_ratio() const { return thrust_ratio_; }
  /// A state at rest at `p_W` with yaw `yaw`, motors at `motor_thrust`.
  StateVector MakeState(const Vector3& p_W, double yaw, const RotorVector& motor_thrust) const;

  /// Thrust each rotor applies to the airframe [N], given motor states and faults.
  void RotorThrusts(const StateVector& x, const RotorFaults& faults, RotorVector* thrust) const;
  /// Speed of each motor [rad/s] (what ESC telemetry measures).
  void MotorSpeeds(const StateVector& x, const RotorFaults& faults, RotorVector* speed) const;

  /// x_dot = f(x, u): eqs. (1)-(3) with rotor drag and yaw damping, eq. (6) with commands
  /// saturated to [0, T_bar]. `u` holds commanded thrusts [N].
  void Derivative(const StateVector& x, const RotorVector& u, const RotorFaults& faults,
                  const Disturbance& disturbance, StateVector* x_dot) const;

  /// Linear and angular acceleration at x (from the same equations as Derivative).
  Accelerations ComputeAccelerations(const StateVector& x, const RotorFaults& faults,
                                     const Disturbance& disturbance) const;

 private:
  VehicleParams params_;
  EffectivenessMatrix effectiveness_;
  RotorVector max_thrust_;
  RotorVector thrust_ratio_;
  Matrix3 inertia_inv_;
};

/// Classic fourth-order Runge-Kutta over MultirotorModel::Derivative, with the input held
/// constant over the step and the quaternion renormalised after it. Owns its scratch memory.
class Rk4Integrator {
 public:
  explicit Rk4Integrator(const MultirotorModel& model);
  /// Advances x by dt [s] in place; `state_wrench`, when given, adds to `disturbance` at every stage.
  void Step(const RotorVector& u, const RotorFaults& faults, const Disturbance& disturbance,
            double dt, StateVector* x, const StateWrench* state_wrench = nullptr);

 private:
  void Derivative(const StateVector& x, const RotorVector& u, const RotorFaults& faults,
                  const Disturbance& disturbance, const StateWrench* state_wrench, StateVector* x_dot) const;

  const MultirotorModel& model_;
  StateVector k1_, k2_, k3_, k4_, tmp_;
};

}  // namespace rotorguard::vehicle
