#pragma once
/// Composite fault detection and diagnosis of paper 000, Sec. V-B: the motor index (eq. 13) from
/// ESC telemetry, the thrust/torque-loss observer (eqs. 14-17) on filtered IMU data and measured
/// rotor speeds, and the take-off detector (eq. 18). It sees only sensor messages, the stack's
/// estimate and its own commands; docs/fdd.md gives the filter design, docs/results.md the
/// measured latencies.
/// After an isolation the motor index and the observer keep watching the remaining rotors for a
/// second complete failure; partial losses and the take-off detector assume a single failure, as
/// the paper does.
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/filters.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/core/rpm_notch.h"
#include "rotorguard/core/types.h"
#include "rotorguard/fdd/commanded_motors.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::fdd {

struct CompositeFddOptions {
  /// Motor index M_i = w_measured / w_expected (eq. 13) at or below this isolates a motor failure
  /// (gamma_M, paper: 0.2), in (0, 1).
  double motor_index_threshold = 0.2;
  /// Consecutive telemetry samples the index must stay low (debounce), >= 1.
  int motor_index_samples = 2;
  /// The index's reference, the motors as commanded, waits this much beyond the command delay
  /// the stack expects [s], in [0, 0.1]: the true delay varies from vehicle to vehicle and cycle to
  /// cycle, and a reference that leads the motors reads a healthy motor spinning up as stopped.
  /// Judged against the latest plausible response, a stopped motor is found this much later.
  double motor_index_delay_margin_s = 0.005;
  /// Motor shortfall: a stopping motor slows faster than any command lets a healthy one
  /// (docs/fdd.md, "The motor shortfall"). S_i = 1 - T_measured / floor, the floor the lowest thrust
  /// a healthy motor can have now (HealthyThrustFloor) from its telemetry motor_shortfall_window_s
  /// ago; S_i above this for motor_index_samples samples isolates a motor failure (gamma_S), in
  /// (0, 1]: 1 turns the rule off (S_i never exceeds 1).
  double motor_shortfall_threshold = 0.05;
  /// The window over which the floor is taken [s], in (0, 0.1].
  double motor_shortfall_window_s = 0.005;
  /// A healthy motor may be this fraction faster than the vehicle file's time constant, in [0, 0.9].
  double motor_lag_fraction = 0.3;
  /// A command may act with any delay from 0 to command_delay_s plus this [s], in [0, 0.1].
  double motor_delay_span_s = 0.015;
  /// Each rotor's measured-to-modelled thrust ratio (its telemetry against CommandedMotors), which
  /// scales the commands the floor starts from, is the ratio of their averages over this time
  /// constant [s], in (0, 100] ...
  double motor_scale_time_constant_s = 0.5;
  /// ... less this fraction, in [0, 0.5].
  double motor_scale_margin = 0.03;
  /// The indices are evaluated only while the rotor's thrust (expected, for M_i; measured, for
  /// P_i) exceeds this fraction of its share of the hover thrust, W / n (w_expected -> 0 makes
  /// the ratios meaningless), in (0, 1].
  double min_thrust_fraction = 0.1;
  /// Propeller index P_i = thrust lost / thrust the rotor should give (eq. 17) above this isolates
  /// a propeller failure (gamma_P, paper: 0.8), in (0, 1].
  double propeller_index_threshold = 0.8;
  /// P_i must stay above its threshold this long [s], >= 0.
  double propeller_persistence_s = 0.015;
  /// Partial loss: P_i between this and the propeller threshold for degraded_persistence_s is
  /// reported as degradation with eta = mean P_i, in (0, propeller_index_threshold).
  double degraded_threshold = 0.15;
  double degraded_persistence_s = 0.5;  ///< [s], > 0
  /// Cut-off of the low-pass filters on specific force, body rate, angular acceleration and the
  /// measured wrench [Hz], > 0 and below the IMU's Nyquist frequency.
  double filter_cutoff_hz = 20.0;
  /// The observer learns the healthy vehicle's residual wrench (what the vehicle file misses: a
  /// centre-of-gravity offset, mass and thrust-coefficient errors) with this time constant [s]
  /// while airborne, every rotor healthy and every |P_i| within degraded_threshold, and measures
  /// losses from it (docs/fdd.md). 0: losses from the file's model alone. In [0, 100].
  double baseline_time_constant_s = 0.5;
  /// After an isolation the observer learns the reconfigured vehicle's residual for this long [s]
  /// and judges nothing meanwhile (the reconfiguration's step through the motor lag and the
  /// filters); then it watches the remaining rotors for a second complete loss (docs/fdd.md).
  /// In [0, 100].
  double post_isolation_relearn_s = 0.1;
  /// ... and isolates a second propeller failure only while the force balance misses at least
  /// this fraction of that rotor's thrust, in [0, 1].
  double second_failure_missing_thrust_fraction = 0.5;
  /// ... on a rotor giving at least this fraction of the hover thrust per rotor, in [0, 1]: below
  /// it the loss is within what the spinning vehicle's force balance swings by (docs/fdd.md), and
  /// the rotor matters little (the one the controller turns nearly off beside a failure).
  double second_failure_min_thrust_fraction = 0.5;
  /// ... above gamma_P for most of this long [s]: the lower median of its gated P_i over the last
  /// second_failure_persistence_s exceeds gamma_P. A vehicle spinning on three rotors drives them
  /// through steps the telemetry lags, and the mismatch reads as a short loss, which a window
  /// rejects; but a lost propeller's P_i on that spinning vehicle swings about gamma_P, and a rule
  /// that restarts at every dip below it (the first failure's) waits long after the loss
  /// (docs/fdd.md, "Second failures"). In [0, 10].
  double second_failure_persistence_s = 0.05;
  /// Take-off detector (eq. 18): active while the vehicle is airborne below this altitude [m] and
  /// within takeoff_window_s of lift-off, > 0.
  double takeoff_max_altitude_m = 0.6;
  double takeoff_window_s = 3.0;
  /// ... after the flight's first lift-off, or one from at least this long on the ground [s], in
  /// [0, 100]: a touchdown's bounce is not a take-off.
  double takeoff_rest_s = 0.3;
  /// The take-off index: the filtered roll/pitch angular acceleration magnitude over the one that
  /// losing one rotor's share of the hover thrust causes (the smallest over the rotors,
  /// |I^-1 (r_i x (W/n) e3)|). Above this it fires, > 0 ...
  double takeoff_index_threshold = 0.47;
  /// ... pointing within this cosine of the signature of losing one rotor, in (0, 1] ...
  double takeoff_direction_cosine = 0.9;
  /// ... while that rotor misses at least this fraction of its expected thrust, by its telemetry
  /// (a motor slowing) or by the observer's force balance (a propeller lost), in [0, 1]: a
  /// centre-of-gravity offset turns the vehicle at lift-off as a lost rotor does, but costs no
  /// thrust.
  double takeoff_missing_thrust_fraction = 0.5;
  /// Nominal IMU sample rate [Hz] (filters are designed for it), > 2 * filter_cutoff_hz.
  double imu_rate_hz = 333.0;
  /// IMU mounting point relative to the centre of gravity, body frame [m]: its lever-arm
  /// accelerations are removed before the observer uses the accelerometer.
  Vector3 imu_position_m = Vector3::Zero();
  /// The delay from a command's instant to the motors acting on it that the stack expects [s],
  /// >= 0: the motors are modelled as acting on it then (CommandedMotors). Set by the stack from
  /// stack.command_delay_s, not a key of its own.
  double command_delay_s = 0.0;
  /// The notches the stack runs its IMU through before this detector (stack.imu_notch): the
  /// detector passes its telemetry's wrench through a bank alike, so that the two it compares are
  /// delayed alike. Set by the stack, not a key of its own; disabled by default.
  RpmNotchOptions imu_notch = [] {
    RpmNotchOptions o;
    o.enabled = false;
    return o;
  }();
  void Validate() const;
  /// These options with every threshold out of reach (gamma_M 1e-6, gamma_P 1, take-off 1e6): no
  /// rule fires in fault-free flight, and the debounce, persistence and gates, which define the
  /// rules' statistics (IndexExtremes), are unchanged.
  CompositeFddOptions Disarmed() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("motor_index_threshold", &motor_index_threshold,
             {.meaning = "γ_M: a motor index M_i (eq. 13) at or below it isolates a motor failure",
              .max = 1.0,
              .positive = true,
              .open_max = true});
    a->Visit("motor_index_samples", &motor_index_samples,
             {.meaning = "consecutive telemetry samples the index must stay low", .min = 1, .max = 1000});
    a->Visit("motor_index_delay_margin_s", &motor_index_delay_margin_s,
             {.meaning = "the index's reference waits this much beyond stack.command_delay_s [s]: the delay's "
                         "uncertainty",
              .min = 0.0,
              .max = 0.1});
    a->Visit("motor_shortfall_threshold", &motor_shortfall_threshold,
             {.meaning = "γ_S: a motor shortfall S_i above it for motor_index_samples isolates a motor failure "
                         "(1: off)",
              .max = 1.0,
              .positive = true});
    a->Visit("motor_shortfall_window_s", &motor_shortfall_window_s,
             {.meaning = "the window of the healthy thrust floor [s]", .max = 0.1, .positive = true});
    a->Visit("motor_lag_fraction", &motor_lag_fraction,
             {.meaning = "a healthy motor may be this fraction faster than the file's time constant", .min = 0.0, .max = 0.9});
    a->Visit("motor_delay_span_s", &motor_delay_span_s,
             {.meaning = "a command may act with any delay up to stack.command_delay_s plus this [s]", .min = 0.0, .max = 0.1});
    a->Visit("motor_scale_time_constant_s", &motor_scale_time_constant_s,
             {.meaning = "each rotor's measured-to-modelled thrust ratio is averaged over this [s] ...",
              .max = 100.0,
              .positive = true});
    a->Visit("motor_scale_margin", &motor_scale_margin,
             {.meaning = "... and lowered by this fraction", .min = 0.0, .max = 0.5});
    a->Visit("min_thrust_fraction", &min_thrust_fraction,
             {.meaning = "the indices are evaluated only above this fraction of a rotor's hover thrust W/n",
              .max = 1.0,
              .positive = true});
    a->Visit("propeller_index_threshold", &propeller_index_threshold,
             {.meaning = "γ_P: a propeller index P_i (eq. 17) above it isolates a propeller failure",
              .max = 1.0,
              .positive = true});
    a->Visit("propeller_persistence_s", &propeller_persistence_s,
             {.meaning = "P_i must stay above γ_P this long [s]", .min = 0.0, .max = 10.0});
    a->Visit("degraded_threshold", &degraded_threshold,
             {.meaning = "P_i between this and γ_P for degraded_persistence_s is a partial loss",
              .max = 1.0,
              .positive = true,
              .rule_text = "in (0, propeller_index_threshold)"});
    a->Visit("degraded_persistence_s", &degraded_persistence_s,
             {.meaning = "how long a partial loss must last [s]", .min = 1e-3, .max = 100.0});
    a->Visit("filter_cutoff_hz", &filter_cutoff_hz,
             {.meaning = "cut-off of the observer's low-pass filters [Hz], below the IMU's Nyquist frequency",
              .max = kMaxRateHz / 2.0,
              .positive = true});
    a->Visit("takeoff_max_altitude_m", &takeoff_max_altitude_m,
             {.meaning = "the take-off detector (eq. 18) runs below this altitude [m] ...", .min = 1e-3, .max = 100.0});
    a->Visit("takeoff_window_s", &takeoff_window_s,
             {.meaning = "... and within this long of lift-off [s] ...", .min = 1e-3, .max = 1000.0});
    a->Visit("takeoff_rest_s", &takeoff_rest_s,
             {.meaning = "... of the first lift-off, or one after this long on the ground (a touchdown's bounce is no take-off) [s]",
              .min = 0.0,
              .max = 100.0});
    // 1e6: out of reach, the detector off (Disarmed).
    a->Visit(
        "takeoff_index_threshold", &takeoff_index_threshold,
        {.meaning = "roll/pitch angular acceleration, over that of losing one rotor's hover thrust, that fires it ...",
         .min = 1e-6,
         .max = 1e6});
    a->Visit("takeoff_direction_cosine", &takeoff_direction_cosine,
             {.meaning = "... pointing within this cosine of the loss of one rotor ...", .max = 1.0, .positive = true});
    a->Visit("takeoff_missing_thrust_fraction", &takeoff_missing_thrust_fraction,
             {.meaning = "... while that rotor misses this fraction of its expected thrust", .min = 0.0, .max = 1.0});
    a->Visit("baseline_time_constant_s", &baseline_time_constant_s,
             {.meaning = "the healthy residual is learnt with this time constant [s] (0: off; docs/fdd.md)",
              .min = 0.0,
              .max = 100.0});
    a->Visit("post_isolation_relearn_s", &post_isolation_relearn_s,
             {.meaning = "after an isolation the residual is relearnt this long [s] before a second failure is sought",
              .min = 0.0,
              .max = 100.0});
    a->Visit(
        "second_failure_missing_thrust_fraction", &second_failure_missing_thrust_fraction,
        {.meaning = "... and a second propeller failure must miss this fraction of its thrust in the force balance",
         .min = 0.0,
         .max = 1.0});
    a->Visit("second_failure_min_thrust_fraction", &second_failure_min_thrust_fraction,
             {.meaning = "... on a rotor giving at least this fraction of the hover thrust per rotor", .min = 0.0, .max = 1.0});
    a->Visit("second_failure_persistence_s", &second_failure_persistence_s,
             {.meaning = "... for this long [s]", .min = 0.0, .max = 10.0});
  }
};

