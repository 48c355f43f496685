#pragma once
/// Paper 004's planning and re-planning, Sec. III, as the reference a stack follows: every leg to
/// a waypoint is a critically damped move (eq. 7, from the current reference state: eq. 8) whose
/// settling time is the largest closed-form candidate (PlanSettlingTime); on a detected fault the
/// leg is re-planned with a very long settling time (`hold_t_s`, the paper's 900 s: the vehicle
/// stays nearly in place) while the UKF identifies the loss; once its estimate has settled (at
/// least `min_hold_s`, at most `max_hold_s` later) the remaining distance is re-planned with the
/// degraded actuator limit (1 − ŵ_i) ρ_u u_max, and the vehicle continues, returns home or lands
/// depending on that settling time against `time_budget_s`. Every decision is logged.
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/planning/flatness.h"

namespace rotorguard::planning {

struct FlatnessNavigatorOptions {
  FlatnessLimits limits;
  // Every time in (0, kMaxTimeoutS] (min_hold_s from 0): an hour is longer than a battery lasts.
  double hold_t_s = 900.0;      ///< settling time of the slow trajectory after a detection [s], > 0
  double min_hold_s = 3.0;      ///< the shortest hold [s], >= 0
  double max_hold_s = 30.0;     ///< replan after this even if the estimate has not settled [s], >= min_hold_s
  /// The longest settling time of a re-planned leg the mission accepts [s], > 0: beyond it the
  /// vehicle returns home if that is within the budget, else lands.
  double time_budget_s = 60.0;
  double min_t_s = 1.0;         ///< settling time of a leg without a horizontal move [s], > 0
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("theta_max_deg", DegreesOf{&limits.theta_max_rad},
             {.meaning = "pitch bound θ_max of eq. (16) [deg]", .min = 0.0, .max = 90.0});
    a->Visit("phi_max_deg", DegreesOf{&limits.phi_max_rad},
             {.meaning = "roll bound φ_max [deg]", .min = 0.0, .max = 90.0});
    a->Visit("rho_angle", &limits.rho_angle,
             {.meaning = "ρ_θ = ρ_φ, the model's safety margin", .max = 1.0, .positive = true});
    a->Visit("u_max", &limits.u_max,
             {.meaning = "the largest PWM input a plan may ask of a motor (0: the vehicle's)",
              .min = 0.0,
              .max = kMaxPwmInput});
    a->Visit("rho_u", &limits.rho_u, {.meaning = "ρ_u of eq. (23)", .max = 1.0, .positive = true});
    a->Visit("hold_t_s", &hold_t_s,
             {.meaning = "settling time of the slow trajectory held after a detection [s]",
              .max = kMaxTimeoutS,
              .positive = true});
    a->Visit("min_hold_s", &min_hold_s, {.meaning = "the shortest hold [s]", .min = 0.0, .max = kMaxTimeoutS});
    a->Visit("max_hold_s", &max_hold_s,
             {.meaning = "re-plan after this even if the estimate has not settled [s], at least min_hold_s",
              .min = 0.0,
              .max = kMaxTimeoutS});
    a->Visit("time_budget_s", &time_budget_s,
             {.meaning = "the longest re-planned leg accepted [s]; beyond it: return home, or land",
              .max = kMaxTimeoutS,
              .positive = true});
    a->Visit(
        "min_t_s", &min_t_s,
        {.meaning = "settling time of a leg without a horizontal move [s]", .max = kMaxTimeoutS, .positive = true});
  }
};

struct FlatnessDecision {
  double t = 0.0;
  std::string kind;    ///< "plan", "hold", "continue", "return", "land"
  double t_s = 0.0;    ///< the leg's settling time (0 for land)
  std::string binding; ///< the limit that set it
  Eigen::Vector4d w_hat = Eigen::Vector4d::Zero();  ///< the losses it was planned with
  std::string reason;
  Vector3 delta_m = Vector3::Zero();  ///< the distance the leg covers (Δ of eq. 8)
  double envelope_s = 0.0, actuator_s = 0.0;  ///< the candidates (eqs. 16-17 and 23)
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("t", &t);
    a->Visit("kind", &kind);
    a->Visit("t_s", &t_s);
    a->Visit("binding", &binding);
    a->Visit("w_hat", &w_hat);
    a->Visit("reason", &reason);
    a->Visit("delta_m", &delta_m);
    a->Visit("envelope_s", &envelope_s);
    a->Visit("actuator_s", &actuator_s);
  }
};

class FlatnessNavigator final : public ReferenceTrajectory {
 public:
  /// Throws ValidationError naming the field. Holds `home` until given a goal.
  FlatnessNavigator(const vehicle::PwmQuadModel& model, const FlatnessNavigatorOptions& options, const Vector3& home,
                    double yaw = 0.0);

  /// Plans a leg to `goal` from the reference state at t.
  void SetGoal(const Vector3& goal, double t);
  /// A fault was detected at t: hold (the slow re-plan) until the estimate settles.
  void OnFaultDetected(double t);
  /// At the planner's rate: ends a hold once `estimate_settled` (or after max_hold_s) with the
  /// re-plan and its decision.
  void Update(double t, bool estimate_settled, const Eigen::Vector4d& w_hat);

  ReferencePoint Evaluate(double t) const override;
  double duration() const override { return std::numeric_limits<double>::infinity(); }
  /// The current leg has settled (t past its start plus t_s) and was not a hold.
  bool arrived(double t) const;
  bool holding() const { return hold_since_.has_value(); }
  /// Set when the decision was to land: the reason.
  const std::optional<std::string>& land_request() const { return land_request_; }
  /// The decision was to return home: the mission's other waypoints are dropped.
  bool returning() const { return returning_; }
  const std::vector<FlatnessDecision>& decisions() const { return decisions_; }
  /// The leg being flown, if any.
  const std::optional<CriticallyDampedReference>& leg() const { return leg_; }
  /// Counts the changes of what is followed (a new leg); see Replanner::path_serial.
  std::uint64_t path_serial() const { return path_serial_; }
  /// An immutable copy of what is followed (FollowedReference): Evaluate's reference, as a value.
  std::shared_ptr<const ReferenceTrajectory> Followed() const;

 private:
  /// A leg from the reference state at t to `goal` with the losses `w_hat`; nullopt when
  /// infeasible (the reason in *why).
  std::optional<SettlingTime> Plan(const Vector3& goal, double t, const Eigen::Vector4d& w_hat, std::string* why) const;
  void Start(const Vector3& goal, double t, double t_s);

  vehicle::PwmQuadModel model_;
  FlatnessNavigatorOptions options_;
  Vector3 home_, goal_;
  double yaw_;
  std::optional<CriticallyDampedReference> leg_;
  std::uint64_t path_serial_ = 0;
  std::optional<double> hold_since_;
  std::optional<std::string> land_request_;
  bool returning_ = false;
  std::vector<FlatnessDecision> decisions_;
};

}  // namespace rotorguard::planning
