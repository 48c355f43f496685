#include "rotorguard/vehicle/multirotor.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "rotorguard/core/math.h"
#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::vehicle {

MultirotorModel::MultirotorModel(VehicleParams params, RotorVector thrust_ratio)
    : params_(std::move(params)), thrust_ratio_(std::move(thrust_ratio)) {
  params_.Validate();
  if (thrust_ratio_.size() == 0) thrust_ratio_ = RotorVector::Ones(num_rotors());
  if (thrust_ratio_.size() != num_rotors() || !(thrust_ratio_.array() > 0.0).all() || !thrust_ratio_.allFinite()) {
    throw std::invalid_argument(
        fmt::format("MultirotorModel: thrust_ratio has {} entries; expected {} positive finite ratios, one per rotor",
                    thrust_ratio_.size(), num_rotors()));
  }
  effectiveness_ = ComputeEffectivenessMatrix(params_.rotors);
  max_thrust_.resize(num_rotors());
  for (int i = 0; i < num_rotors(); ++i) max_thrust_[i] = params_.rotors[i].max_thrust_n;
  inertia_inv_ = params_.inertia_kg_m2.inverse();
}

RotorVector MultirotorModel::HoverThrusts() const {
  const AllocationMatrix pinv = PseudoInverse(effectiveness_);
  const RotorVector applied = pinv * Eigen::Vector4d(params_.weight_n(), 0.0, 0.0, 0.0);
  return applied.cwiseQuotient(thrust_ratio_);
}

StateVector MultirotorModel::MakeState(const Vector3& p_W, double yaw,
                                       const RotorVector& motor_thrust) const {
  StateVector x = StateVector::Zero(state_size());
  x.segment<3>(StateIndex::kPosition) = p_W;
  const Quaternion q = QuaternionFromYaw(yaw);
  x.segment<4>(StateIndex::kQuaternion) << q.w(), q.x(), q.y(), q.z();
  x.tail(num_rotors()) = motor_thrust;
  return x;
}

void MultirotorModel::RotorThrusts(const StateVector& x, const RotorFaults& faults,
                                   RotorVector* thrust) const {
  thrust->resize(num_rotors());
  for (int i = 0; i < num_rotors(); ++i) {
    const double drive = std::max(0.0, x[StateIndex::kMotor + i]);
    switch (faults[i].kind) {
      case FaultKind::kPropellerLoss:
        (*thrust)[i] = 0.0;
        break;
      case FaultKind::kLossOfEffectiveness:
        (*thrust)[i] = (1.0 - faults[i].eta) * thrust_ratio_[i] * drive;
        break;
      case FaultKind::kNone:
      case FaultKind::kMotorStop:
      case FaultKind::kStuck:
        (*thrust)[i] = thrust_ratio_[i] * drive;
        break;
    }
  }
}

void MultirotorModel::MotorSpeeds(const StateVector& x, const RotorFaults& faults,
                                  RotorVector* speed) const {
  speed->resize(num_rotors());
  for (int i = 0; i < num_rotors(); ++i) {
    // T = k_n w^2 for the loaded propeller; the motor state is that loaded-equivalent thrust.
    const double w = std::sqrt(std::max(0.0, x[StateIndex::kMotor + i]) /
                               params_.thrust_coefficient_n_s2);
    (*speed)[i] = faults[i].kind == FaultKind::kPropellerLoss ? params_.unloaded_speed_ratio * w : w;
  }
}