/// kFailed: a rotor isolated as failed by a method that cannot tell the motor from the propeller.
enum class RotorHealth { kOk, kMotorFailed, kPropellerFailed, kDegraded, kFailed };
inline constexpr EnumName<RotorHealth> kRotorHealthNames[] = {{RotorHealth::kOk, "ok"},
                                                              {RotorHealth::kMotorFailed, "motor_failed"},
                                                              {RotorHealth::kPropellerFailed, "propeller_failed"},
                                                              {RotorHealth::kDegraded, "degraded"},
                                                              {RotorHealth::kFailed, "failed"}};
constexpr std::span<const EnumName<RotorHealth>> NamesOf(const RotorHealth*) { return kRotorHealthNames; }
inline std::string_view ToString(RotorHealth health) { return ToName(health); }
/// Motor, propeller or unclassified failure: the rotor is out of the vehicle.
bool IsIsolated(RotorHealth health);

struct RotorStatus {
  RotorHealth health = RotorHealth::kOk;
  double eta = 0.0;              ///< estimated loss of effectiveness (degraded), in [0, 1]
  double motor_index = 1.0;      ///< M_i, latest
  double propeller_index = 0.0;  ///< P_i, latest
  std::optional<double> detected_s;  ///< when the health left kOk
  /// When the evidence for the diagnosis began: the first sample of the index that crossed its
  /// threshold (the detection time for detectors that cannot tell).
  std::optional<double> onset_s;
  std::string detector;          ///< "motor_index", "thrust_loss_observer", "takeoff"
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("health", &health);
    a->Visit("eta", &eta);
    a->Visit("motor_index", &motor_index);
    a->Visit("propeller_index", &propeller_index);
    a->Visit("detected_s", &detected_s);
    a->Visit("onset_s", &onset_s);
    a->Visit("detector", &detector);
  }
};

