
#include "rotorguard/control/nmpc.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/core/math.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/vehicle/effectiveness.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::control {

namespace {
using vehicle::StateIndex;

// Regularises the reduced-attitude decomposition at a 180 degree tilt (where w^2 + z^2 = 0).
constexpr double kDecompositionEpsilon = 1e-9;

}  // namespace

std::string_view ToString(NmpcStatus status) {
  switch (status) {
    case NmpcStatus::kNotSolved: return "not solved (Compute() was not called)";
    case NmpcStatus::kSolved: return "solved";
    case NmpcStatus::kMaxIterations: return "max SQP iterations reached";
    case NmpcStatus::kFallback: return "fallback to the shifted previous plan";
    case NmpcStatus::kInvalidInput: return "invalid (non-finite) input: hover command";
  }
  return "unknown";
}

std::string NmpcSummary::BriefReport() const {
  return fmt::format("NMPC {}: {} SQP, {} QP iterations, KKT residual {:.2e} (step {:.2e}, gap {:.2e}), "
                     "{:.3f} ms ({} fallbacks)",
                     ToString(status), sqp_iterations, qp_iterations, kkt_residual, step_norm, dynamics_gap,
                     solve_time_s * 1e3, fallbacks);
}

void NmpcOptions::Validate() const {
  CheckDeclaredRanges("NmpcOptions", *this);
  if (!(sqp_tolerance > 0.0) || !std::isfinite(sqp_tolerance)) {
    ThrowValidation("NmpcOptions", "sqp_tolerance", sqp_tolerance, "a value > 0");
  }
  if (!(expected_delay_s >= 0.0 && expected_delay_s <= 0.1)) {
    ThrowValidation("NmpcOptions", "expected_delay_s", expected_delay_s, "a delay in [0, 0.1] s");
  }
  disturbance.Validate();
  qp.Validate();
}

NmpcController::NmpcController(const vehicle::VehicleParams& vehicle, const NmpcOptions& options)
    : vehicle_(vehicle),
      options_((options.Validate(), options)),
      model_(vehicle),
      integrator_(model_, options.step_s, options.integrator_substeps),
      nx_(model_.nx()),
      nu_(model_.nu()),
      N_(options.horizon_steps),
      qp_(OcpQpDims{options.horizon_steps,
                    model_.nx(),
                    model_.nu(),
                    {StateIndex::kBodyRate, StateIndex::kBodyRate + 1, StateIndex::kBodyRate + 2}}),
      qp_solver_(MakeOcpQpSolver(options.qp_solver, qp_.dims, options.qp)),
      observer_(model_, options.disturbance),
      failed_(static_cast<std::size_t>(model_.nu()), false) {
  weights_.resize(nx_);
  weights_ << options_.q_position, options_.q_attitude, options_.q_velocity, options_.q_rate,
      Eigen::VectorXd::Constant(nu_, options_.q_thrust);
  u_max_.resize(nu_);
  for (int i = 0; i < nu_; ++i) u_max_[i] = vehicle_.rotors[i].max_thrust_n;
  x_.assign(N_ + 1, Eigen::VectorXd::Zero(nx_));
  u_.assign(N_, Eigen::VectorXd::Zero(nu_));
  x_shift_ = x_;
  u_shift_ = u_;
  x_next_.resize(nx_);
  y_.resize(nx_);
  dy_.resize(nx_, nx_);
  x0_.resize(nx_);
  x0_delta_.resize(nx_);
  for (Eigen::VectorXd& k : k_) k.resize(nx_);
  x_stage_.resize(nx_);
  u_acting_.resize(nu_);
  sent_.assign(kSentCommands, SentCommand{-std::numeric_limits<double>::infinity(), Eigen::VectorXd::Zero(nu_)});
  weighted_y_.resize(nx_);
  for (int k = 0; k < N_; ++k) qp_.R[k] = options_.r_input * Eigen::MatrixXd::Identity(nu_, nu_);
  torque_offset_ = Eigen::VectorXd::Zero(nu_);
  UpdateThrustSplit();
}

void NmpcController::Reset() {
  initialised_ = false;
  for (SentCommand& c : sent_) c.t = -std::numeric_limits<double>::infinity();
  prepared_for_t_.reset();
  reused_since_linearisation_ = -1;
  summary_ = NmpcSummary{};
  observer_.Reset();
  ApplyCorrection();
}

