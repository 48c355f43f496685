#pragma once
/// The LQR baseline of paper 004 (Sec. IV: "an LQR controller which is designed based on the
/// simplified model (1)"): a discrete-time infinite-horizon LQR on eqs. (1)-(2) with integral
/// action on x, y, z and ψ, discretised exactly (zero-order hold) at the control rate, flying the
/// full nonlinear vehicle. Its Riccati equation is solved by the structured doubling algorithm.
#include <string_view>

#include <Eigen/Core>

#include "rotorguard/control/controller.h"
#include "rotorguard/vehicle/pwm_model.h"

namespace rotorguard::control {

struct DareOptions {
  int max_iterations = 100;       ///< doubling steps (each squares the convergence), >= 1
  double tolerance = 1e-12;       ///< relative change of P that stops the iteration, > 0
};

struct DareSummary {
  Eigen::MatrixXd P;          ///< the stabilising solution
  int iterations = 0;
  bool converged = false;
  double residual = 0.0;      ///< max |A'PA − P − A'PB (R + B'PB)⁻¹ B'PA + Q| relative to max |P|
};

/// Solves the discrete algebraic Riccati equation
///   P = A'PA − A'PB (R + B'PB)⁻¹ B'PA + Q
/// for its stabilising solution by the structured doubling algorithm (Chu, Fan, Lin, "A
/// structure-preserving doubling algorithm for discrete-time algebraic Riccati equations", 2005):
/// A_{k+1} = A_k (I + G_k H_k)⁻¹ A_k, G_{k+1} = G_k + A_k (I + G_k H_k)⁻¹ G_k A_k',
/// H_{k+1} = H_k + A_k' H_k (I + G_k H_k)⁻¹ A_k with G_0 = B R⁻¹ B', H_0 = Q; H_k → P
/// quadratically when (A, B) is stabilisable and (A, Q^½) detectable. Throws std::invalid_argument
/// for mismatched sizes, R not positive definite or Q not symmetric positive semi-definite.
DareSummary SolveDare(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Q,
                      const Eigen::MatrixXd& R, const DareOptions& options = {});

/// The LQR gain K = (R + B'PB)⁻¹ B'PA of u = −K x for the solution P.
Eigen::MatrixXd LqrGain(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& R,
                        const Eigen::MatrixXd& P);

/// Zero-order-hold discretisation: A_d = e^{A dt}, B_d = ∫₀^dt e^{A s} ds B, from the exponential
/// of the augmented matrix [[A, B], [0, 0]] dt.
void DiscretizeZoh(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double dt, Eigen::MatrixXd* A_d,
                   Eigen::MatrixXd* B_d);

/// The state of the LQR's design model, in the heading frame (the yaw-rotated world frame, where
/// eq. 1 holds with ψ = 0):
///   0 x, 1 ẋ, 2 θ, 3 θ̇, 4 y, 5 ẏ, 6 φ, 7 φ̇, 8 z, 9 ż, 10 ψ, 11 ψ̇, 12-15 ∫x, ∫y, ∫z, ∫ψ.
/// Inputs: the four PWM inputs' deviations from hover.
struct LqrDesignModel {
  static constexpr int kStates = 16, kInputs = 4;
  Eigen::MatrixXd A, B;  ///< continuous time
};
/// Eqs. (1)-(2) with the integrators.
LqrDesignModel BuildLqrDesignModel(const vehicle::PwmQuadModel& model);

/// Bryson's rule: each weight is 1 / (the largest acceptable value)².
struct LqrControllerOptions {
  double sample_hz = 200.0;          ///< rate at which Compute is called [Hz], > 0
  double position_m = 0.1;           ///< acceptable x, y error [m], > 0
  double altitude_m = 0.05;          ///< acceptable z error [m], > 0
  double velocity_m_s = 0.5;         ///< [m/s], > 0
  double angle_rad = 0.15;           ///< roll, pitch [rad], > 0
  double rate_rad_s = 0.5;           ///< roll, pitch, yaw rates [rad/s], > 0
  double yaw_rad = 0.2;              ///< [rad], > 0
  double integral_m_s = 0.2;         ///< acceptable ∫x, ∫y, ∫z [m s] (and ∫ψ [rad s]), > 0
  double input_pwm = 0.01;           ///< acceptable PWM deviation from hover, > 0
  /// The integrators stop growing beyond this [m s], > 0 (anti-windup).
  double integral_limit = 2.0;
  /// Throws ValidationError naming the field.
  void Validate() const;
};

class LqrController final : public Controller {
 public:
  /// Throws ValidationError naming the vehicle's or the options' field (a vehicle without a PWM
  /// model, not in paper 004's + layout) or std::runtime_error when the Riccati iteration fails.
  LqrController(const vehicle::PwmQuadModel& model, const LqrControllerOptions& options);

  std::string_view name() const override { return "lqr"; }
  /// u = u_hover + u_ff − K (s − s_ref): the reference's state through flatness (θ* = ẍ*/g, eq. 3,
  /// in the heading frame) and its feed-forward (eq. 5: u_θ* = J1 F⁽⁴⁾/g, the snap by central
  /// differences of the reference's jerk), then T_i = K u_i within [0, max thrust].
  void Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t, double dt,
               RotorVector* thrust_command) override;
  void Reset() override;
  /// The paper's LQR does not reconfigure: a failed rotor is left to the feedback.
  void SetRotorFailed(int /*rotor*/) override {}

  const Eigen::MatrixXd& gain() const { return gain_; }
  const DareSummary& dare() const { return dare_; }
  /// The last PWM inputs (before conversion to thrust), for logs and the FDD.
  const Eigen::Vector4d& pwm() const { return pwm_; }

 private:
  vehicle::PwmQuadModel model_;
  LqrControllerOptions options_;
  DareSummary dare_;
  Eigen::MatrixXd gain_;
  Eigen::Vector4d integral_ = Eigen::Vector4d::Zero();  // ∫x, ∫y, ∫z, ∫ψ
  Eigen::Vector4d pwm_ = Eigen::Vector4d::Zero();
};

}  // namespace rotorguard::control
