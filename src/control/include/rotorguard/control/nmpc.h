#pragma once
/// Fault-tolerant NMPC of paper 000, Sec. V-A: multiple shooting over N steps of the model with
/// motor dynamics (eqs. 1-3, 6; RK4), the cost of eq. (8) with y and Q of eqs. (10)-(12) and the
/// tilt-prioritised reduced-attitude error of Brescianini & D'Andrea, input bounds 0 <= u <= u_bar
/// and body-rate bounds. Solved by real-time iteration (one Gauss-Newton SQP step per call, split
/// into preparation and feedback, warm-started from the previous solution shifted by the elapsed
/// time) or iterated to convergence. A rotor isolated as failed gets u_bar_i = 0 at run time; the
/// yaw-error weight drops to 0 and the thrust reference switches to the post-failure equilibrium.
/// Offset-free: a disturbance observer estimates what the model misses, and the model predicts
/// with it and with each rotor's known effectiveness (docs/control.md).
#include <Eigen/Core>
#include <algorithm>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rotorguard/control/controller.h"
#include "rotorguard/control/disturbance_observer.h"
#include "rotorguard/control/nmpc_model.h"
#include "rotorguard/control/ocp_qp.h"
#include "rotorguard/core/config_schema.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::control {

struct NmpcOptions {
  int horizon_steps = 20;       ///< N (paper: 20), in [1, 200]
  double step_s = 0.05;         ///< dt between shooting nodes (paper: 50 ms), in (0, 1]
  int integrator_substeps = 1;  ///< RK4 sub-steps per node (1 suffices: docs/control.md), in [1, 20]
  // Weights of eqs. (10)-(11), paper 000 Sec. VI. All >= 0 (r_input > 0).
  Eigen::Vector3d q_position = Eigen::Vector3d(100.0, 100.0, 600.0);
  Eigen::Vector4d q_attitude = Eigen::Vector4d(60.0, 60.0, 60.0, 60.0);  ///< [tilt x, tilt y, tilt^2, yaw]
  Eigen::Vector3d q_velocity = Eigen::Vector3d(5.0, 5.0, 5.0);
  Eigen::Vector3d q_rate = Eigen::Vector3d(1.0, 1.0, 1.0);
  double q_thrust = 1.0;  ///< Q_t on T - t_ref
  double r_input = 1.0;   ///< R on u - t_ref (the paper's R_N; see docs/control.md)
  Eigen::Vector3d max_rate_rad_s = Eigen::Vector3d(10.0, 10.0, 20.0);  ///< |w| bounds, > 0
  /// SQP iterations per call: 1 is the real-time iteration; more iterate towards convergence.
  int max_sqp_iterations = 1;
  /// Converge mode stops when the largest step in (x, u) is below this, > 0.
  double sqp_tolerance = 1e-8;
  /// Real-time iteration only: linearise the dynamics and the cost every this many preparations,
  /// in [1, 20]. In between (a mixed-level iteration, after Bock et al.'s multi-level scheme) the
  /// previous preparation's Jacobians A_k, B_k and Gauss-Newton Hessians Q_k are reused with the
  /// shifted plan's own shooting gaps, residual gradients, input and rate bounds, so that the
  /// condensed Hessian and its factorisation are kept: an RK4 step without sensitivities and
  /// O(N nx^2) condensing instead of sensitivities, O(N^2) condensing and a factorisation. 1 is
  /// the paper's scheme; a rotor reconfiguration always re-linearises (docs/control.md).
  int relinearise_every = 1;
  /// What the model misses, estimated in flight and predicted with (offset-free NMPC).
  DisturbanceObserverOptions disturbance;
  ActiveSetOptions qp;
  /// The QP solver of each iteration: riccati (the stage form factorised by a Riccati recursion,
  /// the default: faster on average) or condensing (the states eliminated, a dense active-set
  /// solve); the same QP, the same solution (docs/control.md, "Two QP solvers").
  OcpQpMethod qp_solver = OcpQpMethod::kRiccati;
  /// The delay the NMPC expects from the instant of a call (the state it is given) to its command
  /// acting on the motors: the cycle's computation and the ESCs' latency [s], in [0, 0.1]. Its
  /// prediction starts from the state propagated over this delay with the commands it has already
  /// sent (the last one acts until the new one does), as delay-compensated MPC does on vehicles.
  /// 0: the state as given. In a FlightStack: stack.command_delay_s, not a key of its own.
  double expected_delay_s = 0.0;
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("horizon_steps", &horizon_steps, {.meaning = "N, the shooting nodes", .min = 1, .max = 200});
    a->Visit("step_s", &step_s, {.meaning = "time between nodes [s]", .max = 1.0, .positive = true});
    a->Visit("integrator_substeps", &integrator_substeps, {.meaning = "RK4 sub-steps per node", .min = 1, .max = 20});
    a->Visit("q_position", &q_position, {.meaning = "Q_p of eq. (10)", .min = 0.0, .max = kMaxWeight});
    a->Visit("q_attitude", &q_attitude,
             {.meaning = "Q_q of eq. (10): tilt x, tilt y, tilt², yaw", .min = 0.0, .max = kMaxWeight});
    a->Visit("q_velocity", &q_velocity, {.meaning = "Q_v of eq. (10)", .min = 0.0, .max = kMaxWeight});
    a->Visit("q_rate", &q_rate, {.meaning = "Q_ω of eq. (10)", .min = 0.0, .max = kMaxWeight});
    a->Visit("q_thrust", &q_thrust, {.meaning = "Q_t of eq. (10) on the motor thrusts", .min = 0.0, .max = kMaxWeight});
    a->Visit("r_input", &r_input, {.meaning = "R of eq. (10) on the commands", .max = kMaxWeight, .positive = true});
    a->Visit("max_rate_rad_s", &max_rate_rad_s,
             {.meaning = "body-rate bounds [rad/s]", .max = kMaxBodyRateRadS, .positive = true});
    a->Visit("max_sqp_iterations", &max_sqp_iterations,
             {.meaning = "SQP iterations a cycle (1: the real-time iteration)", .min = 1, .max = 1000});
    a->Visit("relinearise_every", &relinearise_every,
             {.meaning = "a full linearisation every this many preparations (docs/control.md)", .min = 1, .max = 20});
    a->Visit("qp_solver", &qp_solver, {.meaning = "condensing or riccati (docs/control.md, \"Two QP solvers\")"});
    a->Visit("disturbance", &disturbance,
             {.meaning = "the disturbance observer that makes the NMPC offset-free (docs/control.md)"});
  }
};