void NmpcController::SetRotorFailed(int rotor) {
  if (rotor < 0 || rotor >= nu_) {
    ThrowInvalidArgument("NmpcController::SetRotorFailed", "rotor", rotor, fmt::format("an index in [0, {})", nu_));
  }
  if (failed_[rotor]) return;  // already reconfigured
  failed_[rotor] = true;
  observer_.SlowTorque();            // the spin that follows is no place for a fast torque observer
  reused_since_linearisation_ = -1;  // the weights change: Q_k with them
  u_max_[rotor] = 0.0;               // u_bar_i = 0 (paper 000, Sec. V-A)
  weights_[StateIndex::kQuaternion + 3] = 0.0;  // yaw is given up
  SetModelEffectiveness(rotor, 0.0);
}

void NmpcController::SetRotorEffectiveness(int rotor, double effectiveness) {
  if (rotor < 0 || rotor >= nu_ || !std::isfinite(effectiveness)) {
    ThrowInvalidArgument("NmpcController::SetRotorEffectiveness", "rotor, effectiveness",
                         fmt::format("{}, {}", rotor, effectiveness),
                         fmt::format("an index in [0, {}), a finite value", nu_));
  }
  if (effectiveness <= 0.0) return SetRotorFailed(rotor);
  const double eta = std::min(effectiveness, 1.0);
  if (failed_[rotor] || eta == model_.effectiveness()[rotor]) return;
  reused_since_linearisation_ = -1;  // the model's columns change
  SetModelEffectiveness(rotor, eta);
}

void NmpcController::SetModelEffectiveness(int rotor, double eta) {
  Eigen::VectorXd all = model_.effectiveness();
  all[rotor] = eta;
  model_.SetEffectiveness(all);
  UpdateThrustSplit();
}

Eigen::VectorXd NmpcController::ThrustReference(double total) const { return ThrustReferenceOf(total); }

void NmpcController::UpdateThrustSplit() {
  const Eigen::VectorXd& eta = model_.effectiveness();
  const Eigen::MatrixXd E = vehicle::ComputeEffectivenessMatrix(vehicle_.rotors) * eta.asDiagonal();
  torque_split_ = Eigen::MatrixXd::Zero(nu_, 3);
  if (!AnyFailed()) {
    // Minimum-norm split of a unit total thrust with zero torque, and of unit torques.
    const Eigen::MatrixXd pinv = E.completeOrthogonalDecomposition().pseudoInverse();
    unit_split_ = pinv.col(0);
    torque_split_ = pinv.rightCols<3>();
  } else {
    // The exact mirror image of a failed rotor through the centre of gravity (its diagonal twin
    // on a quadrotor) idles, so that roll and pitch torques balance; only a healthy twin counts.
    // The others carry a unit total thrust with zero roll and pitch torque (least squares when the
    // torques cannot balance, e.g. two adjacent rotors lost); yaw is not controlled.
    const std::vector<int> active = ActiveRotorsAfterFailure();
    unit_split_ = Eigen::VectorXd::Zero(nu_);
    if (!active.empty()) {
      Eigen::MatrixXd Ea(3, static_cast<int>(active.size()));
      for (int c = 0; c < static_cast<int>(active.size()); ++c) Ea.col(c) = E.col(active[c]).head<3>();
      const Eigen::MatrixXd pinv = Ea.completeOrthogonalDecomposition().pseudoInverse();
      for (int c = 0; c < static_cast<int>(active.size()); ++c) {
        unit_split_[active[c]] = std::max(0.0, pinv(c, 0));
        torque_split_.row(active[c]).head<2>() = pinv.row(c).tail<2>();
      }
    }
  }
  ApplyCorrection();
}

std::vector<int> NmpcController::ActiveRotorsAfterFailure() const {
  std::vector<bool> idle = failed_;
  for (int f = 0; f < nu_; ++f) {
    if (!failed_[f]) continue;
    for (int j : vehicle::DiagonalTwins(vehicle_.rotors, f)) idle[j] = true;
  }
  std::vector<int> active;
  for (int i = 0; i < nu_; ++i) {
    if (!idle[i]) active.push_back(i);
  }
  return active;
}