Accelerations MultirotorModel::ComputeAccelerations(const StateVector& x,
                                                    const RotorFaults& faults,
                                                    const Disturbance& d) const {
  const StateView s(x);
  RotorVector thrust;
  RotorThrusts(x, faults, &thrust);
  const Eigen::Vector4d wrench = effectiveness_ * thrust;  // [T; tau], eq. (4)
  const Matrix3 R_WB = s.q_WB().toRotationMatrix();
  const Vector3 D = params_.rotor_drag_kg_s;
  // eq. (1): m a = T z_B - R D R^T (v - wind) + m g (+ external force).
  const Vector3 v_air_B = R_WB.transpose() * (s.v_W() - d.wind_W);
  const Vector3 drag_W = -R_WB * D.cwiseProduct(v_air_B);
  Accelerations acc;
  acc.a_W = (wrench[0] * R_WB.col(2) + drag_W + d.force_W) / params_.mass_kg -
            Vector3(0.0, 0.0, kGravity);
  // eq. (3): I alpha = tau - w x I w - A(r), A(r) = [0, 0, k_dpsi r].
  const Vector3 w = s.w_B();
  const Vector3 tau = wrench.tail<3>() - w.cross(params_.inertia_kg_m2 * w) -
                      Vector3(0.0, 0.0, params_.yaw_damping_n_m_s * w.z()) + d.torque_B;
  acc.alpha_B = inertia_inv_ * tau;
  return acc;
}

void MultirotorModel::Derivative(const StateVector& x, const RotorVector& u,
                                 const RotorFaults& faults, const Disturbance& d,
                                 StateVector* x_dot) const {
  x_dot->resize(state_size());
  const StateView s(x);
  const Accelerations acc = ComputeAccelerations(x, faults, d);
  x_dot->segment<3>(StateIndex::kPosition) = s.v_W();
  x_dot->segment<4>(StateIndex::kQuaternion) = QuaternionDerivative(s.q_WB(), s.w_B());  // eq. (2)
  x_dot->segment<3>(StateIndex::kVelocity) = acc.a_W;
  x_dot->segment<3>(StateIndex::kBodyRate) = acc.alpha_B;
  const double sigma = params_.motor_time_constant_s;
  for (int i = 0; i < num_rotors(); ++i) {
    const double motor = x[StateIndex::kMotor + i];
    double rate = 0.0;
    switch (faults[i].kind) {
      case FaultKind::kMotorStop:
        rate = -motor / params_.motor_stop_time_constant_s;
        break;
      case FaultKind::kStuck:
        rate = 0.0;
        break;
      case FaultKind::kNone:
      case FaultKind::kPropellerLoss:
      case FaultKind::kLossOfEffectiveness: {
        const double command = std::clamp(u[i], 0.0, max_thrust_[i]);  // saturation
        rate = (command - motor) / sigma;                               // eq. (6)
        break;
      }
    }
    (*x_dot)[StateIndex::kMotor + i] = rate;
  }
}

Rk4Integrator::Rk4Integrator(const MultirotorModel& model) : model_(model) {
  const int n = model.state_size();
  k1_.resize(n);
  k2_.resize(n);
  k3_.resize(n);
  k4_.resize(n);
  tmp_.resize(n);
}

void Rk4Integrator::Derivative(const StateVector& x, const RotorVector& u, const RotorFaults& faults,
                               const Disturbance& disturbance, const StateWrench* state_wrench,
                               StateVector* x_dot) const {
  if (state_wrench == nullptr) {
    model_.Derivative(x, u, faults, disturbance, x_dot);
    return;
  }
  Disturbance d = disturbance;
  state_wrench->AddTo(x, &d);
  model_.Derivative(x, u, faults, d, x_dot);
}

void Rk4Integrator::Step(const RotorVector& u, const RotorFaults& faults, const Disturbance& d,
                         double dt, StateVector* x, const StateWrench* state_wrench) {
  Derivative(*x, u, faults, d, state_wrench, &k1_);
  tmp_ = *x + 0.5 * dt * k1_;
  Derivative(tmp_, u, faults, d, state_wrench, &k2_);
  tmp_ = *x + 0.5 * dt * k2_;
  Derivative(tmp_, u, faults, d, state_wrench, &k3_);
  tmp_ = *x + dt * k3_;
  Derivative(tmp_, u, faults, d, state_wrench, &k4_);
  *x += (dt / 6.0) * (k1_ + 2.0 * k2_ + 2.0 * k3_ + k4_);
  x->segment<4>(StateIndex::kQuaternion).normalize();
}

}  // namespace rotorguard::vehicle