/// The most alarming values a composite FDD's indices took. The first three are the indices
/// themselves; the others are what each rule compares with its threshold (the index through
/// the rule's debounce, persistence or gates), so a threshold beyond them raises no alarm on that
/// flight: the statistics a margin is stated on (fdd-calibrate, docs/fdd.md).
struct IndexExtremes {
  double min_motor_index = 1.0;      ///< lowest M_i (eq. 13)
  double max_propeller_index = 0.0;  ///< highest P_i (eq. 17)
  double max_takeoff_index = 0.0;    ///< highest take-off index (eq. 18's statistic, normalised)
  /// Lowest M_i held over motor_index_samples consecutive telemetry samples: gamma_M at or above it
  /// would have isolated a motor.
  double debounced_motor_index = 1.0;
  /// Highest P_i held for propeller_persistence_s: gamma_P below it would have isolated a propeller.
  double persistent_propeller_index = 0.0;
  /// Highest take-off index while its direction and missing-thrust conditions held: a take-off
  /// threshold below it would have fired.
  double gated_takeoff_index = 0.0;
  /// After an isolation: highest lower median, over second_failure_persistence_s, of a remaining
  /// rotor's P_i through the second-failure gates (force balance, thrust, largest loss; 0 where
  /// they fail): gamma_P below it would have isolated a second rotor. 0 in a flight with no
  /// isolation.
  double second_failure_index = 0.0;
  /// Highest motor shortfall S_i held over motor_index_samples consecutive telemetry samples:
  /// gamma_S below it would have isolated a motor.
  double debounced_motor_shortfall = 0.0;
  void Merge(const IndexExtremes& other);
  template <typename Archive>
  void Serialize(Archive* a);
};