void NmpcController::ApplyCorrection() {
  const Eigen::Vector3d& alpha = observer_.angular_acceleration_B();
  model_.SetDisturbance(observer_.acceleration_W(), alpha);
  // The rotor thrusts whose torque balances the disturbance's: M diag(eta) T = -I alpha_d.
  const Eigen::Vector3d torque = -(vehicle_.inertia_kg_m2 * alpha);
  torque_offset_.noalias() = torque_split_ * torque;
  if (!AnyFailed()) return;
  // Reference spin: the yaw torque of the post-failure thrust split (and the disturbance's)
  // against the yaw damping.
  const double weight = vehicle_.weight_n();
  double yaw_torque = vehicle_.inertia_kg_m2(2, 2) * alpha.z();
  for (int i = 0; i < nu_; ++i) {
    const double t_ref = weight * unit_split_[i] + torque_offset_[i];
    yaw_torque +=
        vehicle_.rotors[i].yaw_sign() * vehicle_.rotors[i].yaw_coefficient_m * model_.effectiveness()[i] * t_ref;
  }
  spin_reference_ = Eigen::Vector3d(0.0, 0.0, yaw_torque / std::max(vehicle_.yaw_damping_n_m_s, 1e-9));
}

Eigen::Vector3d NmpcController::ReferenceThrustVector(const ReferencePoint& ref) const {
  // Eq. (1) solved for the thrust vector along the reference, with the drag of the reference
  // velocity (body and world frames taken as aligned for the drag term).
  return vehicle_.mass_kg * (ref.a_W + Eigen::Vector3d(0.0, 0.0, kGravity) - model_.correction().acceleration_W) +
         vehicle_.rotor_drag_kg_s.cwiseProduct(ref.v_W);
}

double NmpcController::ReferenceTotalThrust(const ReferencePoint& ref) const {
  return ReferenceThrustVector(ref).norm();
}

Eigen::Quaterniond NmpcController::ReferenceAttitude(const ReferencePoint& ref) const {
  Eigen::Vector3d f = ReferenceThrustVector(ref);
  if (f.norm() < 1e-6) f = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d z = f.normalized();
  const Eigen::Vector3d heading(std::cos(ref.yaw), std::sin(ref.yaw), 0.0);
  Eigen::Vector3d y = z.cross(heading);
  if (y.norm() < 1e-6) y = z.cross(Eigen::Vector3d::UnitX());
  y.normalize();
  Eigen::Matrix3d R;
  R << y.cross(z), y, z;
  return Eigen::Quaterniond(R);
}

void NmpcController::Residual(const Eigen::VectorXd& x, const ReferencePoint& ref, Eigen::VectorXd* y,
                              Eigen::MatrixXd* dy) const {
  y->resize(nx_);
  dy->setZero(nx_, nx_);
  y->segment<3>(0) = x.segment<3>(StateIndex::kPosition) - ref.p_W;
  y->segment<3>(7) = x.segment<3>(StateIndex::kVelocity) - ref.v_W;
  y->segment<3>(10) = x.segment<3>(StateIndex::kBodyRate) - spin_reference_;
  y->tail(nu_) = x.tail(nu_) - ThrustReferenceOf(ReferenceTotalThrust(ref));
  dy->block<3, 3>(0, 0).setIdentity();
  dy->block<3, 3>(7, 7).setIdentity();
  dy->block<3, 3>(10, 10).setIdentity();
  dy->bottomRightCorner(nu_, nu_).setIdentity();

  // Attitude error in the body frame, q_e = q^-1 (x) q_ref = M q with M = [q_ref]_right diag(1,-1,-1,-1),
  // decomposed as q_e = q_red (x) q_yaw (Brescianini & D'Andrea, tilt-prioritised): y_att =
  // [q_red,x, q_red,y, q_e,x^2 + q_e,y^2, q_yaw,z] (paper 000, eq. 10), with the sign of q_e chosen
  // so that its scalar part is non-negative.
  const Eigen::Quaterniond r = ReferenceAttitude(ref);
  Eigen::Matrix4d right;  // p (x) r = right * p
  right << r.w(), -r.x(), -r.y(), -r.z(),  //
      r.x(), r.w(), r.z(), -r.y(),         //
      r.y(), -r.z(), r.w(), r.x(),         //
      r.z(), r.y(), -r.x(), r.w();
  Eigen::Matrix4d M = right;
  M.rightCols<3>() *= -1.0;  // conjugate of q
  Eigen::Vector4d qe = M * x.segment<4>(StateIndex::kQuaternion);
  if (qe[0] < 0.0) {
    qe = -qe;
    M = -M;
  }
  const double w = qe[0], a = qe[1], b = qe[2], c = qe[3];
  const double n2 = w * w + c * c + kDecompositionEpsilon, n = std::sqrt(n2);
  const double ex = (w * a - b * c) / n, ey = (w * b + a * c) / n, tilt2 = a * a + b * b, yaw = c / n;
  y->segment<4>(3) << ex, ey, tilt2, yaw;
  Eigen::Matrix4d d;  // d y_att / d q_e, columns (w, x, y, z)
  d << a / n - ex * w / n2, w / n, -c / n, -b / n - ex * c / n2,  //
      b / n - ey * w / n2, c / n, w / n, a / n - ey * c / n2,      //
      0.0, 2.0 * a, 2.0 * b, 0.0,                                  //
      -yaw * w / n2, 0.0, 0.0, 1.0 / n - yaw * c / n2;
  dy->block<4, 4>(3, 3) = d * M;
}

