#include "rotorguard/control/nmpc_model.h"

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/effectiveness.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::control {

namespace {
using vehicle::StateIndex;

/// Rotation matrix of a (unit) quaternion as the polynomial in its components, and its partial
/// derivatives with respect to (w, x, y, z); smooth for the slightly non-unit quaternions that a
/// prediction integrates.
Eigen::Matrix3d RotationOf(double w, double x, double y, double z) {
  Eigen::Matrix3d R;
  R << 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),  //
      2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),   //
      2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y);
  return R;
}

void RotationDerivatives(double w, double x, double y, double z, Eigen::Matrix3d dR[4]) {
  dR[0] << 0, -2 * z, 2 * y, 2 * z, 0, -2 * x, -2 * y, 2 * x, 0;
  dR[1] << 0, 2 * y, 2 * z, 2 * y, -4 * x, -2 * w, 2 * z, 2 * w, -4 * x;
  dR[2] << -4 * y, 2 * x, 2 * w, 2 * x, 0, 2 * z, -2 * w, 2 * z, -4 * y;
  dR[3] << -4 * z, -2 * w, 2 * x, 2 * w, -4 * z, 2 * y, 2 * x, 2 * y, 0;
}
}  // namespace

NmpcModel::NmpcModel(const vehicle::VehicleParams& params) : params_(params), nu_(params.num_rotors()) {
  params_.Validate();
  inertia_ = params_.inertia_kg_m2;
  inertia_inv_ = inertia_.inverse();
  torque_map_ = vehicle::ComputeEffectivenessMatrix(params_.rotors).bottomRows<3>();
  correction_.effectiveness = Eigen::VectorXd::Ones(nu_);
  alpha_map_ = inertia_inv_ * torque_map_;
}

namespace {
void RequireFinite(const Eigen::Vector3d& acceleration_W, const Eigen::Vector3d& angular_acceleration_B) {
  if (!acceleration_W.allFinite() || !angular_acceleration_B.allFinite()) {
    ThrowInvalidArgument("NmpcModel::SetDisturbance", "acceleration_W, angular_acceleration_B", "(non-finite)",
                         "finite accelerations");
  }
}
}  // namespace

void NmpcModel::SetCorrection(const ModelCorrection& c) {
  RequireFinite(c.acceleration_W, c.angular_acceleration_B);  // before anything changes
  SetEffectiveness(c.effectiveness);
  SetDisturbance(c.acceleration_W, c.angular_acceleration_B);
}

void NmpcModel::SetEffectiveness(const Eigen::VectorXd& effectiveness) {
  const Eigen::VectorXd eta = effectiveness.size() == 0 ? Eigen::VectorXd::Ones(nu_) : effectiveness;
  if (eta.size() != nu_ || !eta.allFinite() || eta.minCoeff() < 0.0 || eta.maxCoeff() > 1.0) {
    ThrowInvalidArgument("NmpcModel::SetEffectiveness", "effectiveness", fmt::format("{} entries", eta.size()),
                         fmt::format("{} entries in [0, 1]", nu_));
  }
  correction_.effectiveness = eta;
  alpha_map_ = inertia_inv_ * torque_map_ * eta.asDiagonal();
}

void NmpcModel::SetDisturbance(const Eigen::Vector3d& acceleration_W, const Eigen::Vector3d& angular_acceleration_B) {
  RequireFinite(acceleration_W, angular_acceleration_B);
  correction_.acceleration_W = acceleration_W;
  correction_.angular_acceleration_B = angular_acceleration_B;
}