/// Each statistic's name in run summaries (fdd.healthy_extremes.NAME) and its member.
inline constexpr std::array<std::pair<std::string_view, double IndexExtremes::*>, 8> kIndexExtremesFields{{
    {"min_motor_index", &IndexExtremes::min_motor_index},
    {"max_propeller_index", &IndexExtremes::max_propeller_index},
    {"max_takeoff_index", &IndexExtremes::max_takeoff_index},
    {"debounced_motor_index", &IndexExtremes::debounced_motor_index},
    {"persistent_propeller_index", &IndexExtremes::persistent_propeller_index},
    {"gated_takeoff_index", &IndexExtremes::gated_takeoff_index},
    {"second_failure_index", &IndexExtremes::second_failure_index},
    {"debounced_motor_shortfall", &IndexExtremes::debounced_motor_shortfall},
}};

template <typename Archive>
void IndexExtremes::Serialize(Archive* a) {
  for (const auto& [name, member] : kIndexExtremesFields) a->Visit(name.data(), &(this->*member));  // literals: terminated
}

/// The interface every fault detector implements, so that a stack or a benchmark swaps them by name.
class FaultDetector {
 public:
  virtual ~FaultDetector() = default;
  virtual std::string_view name() const = 0;
  virtual void OnImu(const ImuSample& imu) = 0;
  virtual void OnEscTelemetry(const EscTelemetry& esc) = 0;
  /// The command sent to the motors (its instant and thrusts) and the stack's current estimate.
  virtual void SetCommand(const RotorCommand& command) = 0;
  virtual void SetEstimate(const StateEstimate& estimate) = 0;
  virtual const std::vector<RotorStatus>& rotors() const = 0;
  /// Rotors isolated as failed since the last call; cleared by the call.
  virtual std::vector<int> TakeNewIsolations() = 0;
};