double NmpcController::NodeCost(const Eigen::VectorXd& x, const Eigen::VectorXd* u, const ReferencePoint& ref,
                                Eigen::VectorXd* grad_x, Eigen::VectorXd* grad_u) const {
  Eigen::VectorXd y;
  Eigen::MatrixXd dy;
  Residual(x, ref, &y, &dy);
  double cost = 0.5 * y.dot(weights_.cwiseProduct(y));
  if (grad_x) *grad_x = dy.transpose() * weights_.cwiseProduct(y);
  if (u) {
    const Eigen::VectorXd e = *u - ThrustReference(ReferenceTotalThrust(ref));
    cost += 0.5 * options_.r_input * e.squaredNorm();
    if (grad_u) *grad_u = options_.r_input * e;
  }
  return cost;
}

void NmpcController::HoverCommand(RotorVector* thrust_command) const {
  const Eigen::VectorXd t = ThrustReference(vehicle_.weight_n());
  *thrust_command = t.cwiseMax(0.0).cwiseMin(u_max_);
}

void NmpcController::RememberSent(double t, const RotorVector& command) {
  SentCommand& c = sent_[static_cast<std::size_t>(sent_next_)];
  c.t = t;
  c.u = command;
  sent_next_ = (sent_next_ + 1) % kSentCommands;
}

void NmpcController::PredictOverDelay(double t) {
  const double d = options_.expected_delay_s;
  const double end = t + d;
  double s = t;
  while (s < end) {
    // The command acting at s: the latest sent whose instant plus the delay has come; before any,
    // the motors hold their state. The piece ends where the next one starts acting.
    double acting_since = -std::numeric_limits<double>::infinity(), next = end;
    u_acting_ = x0_.tail(nu_);
    for (const SentCommand& c : sent_) {
      const double acts = c.t + d;
      if (acts <= s && acts > acting_since) {
        acting_since = acts;
        u_acting_ = c.u;
      } else if (acts > s && acts < next) {
        next = acts;
      }
    }
    // One RK4 step per piece: the delay is a few milliseconds, far below the model's time scales
    // but for the motors' (30 ms), which RK4 integrates to O(h^5).
    const double h = next - s;
    model_.Dynamics(x0_, u_acting_, &k_[0]);
    x_stage_ = x0_ + 0.5 * h * k_[0];
    model_.Dynamics(x_stage_, u_acting_, &k_[1]);
    x_stage_ = x0_ + 0.5 * h * k_[1];
    model_.Dynamics(x_stage_, u_acting_, &k_[2]);
    x_stage_ = x0_ + h * k_[2];
    model_.Dynamics(x_stage_, u_acting_, &k_[3]);
    x0_ += (h / 6.0) * (k_[0] + 2.0 * k_[1] + 2.0 * k_[2] + k_[3]);
    x0_.segment<4>(StateIndex::kQuaternion).normalize();
    s = next;
  }
}

void NmpcController::Initialise(const Eigen::VectorXd& x0, const ReferenceTrajectory& reference, double t) {
  for (int k = 0; k <= N_; ++k) x_[k] = x0;
  for (int k = 0; k < N_; ++k) {
    u_[k] = ThrustReference(ReferenceTotalThrust(reference.Evaluate(t + k * options_.step_s))).cwiseMin(u_max_);
  }
  initialised_ = true;
}