enum class NmpcStatus {
  kNotSolved,        ///< Compute() was not called
  kSolved,           ///< the QP(s) solved; in converge mode, the step fell below tolerance
  kMaxIterations,    ///< converge mode stopped at max_sqp_iterations
  kFallback,         ///< the QP failed or produced non-finite values: the shifted previous plan was used
  kInvalidInput,     ///< non-finite estimate or reference: hover command
};
std::string_view ToString(NmpcStatus status);

struct NmpcSummary {
  NmpcStatus status = NmpcStatus::kNotSolved;
  int sqp_iterations = 0;
  int qp_iterations = 0;        ///< active-set changes, summed over SQP iterations
  double step_norm = 0.0;       ///< largest |dx|, |du| of the last SQP step
  double dynamics_gap = 0.0;    ///< largest shooting gap before the last step
  /// First-order optimality residual of the NLP: max(step_norm, dynamics_gap). A zero Gauss-Newton
  /// step at a gap-free plan is exactly a KKT point (the QP uses the NLP's exact gradient and
  /// constraint linearisation), so this vanishes at the solution of the converge mode.
  double kkt_residual = 0.0;
  double objective = 0.0;       ///< of the last QP
  double prepare_time_s = 0.0;  ///< linearisation, condensing, factorisation (RTI: for the next call)
  double feedback_time_s = 0.0; ///< the QP that needs the measured state
  double command_latency_s = 0.0;  ///< from the call to the command (RTI: the feedback phase)
  double solve_time_s = 0.0;    ///< the whole call, preparation for the next call included
  long fallbacks = 0;           ///< cumulative count since construction
  int rate_bounds_relaxed = 0;  ///< QPs of this call re-solved without rate bounds (infeasible with them)
  /// Preparations of this call that linearised, and that reused the last linearisation
  /// (NmpcOptions::relinearise_every).
  int linearisations = 0;
  int linearisations_reused = 0;
  bool IsSolutionUsable() const { return status == NmpcStatus::kSolved || status == NmpcStatus::kMaxIterations; }
  std::string BriefReport() const;
};

