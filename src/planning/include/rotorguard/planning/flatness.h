#pragma once
/// Flatness-based planning of paper 004 (Chamseddine et al., JGCD 2012), Sec. III: every flat
/// output follows a critically damped second-order reference (eq. 6) towards a step of amplitude
/// R, and the settling time t_s (ω_n = 5.83 / t_s, eq. 11) is chosen in closed form as the
/// shortest that keeps
///   - the flight envelope: |θ*| ≤ ρ_θ θ_max and |φ*| ≤ ρ_φ φ_max (eqs. 9-17), and
///   - the actuators: every motor's nominal PWM input u_i* ≤ ρ_u u_max, after a fault
///     (1 − ŵ_i) ρ_u u_max (eqs. 18-23),
/// taking the largest candidate. Re-planning uses the remaining distance Δ = R − F(t_rep) and the
/// same closed forms; the reference then starts from the state at t_rep (eq. 8).
#include <array>
#include <string>

#include "rotorguard/core/trajectory.h"
#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/pwm_model.h"

namespace rotorguard::planning {

/// Eq. (11): ω_n t_s for a critically damped system settling within 2 %.
inline constexpr double kSettlingConstant = 5.83;

/// The limits a plan keeps (eqs. 16, 17, 23). A limit <= 0 is invalid; an angle limit of
/// +infinity leaves the envelope out (actuator limits only, as in the paper's Fig. 1(b)).
/// The largest PWM input a plan may be given: beyond any PWM scale (the Qball-X4's is 0.06, one in
/// microseconds 2000).
inline constexpr double kMaxPwmInput = 1e4;

struct FlatnessLimits {
  double theta_max_rad = 10.0 * 3.14159265358979323846 / 180.0;  ///< pitch bound, in (0, π/2)
  double phi_max_rad = 10.0 * 3.14159265358979323846 / 180.0;    ///< roll bound, in (0, π/2)
  double rho_angle = 1.0;  ///< ρ_θ = ρ_φ, the model's safety margin, in (0, 1]
  /// The largest PWM input a plan may ask of a motor (the paper's u_max), in (0, the vehicle's
  /// u_max]; 0 takes the vehicle's. At most kMaxPwmInput.
  double u_max = 0.0;
  double rho_u = 1.0;  ///< ρ_u, in (0, 1]
  /// Throws ValidationError naming the field.
  void Validate() const;
};

/// Which limit set t_s.
enum class FlatnessBinding { kNone, kPitch, kRoll, kMotor1, kMotor2, kMotor3, kMotor4 };
const char* ToString(FlatnessBinding b);

struct SettlingTime {
  double t_s = 0.0;          ///< [s]; 0 for a move of zero length
  FlatnessBinding binding = FlatnessBinding::kNone;
  double envelope_s = 0.0;   ///< the largest envelope candidate (eqs. 16-17)
  double actuator_s = 0.0;   ///< the largest actuator candidate (eq. 23)
  /// False when some motor's limit is below its share of the weight, ū_i = (1 − ŵ_i) ρ_u u_max −
  /// m g / 4K <= 0: no settling time keeps it (the vehicle cannot hover within the limit).
  bool feasible = true;
  std::string why;  ///< why not feasible
};

/// Eq. (16) (and eq. 17 for roll): the smallest t_s with |F''(t)| / g ≤ ρ θ_max over the whole
/// reference for a step of `distance_m`: the largest of the candidates at t = 0, 2 t_s / 5.83 and t_s.
double EnvelopeSettlingTime(double distance_m, double angle_max_rad, double rho);

/// Eq. (23) for one motor: the smallest t_s with h + c R ω⁴ (3 − ω t) e^{−ω t} ≤ ū + h over
/// t ∈ [0, t_s], where c R is the motor's signed coefficient (c = ±J/(2 g K L) times the step
/// along its axis) and ū = its limit minus the hover input h. The candidates at t = 0, 4 t_s /
/// 5.83 and t_s whose radicand is negative are the paper's "complex values", ignored; returns 0
/// when none is left (the limit holds for any t_s). Requires ū > 0.
double MotorSettlingTime(double signed_coefficient, double u_bar);

/// The settling time of a move by `delta_m` (x, y; z and yaw are held, as in the paper's
/// eq. 18) for the model's vehicle within `limits`, with estimated losses of effectiveness `w_hat`
/// (zeros: fault-free). Throws ValidationError for invalid limits or losses outside [0, 1).
SettlingTime PlanSettlingTime(const vehicle::PwmQuadModel& model, const FlatnessLimits& limits,
                              const Eigen::Vector2d& delta_m, const Eigen::Vector4d& w_hat = Eigen::Vector4d::Zero());

/// Eq. (19)-(20): the nominal PWM input of each motor along a move flown by the reference below
/// (feed-forward of the flat outputs' fourth derivatives, z and yaw held).
Eigen::Vector4d NominalPwm(const vehicle::PwmQuadModel& model, const Vector3& snap_W);

/// Eq. (8): per axis F(τ) = R − (1 + ω τ) e^{−ω τ} Δ + v0 τ e^{−ω τ}, τ = t − t0, with
/// Δ = R − p0 (eq. 7 when v0 = 0 and p0 = 0), ω = 5.83 / t_s. Position through snap in closed form;
/// before t0 it is the start state. It settles (its deviation from R below 1e-15 of the step)
/// at t0 + 40 / ω and is held exactly there after (duration()).
class CriticallyDampedReference final : public ReferenceTrajectory {
 public:
  /// Throws ValidationError for a non-positive or non-finite t_s or non-finite states.
  CriticallyDampedReference(double t0, const Vector3& p0, const Vector3& v0, const Vector3& goal, double t_s,
                            double yaw = 0.0);
  [[nodiscard]] ReferencePoint Evaluate(double t) const override;
  [[nodiscard]] double duration() const override { return t0_ + 40.0 / omega_; }
  double t0() const { return t0_; }
  double t_s() const { return t_s_; }
  const Vector3& goal() const { return goal_; }

 private:
  /// Derivatives 0..4 of the reference at τ >= 0.
  std::array<Vector3, 5> Derivatives(double tau) const;

  double t0_, t_s_, omega_, yaw_;
  Vector3 p0_, v0_, goal_;
};

}  // namespace rotorguard::planning