void NmpcController::ShiftBy(double elapsed) {
  // Warm start: the previous plan advanced by the elapsed time, interpolated between nodes.
  if (!(elapsed > 0.0)) return;
  const double s = elapsed / options_.step_s;
  x_shift_ = x_;
  u_shift_ = u_;
  for (int k = 0; k <= N_; ++k) {
    const double pos = std::min(static_cast<double>(k) + s, static_cast<double>(N_));
    const int i = std::min(static_cast<int>(pos), N_ - 1);
    const double frac = pos - i;
    x_[k] = (1.0 - frac) * x_shift_[i] + frac * x_shift_[i + 1];
  }
  for (int k = 0; k < N_; ++k) {
    const double pos = std::min(static_cast<double>(k) + s, static_cast<double>(N_ - 1));
    const int i = std::min(static_cast<int>(pos), std::max(N_ - 2, 0));
    const double frac = N_ > 1 ? pos - i : 0.0;
    if (N_ > 1) {
      u_[k] = (1.0 - frac) * u_shift_[i] + frac * u_shift_[i + 1];
    } else {
      u_[k] = u_shift_[0];
    }
  }
  for (int k = 0; k <= N_; ++k) x_[k].segment<4>(StateIndex::kQuaternion).normalize();
}

bool NmpcController::PlannedCommand(double t, RotorVector* thrust_command) const {
  if (!initialised_ || !std::isfinite(t)) return false;
  // The input acting at t + delay, between the nodes around it (ShiftBy's interpolation).
  const double pos = std::clamp((t + options_.expected_delay_s - plan_t0_) / options_.step_s, 0.0,
                                static_cast<double>(N_ - 1));
  const int i = std::min(static_cast<int>(pos), std::max(N_ - 2, 0));
  const double frac = N_ > 1 ? pos - i : 0.0;
  RotorVector u = u_[static_cast<std::size_t>(i)];  // fixed capacity: the control thread never allocates
  if (N_ > 1) u = (1.0 - frac) * u + frac * u_[static_cast<std::size_t>(i) + 1];
  if (!u.allFinite()) return false;
  *thrust_command = u.cwiseMax(0.0).cwiseMin(u_max_);
  return true;
}

bool NmpcController::PrepareIteration(const ReferenceTrajectory& reference, double t, bool reuse) {
  const Stopwatch clock;
  // Linearise the dynamics (exact RK4 sensitivities) and the cost (Gauss-Newton) along the plan;
  // or, reusing the last linearisation, only the shooting gaps and the residuals' gradients.
  double gap = 0.0;
  for (int k = 0; k < N_; ++k) {
    if (reuse) {
      integrator_.Step(x_[k], u_[k], &x_next_);
    } else {
      integrator_.Step(x_[k], u_[k], &x_next_, &qp_.A[k], &qp_.B[k]);
    }
    qp_.c[k] = x_next_ - x_[k + 1];
    gap = std::max(gap, qp_.c[k].cwiseAbs().maxCoeff());
  }
  for (int k = 0; k <= N_; ++k) {
    const ReferencePoint ref = reference.Evaluate(t + k * options_.step_s);
    Residual(x_[k], ref, &y_, &dy_);
    if (!reuse) {
      // Gauss-Newton Hessian dy' W dy: dy is the identity but for the 4x4 attitude block, so only
      // that block is a product.
      qp_.Q[k].setZero();
      qp_.Q[k].diagonal() = weights_;
      const auto d_att = dy_.block<4, 4>(StateIndex::kQuaternion, StateIndex::kQuaternion);
      qp_.Q[k].block<4, 4>(StateIndex::kQuaternion, StateIndex::kQuaternion).noalias() =
          d_att.transpose() * weights_.segment<4>(StateIndex::kQuaternion).asDiagonal() * d_att;
    }
    weighted_y_ = weights_.cwiseProduct(y_);
    qp_.q[k].noalias() = dy_.transpose() * weighted_y_;
    if (k < N_) {
      qp_.r[k] = options_.r_input * (u_[k] - ThrustReferenceOf(ReferenceTotalThrust(ref)));
      qp_.u_lower[k] = -u_[k];
      qp_.u_upper[k] = u_max_ - u_[k];
    }
    if (k > 0) {
      // Per axis (a fixed 3-vector assigned to a dynamic one makes GCC 12 warn of a 4-wide load).
      for (int a = 0; a < 3; ++a) {
        const double w = x_[k][StateIndex::kBodyRate + a];
        qp_.x_lower[k][a] = -options_.max_rate_rad_s[a] - w;
        qp_.x_upper[k][a] = options_.max_rate_rad_s[a] - w;
      }
    }
  }
  qp_.x0.setZero();  // condensed around the plan's own first node; the measurement comes later
  gap_ = gap;
  const OcpQpSummary& qs = reuse ? qp_solver_->PrepareVectors(qp_) : qp_solver_->Prepare(qp_);
  ++(reuse ? summary_.linearisations_reused : summary_.linearisations);
  reused_since_linearisation_ = reuse ? reused_since_linearisation_ + 1 : 0;
  summary_.prepare_time_s += clock.seconds();
  return qs.status != QpStatus::kNumericalFailure;
}