/// Bookkeeping every detector shares: per-rotor statuses, isolations not yet taken, the estimate.
class FaultDetectorBase : public FaultDetector {
 public:
  void SetEstimate(const StateEstimate& estimate) override;
  const std::vector<RotorStatus>& rotors() const override { return rotors_; }
  std::vector<int> TakeNewIsolations() override;
  /// The first rotor isolated as failed, if any.
  std::optional<int> first_isolated_rotor() const { return first_isolated_; }

 protected:
  explicit FaultDetectorBase(int num_rotors);
  /// Marks a rotor's health at time t, on evidence that began at `onset` (default t); a failure
  /// (motor, propeller or unclassified) isolates it once. A rotor already isolated keeps its
  /// diagnosis.
  void Isolate(int rotor, RotorHealth health, double t, const char* detector, std::optional<double> onset = {});

  std::vector<RotorStatus> rotors_;
  std::vector<int> new_isolations_;
  std::optional<int> first_isolated_;
  StateEstimate estimate_;
  bool have_estimate_ = false;
};

class CompositeFdd final : public FaultDetectorBase {
 public:
  CompositeFdd(const vehicle::VehicleParams& vehicle, const CompositeFddOptions& options);

  std::string_view name() const override { return "composite"; }
  void OnImu(const ImuSample& imu) override;
  void OnEscTelemetry(const EscTelemetry& esc) override;
  /// The command sent to the motors: the motor index's reference.
  void SetCommand(const RotorCommand& command) override;
  /// The observer's latest per-rotor thrust-loss estimate [N] (eq. 16, from the baseline), for
  /// inspection.
  const Eigen::VectorXd& thrust_loss() const { return thrust_loss_; }
  /// The healthy residual wrench learnt so far [N, N m]: thrust along body z, then torque.
  const Eigen::Vector4d& baseline() const { return baseline_; }
  /// The take-off index while its window is active, else 0 (for threshold calibration).
  double takeoff_index() const { return takeoff_index_; }
  /// What the indices are normalised by: a rotor's share of the hover thrust W/n [N], and the
  /// roll/pitch angular acceleration of losing it [rad/s^2] (the smallest over the rotors).
  double hover_thrust_per_rotor_n() const { return hover_thrust_per_rotor_n_; }
  double one_rotor_angular_acceleration_rad_s2() const { return one_rotor_alpha_; }
  /// The indices' extremes over every evaluation before the first isolation: over a healthy
  /// flight, what the thresholds must clear (fdd-calibrate, docs/fdd.md).
  const IndexExtremes& healthy_extremes() const { return extremes_; }