void NmpcModel::ModelAccelerations(const Eigen::VectorXd& x, Eigen::Vector3d* a_W, Eigen::Vector3d* alpha_B) const {
  const Eigen::Matrix3d R = RotationOf(x[3], x[4], x[5], x[6]);
  const Eigen::Vector3d v = x.segment<3>(StateIndex::kVelocity);
  const Eigen::Vector3d w = x.segment<3>(StateIndex::kBodyRate);
  const auto T = x.segment(StateIndex::kMotor, nu_);
  const Eigen::Vector3d D = params_.rotor_drag_kg_s;
  *a_W = (R.col(2) * effectiveness().dot(T) - R * D.asDiagonal() * (R.transpose() * v)) / params_.mass_kg -
         Eigen::Vector3d(0, 0, kGravity);
  *alpha_B = alpha_map_ * T -
             inertia_inv_ * (w.cross(inertia_ * w) + Eigen::Vector3d(0, 0, params_.yaw_damping_n_m_s * w.z()));
}

void NmpcModel::Dynamics(const Eigen::VectorXd& x, const Eigen::VectorXd& u, Eigen::VectorXd* x_dot) const {
  x_dot->resize(nx());
  const double qw = x[3], qx = x[4], qy = x[5], qz = x[6];
  Eigen::Vector3d a_W, alpha_B;
  ModelAccelerations(x, &a_W, &alpha_B);
  x_dot->segment<3>(0) = x.segment<3>(StateIndex::kVelocity);
  x_dot->segment<4>(3) = QuaternionDerivative(Quaternion(qw, qx, qy, qz), x.segment<3>(StateIndex::kBodyRate));
  x_dot->segment<3>(7) = a_W + correction_.acceleration_W;
  x_dot->segment<3>(10) = alpha_B + correction_.angular_acceleration_B;
  x_dot->segment(StateIndex::kMotor, nu_) = (u - x.segment(StateIndex::kMotor, nu_)) / params_.motor_time_constant_s;
}

void NmpcModel::DynamicsWithJacobians(const Eigen::VectorXd& x, const Eigen::VectorXd& u, Eigen::VectorXd* x_dot,
                                      Eigen::MatrixXd* fx, Eigen::MatrixXd* fu) const {
  fx->setZero(nx(), nx());
  fu->setZero(nx(), nu_);
  UpdateDynamicsWithJacobians(x, u, x_dot, fx, fu);
}

void NmpcModel::UpdateDynamicsWithJacobians(const Eigen::VectorXd& x, const Eigen::VectorXd& u, Eigen::VectorXd* x_dot,
                                            Eigen::MatrixXd* fx, Eigen::MatrixXd* fu) const {
  Dynamics(x, u, x_dot);
  const double qw = x[3], qx = x[4], qy = x[5], qz = x[6];
  const Eigen::Matrix3d R = RotationOf(qw, qx, qy, qz);
  Eigen::Matrix3d dR[4];
  RotationDerivatives(qw, qx, qy, qz, dR);
  const Eigen::Vector3d v = x.segment<3>(7), w = x.segment<3>(10);
  const double thrust = effectiveness().dot(x.segment(StateIndex::kMotor, nu_));
  const Eigen::Matrix3d D = params_.rotor_drag_kg_s.asDiagonal();
  const double inv_m = 1.0 / params_.mass_kg;

  fx->block<3, 3>(0, 7).setIdentity();  // p_dot = v
  // q_dot = 1/2 Omega(w) q = 1/2 Xi(q) w.
  Eigen::Matrix4d omega;
  omega << 0, -w.x(), -w.y(), -w.z(),  //
      w.x(), 0, w.z(), -w.y(),         //
      w.y(), -w.z(), 0, w.x(),         //
      w.z(), w.y(), -w.x(), 0;
  fx->block<4, 4>(3, 3) = 0.5 * omega;
  Eigen::Matrix<double, 4, 3> xi;
  xi << -qx, -qy, -qz,  //
      qw, -qz, qy,      //
      qz, qw, -qx,      //
      -qy, qx, qw;
  fx->block<4, 3>(3, 10) = 0.5 * xi;
  // v_dot = (R e3 eta'T - R D R' v) / m - g e3 + a_c.
  const Eigen::Vector3d drag_body = D * (R.transpose() * v);
  for (int i = 0; i < 4; ++i) {
    fx->block<3, 1>(7, 3 + i) =
        inv_m * (dR[i].col(2) * thrust - dR[i] * drag_body - R * D * (dR[i].transpose() * v));
  }
  fx->block<3, 3>(7, 7) = -inv_m * R * D * R.transpose();
  for (int j = 0; j < nu_; ++j) fx->block<3, 1>(7, StateIndex::kMotor + j) = (effectiveness()[j] * inv_m) * R.col(2);
  // w_dot = I^-1 (M diag(eta) T - w x I w - k_dpsi r e3) + alpha_c.
  const Eigen::Matrix3d gyro = Skew(w) * inertia_ - Skew(inertia_ * w);
  Eigen::Matrix3d damping = Eigen::Matrix3d::Zero();
  damping(2, 2) = params_.yaw_damping_n_m_s;
  fx->block<3, 3>(10, 10) = -inertia_inv_ * (gyro + damping);
  fx->block(10, StateIndex::kMotor, 3, nu_) = alpha_map_;
  // T_dot = (u - T) / sigma (eq. 6).
  const double inv_sigma = 1.0 / params_.motor_time_constant_s;
  fx->block(StateIndex::kMotor, StateIndex::kMotor, nu_, nu_) = -inv_sigma * Eigen::MatrixXd::Identity(nu_, nu_);
  fu->block(StateIndex::kMotor, 0, nu_, nu_) = inv_sigma * Eigen::MatrixXd::Identity(nu_, nu_);
}