bool NmpcController::FeedbackIteration(const Eigen::VectorXd& x0) {
  Stopwatch clock;
  x0_delta_ = x0 - x_[0];
  const OcpQpSummary* qs = &qp_solver_->Feedback(x0_delta_);
  if (qs->status == QpStatus::kInfeasible) {
    // The body-rate bounds are hard constraints, and the motors can change the rate only so fast:
    // a measured rate far beyond its bound (a gust, a collision, a late isolation) leaves no
    // feasible plan. Dropping the rate bounds for this iteration beats falling back to a stale
    // plan that holds no corrective torque.
    for (int k = 1; k <= N_; ++k) {
      qp_.x_lower[k].setConstant(-std::numeric_limits<double>::infinity());
      qp_.x_upper[k].setConstant(std::numeric_limits<double>::infinity());
    }
    ++summary_.rate_bounds_relaxed;
    summary_.feedback_time_s += clock.Restart();
    qp_solver_->Prepare(qp_);
    summary_.prepare_time_s += clock.Restart();
    qs = &qp_solver_->Feedback(x0_delta_);
  }
  const OcpQpSummary& q = *qs;
  summary_.qp_iterations += q.iterations;
  summary_.dynamics_gap = gap_;
  summary_.objective = q.objective;
  ++summary_.sqp_iterations;
  bool ok = q.IsSolutionUsable();
  double step = 0.0;
  for (int k = 0; ok && k <= N_; ++k) {
    ok = qp_solver_->x()[k].allFinite() && (k == N_ || qp_solver_->u()[k].allFinite());
    if (!ok) break;
    step = std::max(step, qp_solver_->x()[k].cwiseAbs().maxCoeff());
    x_[k] += qp_solver_->x()[k];
    if (k < N_) {
      step = std::max(step, qp_solver_->u()[k].cwiseAbs().maxCoeff());
      u_[k] += qp_solver_->u()[k];
    }
  }
  summary_.step_norm = step;
  summary_.kkt_residual = std::max(step, gap_);
  summary_.feedback_time_s += clock.seconds();
  return ok;
}

bool NmpcController::SqpIteration(const Eigen::VectorXd& x0, const ReferenceTrajectory& reference, double t) {
  return PrepareIteration(reference, t) && FeedbackIteration(x0);
}