 private:
  /// The latest (time, value) samples of an index in a ring fixed at construction (nothing is
  /// allocated in flight); when full, a new sample drops the oldest.
  class SampleRing {
   public:
    explicit SampleRing(std::size_t capacity = 1) : t_(capacity), v_(capacity) {}
    void Clear() { size_ = 0; }
    void Push(double t, double v);
    void PopFront();
    std::size_t size() const { return size_; }
    double time(std::size_t k) const { return t_[(head_ + k) % t_.size()]; }
    double value(std::size_t k) const { return v_[(head_ + k) % v_.size()]; }
    double Min() const;
    double Max() const;
    /// Pushes (t, v), keeps the samples spanning the last `span` seconds, and returns the smallest
    /// value held over the whole span (the value a persistence rule compares), or nullopt while
    /// the samples span less.
    std::optional<double> HeldOver(double t, double v, double span);
    /// Pushes (t, v) as HeldOver does and returns the lower median of the samples spanning the
    /// last `span` seconds (it exceeds a threshold when a strict majority of them do), or nullopt
    /// while the samples span less. `scratch` holds a copy (reserved by the caller: no allocation).
    std::optional<double> MedianOver(double t, double v, double span, std::vector<double>* scratch);

   private:
    /// Pushes (t, v) and drops the samples older than needed to span `span` seconds; true when
    /// the samples left span it.
    bool PushSpanning(double t, double v, double span);
    std::vector<double> t_, v_;
    std::size_t head_ = 0, size_ = 0;  // the oldest sample, and how many
  };

  void RunObserver(double t, double dt);
  /// The motor shortfall rule on the telemetry at t (measured_thrust_ and expected_thrust_ set).
  void CheckShortfall(TimeNs t);

  vehicle::VehicleParams vehicle_;
  CompositeFddOptions options_;
  int n_;
  EffectivenessMatrix effectiveness_;
  AllocationMatrix pinv_;
  // Motor index: the motors as commanded (the expected thrusts), against their telemetry.
  CommandedMotors motors_;
  RotorVector expected_thrust_;
  RpmNotchBank<4> wrench_notch_;  // the telemetry's wrench, notched as the stack notches the IMU
  std::vector<int> low_index_count_;
  std::vector<double> low_index_since_s_;
  // Motor shortfall: the commands and the telemetry's thrusts of the last window and delay span,
  // each rotor's averages of measured and modelled thrust, and its debounce.
  RotorHistory commands_, measured_history_;
  RotorVector mean_measured_, mean_modelled_, lowest_command_;
  std::optional<TimeNs> last_esc_ns_;
  std::vector<int> shortfall_count_;
  std::vector<double> shortfall_since_s_;
  std::vector<SampleRing> recent_shortfall_;
  // For the rules' statistics (IndexExtremes): each rotor's last motor_index_samples M_i, and its
  // P_i over the last propeller_persistence_s.
  std::vector<SampleRing> recent_motor_index_, recent_propeller_index_;
  std::vector<double> median_scratch_;  // SampleRing::MedianOver's copy, reserved once
  RotorVector measured_thrust_;
  RotorVector working_;  // 1 for a rotor not isolated, else 0
  int isolated_seen_ = 0;
  std::optional<double> relearn_since_s_;
  bool have_esc_ = false;
  // Observer.
  std::optional<TimeNs> last_imu_ns_;
  LowPass2<3> force_filter_, rate_filter_;
  FilteredDerivative<3> alpha_filter_;
  LowPass2<4> wrench_filter_;
  std::optional<double> airborne_since_s_;
  std::optional<double> grounded_since_s_;  // on the ground (by the estimate and the contact test) since
  bool takeoff_armed_ = false;               // the current airborne phase began with a take-off
  bool been_airborne_ = false;               // an airborne phase came before
  bool been_above_takeoff_ = false;          // the estimate has been above takeoff_max_altitude_m
  std::vector<double> above_since_s_, degraded_since_s_, degraded_sum_;
  std::vector<int> degraded_count_;
  Eigen::VectorXd thrust_loss_;
  Eigen::Vector4d baseline_ = Eigen::Vector4d::Zero();  // the healthy residual wrench
  double takeoff_index_ = 0.0;
  double hover_thrust_per_rotor_n_ = 0.0, one_rotor_alpha_ = 0.0;
  std::vector<Eigen::Vector2d> loss_signature_;  // per rotor: eq. (18)'s direction of losing it
  IndexExtremes extremes_;
};

}  // namespace rotorguard::fdd