namespace {
/// out = fx * M using the block sparsity of fx; NU and C are compile-time sizes when known (the
/// quadrotor's RK4: NU = 4, C = 18), else Eigen::Dynamic.
template <int NU, int C>
void MultiplyBlocks(const Eigen::MatrixXd& fx, const Eigen::MatrixXd& M_in, int nu, double sigma,
                    Eigen::MatrixXd* out_full) {
  constexpr int NX = NU == Eigen::Dynamic ? Eigen::Dynamic : 13 + NU;
  const int nx = 13 + nu, c = static_cast<int>(M_in.cols());
  const Eigen::Map<const Eigen::Matrix<double, NX, NX>> F(fx.data(), nx, nx);
  const Eigen::Map<const Eigen::Matrix<double, NX, C>> M(M_in.data(), nx, c);
  Eigen::Map<Eigen::Matrix<double, NX, C>> out(out_full->data(), nx, c);
  const auto Mq = M.template middleRows<4>(StateIndex::kQuaternion);
  const auto Mv = M.template middleRows<3>(StateIndex::kVelocity);
  const auto Mw = M.template middleRows<3>(StateIndex::kBodyRate);
  const auto MT = M.template bottomRows<NU>(nu);
  out.template middleRows<3>(StateIndex::kPosition) = Mv;
  out.template middleRows<4>(StateIndex::kQuaternion).noalias() =
      F.template block<4, 4>(StateIndex::kQuaternion, StateIndex::kQuaternion) * Mq +
      F.template block<4, 3>(StateIndex::kQuaternion, StateIndex::kBodyRate) * Mw;
  // The thrust columns of v_dot are eta_j R e3 / m.
  out.template middleRows<3>(StateIndex::kVelocity).noalias() =
      F.template block<3, 4>(StateIndex::kVelocity, StateIndex::kQuaternion) * Mq +
      F.template block<3, 3>(StateIndex::kVelocity, StateIndex::kVelocity) * Mv;
  out.template middleRows<3>(StateIndex::kVelocity).noalias() +=
      F.template block<3, NU>(StateIndex::kVelocity, StateIndex::kMotor, 3, nu) * MT;
  out.template middleRows<3>(StateIndex::kBodyRate).noalias() =
      F.template block<3, 3>(StateIndex::kBodyRate, StateIndex::kBodyRate) * Mw +
      F.template block<3, NU>(StateIndex::kBodyRate, StateIndex::kMotor, 3, nu) * MT;
  out.template bottomRows<NU>(nu) = (-1.0 / sigma) * MT;
}
}  // namespace