void NmpcController::Compute(const StateEstimate& est, const ReferenceTrajectory& reference, double t, double dt,
                             RotorVector* thrust_command) {
  const Stopwatch clock;
  const long fallbacks = summary_.fallbacks;
  summary_ = NmpcSummary{};
  summary_.fallbacks = fallbacks;
  const ReferencePoint ref_now = reference.Evaluate(t);
  const bool finite = est.valid && est.p_W.allFinite() && est.v_W.allFinite() && est.w_B.allFinite() &&
                      est.q_WB.coeffs().allFinite() && est.q_WB.norm() > 0.5 && ref_now.p_W.allFinite() &&
                      ref_now.v_W.allFinite() && ref_now.a_W.allFinite() && std::isfinite(ref_now.yaw) &&
                      std::isfinite(t);
  if (!finite) {
    summary_.status = NmpcStatus::kInvalidInput;
    if (initialised_) {
      *thrust_command = u_[0].cwiseMax(0.0).cwiseMin(u_max_);
    } else {
      HoverCommand(thrust_command);
    }
    if (std::isfinite(t)) RememberSent(t, *thrust_command);
    summary_.solve_time_s = clock.seconds();
    return;
  }
  // The measured state: pose and velocity from the estimator, motor thrusts from telemetry when
  // there is any, else from the plan.
  x0_.segment<3>(StateIndex::kPosition) = est.p_W;
  Eigen::Vector4d q(est.q_WB.w(), est.q_WB.x(), est.q_WB.y(), est.q_WB.z());
  q.normalize();
  if (initialised_ && q.dot(x_[0].segment<4>(StateIndex::kQuaternion)) < 0.0) q = -q;  // same cover as the plan
  x0_.segment<4>(StateIndex::kQuaternion) = q;
  x0_.segment<3>(StateIndex::kVelocity) = est.v_W;
  x0_.segment<3>(StateIndex::kBodyRate) = est.w_B;
  if (est.motor_thrust_n.size() == nu_ && est.motor_thrust_n.allFinite()) {
    x0_.tail(nu_) = est.motor_thrust_n;
  } else if (initialised_) {
    x0_.tail(nu_) = x_[0].tail(nu_);
  } else {
    x0_.tail(nu_) = ThrustReferenceOf(vehicle_.weight_n());
  }
  // What the model misses, from this measurement, into the prediction (nothing when disabled).
  observer_.Update(x0_, t);
  ApplyCorrection();
  // The command of this call acts only after the delay: the plan starts from the state then, and
  // runs on the clock of that instant (the references, the preparation for the next call).
  const double t_call = t;
  if (options_.expected_delay_s > 0.0) {
    PredictOverDelay(t);
    t += options_.expected_delay_s;
  }

  int iterations = options_.max_sqp_iterations;
  // Real-time iteration: when the previous call prepared the QP for this very time, only the
  // feedback phase stands between the measurement and the command.
  const bool prepared = initialised_ && prepared_for_t_ && std::abs(*prepared_for_t_ - t) < 1e-9;
  prepared_for_t_.reset();
  if (!initialised_) {
    Initialise(x0_, reference, t);
    iterations = std::max(iterations, 3);  // a first plan from scratch needs a few iterations
  } else if (!prepared) {
    ShiftBy(t - last_t_);
  }
  last_t_ = t;
  plan_t0_ = t;
  x_shift_ = x_;
  u_shift_ = u_;
  bool ok = true;
  summary_.status = NmpcStatus::kMaxIterations;
  for (int i = 0; i < iterations; ++i) {
    ok = (i == 0 && prepared) ? FeedbackIteration(x0_) : SqpIteration(x0_, reference, t);
    if (!ok) break;
    if (summary_.step_norm < options_.sqp_tolerance || (options_.max_sqp_iterations == 1 && i + 1 >= iterations)) {
      summary_.status = NmpcStatus::kSolved;
      break;
    }
  }
  if (!ok) {
    x_ = x_shift_;
    u_ = u_shift_;
    ++summary_.fallbacks;
    summary_.status = NmpcStatus::kFallback;
  }
  *thrust_command = u_[0].cwiseMax(0.0).cwiseMin(u_max_);
  if (!thrust_command->allFinite()) {
    HoverCommand(thrust_command);
    summary_.status = NmpcStatus::kFallback;
    ++summary_.fallbacks;
    reused_since_linearisation_ = -1;  // a fallback: the next preparation linearises
  }
  RememberSent(t_call, *thrust_command);
  summary_.command_latency_s = clock.seconds();
  // Preparation for the next call, after the command is out: shift the plan by this call's period
  // (the stack's control period) and linearise and condense around it.
  if (options_.max_sqp_iterations == 1 && dt > 0.0 && std::isfinite(dt) && ok) {
    ShiftBy(dt);
    // The linearisation is reused while it is younger than relinearise_every preparations. A call
    // that had to drop its rate bounds met a large disturbance: fresh Jacobians then (a choice,
    // not a need: the relaxed QP kept the same matrices).
    const bool reuse = summary_.rate_bounds_relaxed == 0 && reused_since_linearisation_ >= 0 &&
                       reused_since_linearisation_ + 1 < options_.relinearise_every;
    plan_t0_ = t + dt;
    if (PrepareIteration(reference, t + dt, reuse)) prepared_for_t_ = t + dt;
  }
  // Unprepared, the next call iterates from scratch: its own preparation linearises.
  summary_.solve_time_s = clock.seconds();
}

}  // namespace rotorguard::control