class NmpcController final : public Controller {
 public:
  NmpcController(const vehicle::VehicleParams& vehicle, const NmpcOptions& options);
  std::string_view name() const override { return "nmpc"; }
  void Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t, double dt,
               RotorVector* thrust_command) override;
  void Reset() override;

  /// Reconfigures for a failed rotor: u_bar_i = 0, yaw weight 0, post-failure thrust reference
  /// (a healthy diagonal twin idles, the others share the weight with zero roll/pitch torque, in
  /// the least-squares sense when that is impossible) and reference spin. No rebuild. Throws
  /// std::invalid_argument for a rotor out of range.
  void SetRotorFailed(int rotor) override;
  /// A rotor delivers only `effectiveness` of its thrust and torque (a partial loss; <= 0 is a
  /// failure): its column of the model scales, and the thrust reference reallocates with yaw kept.
  /// Throws std::invalid_argument for a rotor out of range or a non-finite value.
  void SetRotorEffectiveness(int rotor, double effectiveness) override;
  /// The disturbance estimates return to their values at time t [s] (DisturbanceObserver::RewindTo):
  /// a fault just put into the model was, until then, partly estimated as a disturbance.
  void RewindDisturbance(double t) { observer_.RewindTo(t); }
  const std::vector<bool>& failed_rotors() const { return failed_; }
  /// The model's correction in use: rotor effectiveness and the disturbance estimates.
  const ModelCorrection& model_correction() const { return model_.correction(); }
  const NmpcSummary& summary() const { return summary_; }
  const NmpcOptions& options() const { return options_; }
  /// The plan's input at the plan's time t + expected_delay_s, interpolated between its nodes as
  /// the warm start's shift does: the shifted plan an executor holds while a cycle is late.
  bool PlannedCommand(double t, RotorVector* thrust_command) const override;
  /// The current plan: N + 1 states and N inputs (after the last call).
  const std::vector<Eigen::VectorXd>& planned_states() const { return x_; }
  const std::vector<Eigen::VectorXd>& planned_inputs() const { return u_; }
  /// The thrust reference t_ref in use for a total thrust (hover split, or the post-failure
  /// equilibrium), with the rotor thrusts that balance the estimated disturbance torque.
  Eigen::VectorXd ThrustReference(double total_thrust) const;

  /// Gauss-Newton cost of one node (for tests): residual y and its Jacobian dy/dx at `x` for the
  /// reference at time t.
  void Residual(const Eigen::VectorXd& x, const ReferencePoint& ref, Eigen::VectorXd* y, Eigen::MatrixXd* dy_dx) const;
  /// The cost of one node of the OCP, 1/2 y' W y (+ 1/2 r |u - t_ref|^2 when `u` is given), and its
  /// gradients: what an independent NLP solver needs to solve the same discretised problem.
  double NodeCost(const Eigen::VectorXd& x, const Eigen::VectorXd* u, const ReferencePoint& ref,
                  Eigen::VectorXd* grad_x, Eigen::VectorXd* grad_u) const;
  /// Upper input bounds u_bar (zero for failed rotors); the lower bounds are zero.
  const Eigen::VectorXd& input_upper_bounds() const { return u_max_; }
  /// The state the last call's plan started from: the given state propagated over
  /// expected_delay_s (NmpcOptions), at the call's time plus that delay.
  const Eigen::VectorXd& predicted_state() const { return x0_; }

 private:
  void Initialise(const Eigen::VectorXd& x0, const ReferenceTrajectory& reference, double t);
  void ShiftBy(double elapsed_s);
  bool SqpIteration(const Eigen::VectorXd& x0, const ReferenceTrajectory& reference, double t);
  /// Linearisation, condensing and factorisation around the current plan (no measurement needed).
  /// `reuse`: keep the last linearisation's A_k, B_k and Q_k (NmpcOptions::relinearise_every).
  bool PrepareIteration(const ReferenceTrajectory& reference, double t, bool reuse = false);
  /// The prepared QP for the measured state, and the plan update.
  bool FeedbackIteration(const Eigen::VectorXd& x0);
  Eigen::Quaterniond ReferenceAttitude(const ReferencePoint& ref) const;
  /// ThrustReference as an expression on the members (no allocation on the control-rate path).
  auto ThrustReferenceOf(double total) const { return total * unit_split_ + torque_offset_; }
  Eigen::Vector3d ReferenceThrustVector(const ReferencePoint& ref) const;
  double ReferenceTotalThrust(const ReferencePoint& ref) const;
  void HoverCommand(RotorVector* thrust_command) const;
  /// x0_ (the state at time t) carried to t + expected_delay_s through the model, each command
  /// sent acting from its instant plus the delay (the motors' state holds before the first).
  void PredictOverDelay(double t);
  /// Remembers a command sent at time t (a ring of kSentCommands).
  void RememberSent(double t, const RotorVector& command);

  vehicle::VehicleParams vehicle_;
  NmpcOptions options_;
  NmpcModel model_;
  Rk4Sensitivity integrator_;
  int nx_, nu_, N_;
  OcpQp qp_;
  std::unique_ptr<OcpQpSolver> qp_solver_;
  Eigen::VectorXd weights_;          // diagonal of W for y (nx entries)
  Eigen::VectorXd u_max_;
  DisturbanceObserver observer_;   // the rotors' effectiveness (0 once failed) is model_'s
  Eigen::VectorXd unit_split_;     // the thrust reference per newton of total thrust
  Eigen::MatrixXd torque_split_;   // rotor thrusts per N m of roll, pitch, yaw torque (n x 3)
  Eigen::VectorXd torque_offset_;  // torque_split_ times the torque the disturbance asks for
  /// The splits for the failed rotors and the effectiveness: the minimum-norm split with yaw
  /// while every rotor flies; else the post-failure one (SetRotorFailed).
  void UpdateThrustSplit();
  /// After a failure: the rotors that carry the weight (not failed, not a failed rotor's twin).
  std::vector<int> ActiveRotorsAfterFailure() const;
  /// One rotor's effectiveness into the model, and the splits for it.
  void SetModelEffectiveness(int rotor, double eta);
  /// The observer's estimates into the model, the thrust reference and the reference spin.
  void ApplyCorrection();
  bool AnyFailed() const { return std::find(failed_.begin(), failed_.end(), true) != failed_.end(); }
  std::vector<bool> failed_;
  Eigen::Vector3d spin_reference_ = Eigen::Vector3d::Zero();
  std::vector<Eigen::VectorXd> x_, u_;  // shooting nodes and inputs
  std::vector<Eigen::VectorXd> x_shift_, u_shift_;
  bool initialised_ = false;
  double last_t_ = 0.0;
  double plan_t0_ = 0.0;  // the plan's time (a call's time plus the expected delay) at node 0
  std::optional<double> prepared_for_t_;  // time the prepared QP is for, in RTI mode
  // RTI preparations since the last linearisation; -1 forces the next one to linearise (the
  // weights or bounds' pattern changed, or there is no linearisation to reuse).
  int reused_since_linearisation_ = -1;
  double gap_ = 0.0;
  Eigen::VectorXd x0_delta_;
  NmpcSummary summary_;
  /// The commands sent, newest last in a ring: what acts during the next call's delay.
  static constexpr int kSentCommands = 8;
  struct SentCommand {
    double t = -std::numeric_limits<double>::infinity();
    Eigen::VectorXd u;
  };
  std::vector<SentCommand> sent_;
  int sent_next_ = 0;
  // scratch
  Eigen::VectorXd x_next_, y_, x0_, weighted_y_, k_[4], x_stage_, u_acting_;
  Eigen::MatrixXd dy_;
};

}  // namespace rotorguard::control