void NmpcModel::MultiplyStateJacobian(const Eigen::MatrixXd& fx, const Eigen::MatrixXd& M,
                                      Eigen::MatrixXd* out) const {
  out->resize(nx(), M.cols());
  const double sigma = params_.motor_time_constant_s;
  if (nu_ == 4 && M.cols() == 18) {  // the quadrotor's RK4 sensitivities [d/d(q, v, w, T) d/du]
    MultiplyBlocks<4, 18>(fx, M, nu_, sigma, out);
  } else {
    MultiplyBlocks<Eigen::Dynamic, Eigen::Dynamic>(fx, M, nu_, sigma, out);
  }
}

Rk4Sensitivity::Rk4Sensitivity(const NmpcModel& model, double dt, int substeps)
    : model_(model), h_(dt / substeps), substeps_(substeps) {
  if (!(dt > 0.0) || substeps < 1) {
    ThrowInvalidArgument("Rk4Sensitivity", "dt, substeps", fmt::format("{}, {}", dt, substeps), "dt > 0 and substeps >= 1");
  }
  static_assert(StateIndex::kPosition == 0, "the position columns are the first three");
  const int nx = model.nx(), nu = model.nu(), cols = nx - 3 + nu;
  for (int i = 0; i < 4; ++i) {
    k_[i].resize(nx);
    dk_[i].resize(nx, cols);
  }
  fx_.setZero(nx, nx);  // UpdateDynamicsWithJacobians writes only the structural entries
  fu_.setZero(nx, nu);
  xs_.resize(nx);
  xtmp_.resize(nx);
  ab_.resize(nx, cols);
  abtmp_.resize(nx, cols);
}

void Rk4Sensitivity::Step(const Eigen::VectorXd& x, const Eigen::VectorXd& u, Eigen::VectorXd* x_next,
                          Eigen::MatrixXd* A, Eigen::MatrixXd* B) {
  const bool sens = A != nullptr && B != nullptr;
  const int nx = model_.nx(), nu = model_.nu();
  xs_ = x;
  if (sens) {
    ab_.setZero();  // [d xs / d(q, v, w, T), d xs / d u]
    ab_.topLeftCorner(nx, nx - 3).bottomRows(nx - 3).setIdentity();
  }
  static constexpr double kStage[4] = {0.0, 0.5, 0.5, 1.0};
  static constexpr double kWeight[4] = {1.0 / 6.0, 2.0 / 6.0, 2.0 / 6.0, 1.0 / 6.0};
  for (int s = 0; s < substeps_; ++s) {
    for (int i = 0; i < 4; ++i) {
      xtmp_ = xs_;
      if (i > 0) xtmp_ += kStage[i] * h_ * k_[i - 1];
      if (!sens) {
        model_.Dynamics(xtmp_, u, &k_[i]);
        continue;
      }
      model_.UpdateDynamicsWithJacobians(xtmp_, u, &k_[i], &fx_, &fu_);
      // d k_i = f_x (d xs + c h d k_{i-1}) + f_u d u.
      if (i > 0) {
        abtmp_ = ab_ + (kStage[i] * h_) * dk_[i - 1];
        model_.MultiplyStateJacobian(fx_, abtmp_, &dk_[i]);
      } else if (s == 0) {
        // d xs is still [0 I | 0]: the product is f_x's columns themselves, exactly.
        dk_[i].leftCols(nx - 3) = fx_.rightCols(nx - 3);
        dk_[i].rightCols(nu).setZero();
      } else {
        model_.MultiplyStateJacobian(fx_, ab_, &dk_[i]);
      }
      dk_[i].rightCols(nu) += fu_;
    }
    for (int i = 0; i < 4; ++i) {
      xs_ += kWeight[i] * h_ * k_[i];
      if (sens) ab_ += (kWeight[i] * h_) * dk_[i];
    }
  }
  *x_next = xs_;
  if (sens) {
    A->resize(nx, nx);
    A->leftCols<3>().setZero();
    A->topLeftCorner<3, 3>().setIdentity();
    A->rightCols(nx - 3) = ab_.leftCols(nx - 3);
    *B = ab_.rightCols(nu);
  }
}

}  // namespace rotorguard::control
