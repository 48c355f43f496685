#include "rotorguard/fdd/composite_fdd.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::fdd {

namespace {
// The shortfall rule's rings: commands (a 64-cycle span covers the window and the delay span at
// control rates up to 2 kHz), and telemetry thrusts kept at least an eighth of the window apart,
// so that 16 span more than the window at any telemetry rate.
constexpr int kShortfallCommands = 64;
constexpr int kShortfallSamples = 16;

void RequireIn(const char* field, double v, double lo, double hi, const char* rule) {
  if (!std::isfinite(v) || v < lo || v > hi) ThrowValidation("CompositeFddOptions", field, v, rule);
}
}  // namespace

bool IsIsolated(RotorHealth health) {
  return health == RotorHealth::kMotorFailed || health == RotorHealth::kPropellerFailed ||
         health == RotorHealth::kFailed;
}

void CompositeFddOptions::Validate() const {
  CheckDeclaredRanges("CompositeFddOptions", *this);
  // Rules beyond the declared ranges: their open ends kept a hair inside, and the rules between keys.
  RequireIn("motor_index_threshold", motor_index_threshold, 1e-6, 1.0 - 1e-6, "a value in (0, 1)");
  RequireIn("min_thrust_fraction", min_thrust_fraction, 1e-6, 1.0, "a fraction in (0, 1]");
  RequireIn("propeller_index_threshold", propeller_index_threshold, 1e-6, 1.0, "a value in (0, 1]");
  RequireIn("degraded_threshold", degraded_threshold, 1e-6, propeller_index_threshold - 1e-6,
            "a value in (0, propeller_index_threshold)");
  RequireIn("imu_rate_hz", imu_rate_hz, 1.0, 1e5, "a rate in [1, 1e5] Hz");
  RequireIn("filter_cutoff_hz", filter_cutoff_hz, 1e-3, 0.5 * imu_rate_hz - 1e-6, "a cut-off below half imu_rate_hz");
  RequireIn("takeoff_direction_cosine", takeoff_direction_cosine, 1e-6, 1.0, "a value in (0, 1]");
  if (!imu_position_m.allFinite()) ThrowValidation("CompositeFddOptions", "imu_position_m", "(non-finite)", "finite");
  RequireIn("command_delay_s", command_delay_s, 0.0, 0.5, "a delay in [0, 0.5] s");
}

CompositeFddOptions CompositeFddOptions::Disarmed() const {
  CompositeFddOptions o = *this;
  o.motor_index_threshold = 1e-6;
  o.propeller_index_threshold = 1.0;
  o.takeoff_index_threshold = 1e6;
  o.motor_shortfall_threshold = 1.0;
  return o;
}

CompositeFdd::CompositeFdd(const vehicle::VehicleParams& vehicle, const CompositeFddOptions& options)
    : FaultDetectorBase(vehicle.num_rotors()),
      vehicle_((vehicle.Validate(), vehicle)),
      options_((options.Validate(), options)),
      n_(vehicle.num_rotors()),
      motors_(vehicle.num_rotors(), vehicle.motor_time_constant_s,
              options.command_delay_s + options.motor_index_delay_margin_s),
      wrench_notch_(vehicle.num_rotors(), options.imu_notch),
      commands_(vehicle.num_rotors(), kShortfallCommands),
      measured_history_(vehicle.num_rotors(), kShortfallSamples) {
  effectiveness_ = vehicle::ComputeEffectivenessMatrix(vehicle_.rotors);
  pinv_ = vehicle::PseudoInverse(effectiveness_);
  expected_thrust_ = RotorVector::Zero(n_);
  measured_thrust_ = RotorVector::Zero(n_);
  working_ = RotorVector::Ones(n_);
  low_index_count_.assign(n_, 0);
  low_index_since_s_.assign(n_, 0.0);
  mean_measured_ = mean_modelled_ = lowest_command_ = RotorVector::Zero(n_);
  shortfall_count_.assign(n_, 0);
  shortfall_since_s_.assign(n_, 0.0);
  recent_shortfall_.assign(n_, SampleRing(static_cast<std::size_t>(options_.motor_index_samples)));
  recent_motor_index_.assign(n_, SampleRing(static_cast<std::size_t>(options_.motor_index_samples)));
  // Twice the samples the persistence spans at the nominal IMU rate, for a faster or jittery IMU.
  const auto persistence_samples =
      static_cast<std::size_t>(std::ceil(2.0 * std::max(options_.propeller_persistence_s, options_.second_failure_persistence_s) *
                                         options_.imu_rate_hz) + 4.0);
  recent_propeller_index_.assign(n_, SampleRing(persistence_samples));
  median_scratch_.reserve(persistence_samples);
  above_since_s_.assign(n_, -1.0);
  degraded_since_s_.assign(n_, -1.0);
  degraded_sum_.assign(n_, 0.0);
  degraded_count_.assign(n_, 0);
  thrust_loss_ = Eigen::VectorXd::Zero(n_);
  force_filter_ = LowPass2<3>(options_.filter_cutoff_hz, options_.imu_rate_hz);
  rate_filter_ = LowPass2<3>(options_.filter_cutoff_hz, options_.imu_rate_hz);
  alpha_filter_ = FilteredDerivative<3>(options_.filter_cutoff_hz, options_.imu_rate_hz);
  wrench_filter_ = LowPass2<4>(options_.filter_cutoff_hz, options_.imu_rate_hz);
  // Eq. (18)'s signatures: the roll/pitch angular acceleration per newton rotor i loses,
  // -I^-1 (r_i x e3). The thresholds' units: a rotor's share of the hover thrust, and the angular
  // acceleration of losing it, the smallest over the rotors.
  hover_thrust_per_rotor_n_ = vehicle_.weight_n() / n_;
  one_rotor_alpha_ = std::numeric_limits<double>::infinity();
  const Matrix3 inverse_inertia = vehicle_.inertia_kg_m2.inverse();
  for (const vehicle::Rotor& r : vehicle_.rotors) {
    const Eigen::Vector2d signature = (inverse_inertia * Vector3(-r.p_B.y(), r.p_B.x(), 0.0)).head<2>();
    loss_signature_.push_back(signature.normalized());
    one_rotor_alpha_ = std::min(one_rotor_alpha_, hover_thrust_per_rotor_n_ * signature.norm());
  }
  if (!(one_rotor_alpha_ > 0.0) || !std::isfinite(one_rotor_alpha_)) {
    ThrowValidation("CompositeFdd", "vehicle.rotors", "(a rotor at the centre of gravity)",
                    "every rotor off the centre of gravity: losing it must turn the vehicle");
  }
}

void CompositeFdd::SampleRing::Push(double t, double v) {
  if (size_ == t_.size()) PopFront();
  const std::size_t k = (head_ + size_) % t_.size();
  t_[k] = t;
  v_[k] = v;
  ++size_;
}

void CompositeFdd::SampleRing::PopFront() {
  head_ = (head_ + 1) % t_.size();
  --size_;
}

double CompositeFdd::SampleRing::Min() const {
  double m = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < size_; ++k) m = std::min(m, v_[(head_ + k) % v_.size()]);
  return m;
}

double CompositeFdd::SampleRing::Max() const {
  double m = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < size_; ++k) m = std::max(m, v_[(head_ + k) % v_.size()]);
  return m;
}

bool CompositeFdd::SampleRing::PushSpanning(double t, double v, double span) {
  Push(t, v);
  while (size_ >= 2 && t - time(1) >= span) PopFront();
  return t - time(0) >= span;
}

std::optional<double> CompositeFdd::SampleRing::HeldOver(double t, double v, double span) {
  if (!PushSpanning(t, v, span)) return std::nullopt;
  return Min();
}

std::optional<double> CompositeFdd::SampleRing::MedianOver(double t, double v, double span, std::vector<double>* scratch) {
  if (!PushSpanning(t, v, span)) return std::nullopt;
  scratch->clear();
  for (std::size_t k = 0; k < size_; ++k) scratch->push_back(value(k));
  const auto middle = scratch->begin() + static_cast<std::ptrdiff_t>((size_ - 1) / 2);
  std::nth_element(scratch->begin(), middle, scratch->end());
  return *middle;
}

void IndexExtremes::Merge(const IndexExtremes& other) {
  min_motor_index = std::min(min_motor_index, other.min_motor_index);
  max_propeller_index = std::max(max_propeller_index, other.max_propeller_index);
  max_takeoff_index = std::max(max_takeoff_index, other.max_takeoff_index);
  debounced_motor_index = std::min(debounced_motor_index, other.debounced_motor_index);
  persistent_propeller_index = std::max(persistent_propeller_index, other.persistent_propeller_index);
  gated_takeoff_index = std::max(gated_takeoff_index, other.gated_takeoff_index);
  second_failure_index = std::max(second_failure_index, other.second_failure_index);
  debounced_motor_shortfall = std::max(debounced_motor_shortfall, other.debounced_motor_shortfall);
}

FaultDetectorBase::FaultDetectorBase(int num_rotors) : rotors_(static_cast<std::size_t>(num_rotors)) {}

std::vector<int> FaultDetectorBase::TakeNewIsolations() {
  std::vector<int> out;
  out.swap(new_isolations_);
  return out;
}

void FaultDetectorBase::Isolate(int rotor, RotorHealth health, double t, const char* detector,
                                std::optional<double> onset) {
  RotorStatus& r = rotors_[rotor];
  if (IsIsolated(r.health)) return;
  r.health = health;
  r.detected_s = t;
  r.onset_s = onset.value_or(t);
  r.detector = detector;
  if (health != RotorHealth::kDegraded) {
    r.eta = 1.0;
    new_isolations_.push_back(rotor);
    if (!first_isolated_) first_isolated_ = rotor;
  }
}

void FaultDetectorBase::SetEstimate(const StateEstimate& estimate) {
  if (!estimate.valid || !estimate.p_W.allFinite() || !estimate.v_W.allFinite() ||
      !estimate.q_WB.coeffs().allFinite()) {
    return;  // a corrupt estimate is ignored; the previous one stays
  }
  estimate_ = estimate;
  have_estimate_ = true;
}

void CompositeFdd::SetCommand(const RotorCommand& command) {
  motors_.OnCommand(command.t_ns, command.thrust_n);
  commands_.Push(command.t_ns, command.thrust_n);
}

void CompositeFdd::OnEscTelemetry(const EscTelemetry& esc) {
  if (esc.motor_speed_rad_s.size() != n_ || !esc.motor_speed_rad_s.allFinite()) return;
  wrench_notch_.OnRotorSpeeds(esc.t_ns, esc.motor_speed_rad_s);
  const double t = ToSeconds(esc.t_ns);
  const double kn = vehicle_.thrust_coefficient_n_s2;
  for (int i = 0; i < n_; ++i) measured_thrust_[i] = kn * esc.motor_speed_rad_s[i] * esc.motor_speed_rad_s[i];
  // Expected motor state: the commands, each from its instant plus the expected delay, through the
  // motor lag of eq. (6); the model starts where the motors are.
  if (!motors_.started()) motors_.Start(esc.t_ns, measured_thrust_);
  expected_thrust_ = motors_.AdvanceTo(esc.t_ns);
  for (int i = 0; i < n_; ++i) {
    if (expected_thrust_[i] < options_.min_thrust_fraction * hover_thrust_per_rotor_n_) {
      low_index_count_[i] = 0;
      recent_motor_index_[i].Clear();
      rotors_[i].motor_index = 1.0;
      continue;
    }
    // eq. (13): M_i = w_measured / w_expected.
    const double index = esc.motor_speed_rad_s[i] / std::sqrt(expected_thrust_[i] / kn);
    rotors_[i].motor_index = index;
    if (!first_isolated_) {
      // The rule below fires when motor_index_samples consecutive indices are all at or below
      // gamma_M, that is when their largest is.
      SampleRing& recent = recent_motor_index_[i];
      recent.Push(t, index);  // a ring of motor_index_samples: the oldest drops out
      extremes_.min_motor_index = std::min(extremes_.min_motor_index, index);
      if (static_cast<int>(recent.size()) == options_.motor_index_samples) {
        extremes_.debounced_motor_index = std::min(extremes_.debounced_motor_index, recent.Max());
      }
    }
    low_index_count_[i] = index <= options_.motor_index_threshold ? low_index_count_[i] + 1 : 0;
    if (low_index_count_[i] == 1) low_index_since_s_[i] = t;
    if (low_index_count_[i] >= options_.motor_index_samples) {
      Isolate(i, RotorHealth::kMotorFailed, t, "motor_index", low_index_since_s_[i]);
    }
  }
  CheckShortfall(esc.t_ns);
  have_esc_ = true;
}

void CompositeFdd::CheckShortfall(TimeNs t_ns) {
  const double t = ToSeconds(t_ns);
  const TimeNs window_ns = FromSeconds(options_.motor_shortfall_window_s);
  // Each rotor's measured-to-modelled ratio: the file's thrust coefficient and the ESC's gain are
  // not the vehicle's, and the commands the floor starts from are in the file's newtons.
  const double dt = last_esc_ns_ ? ToSeconds(t_ns - *last_esc_ns_) : 0.0;
  last_esc_ns_ = t_ns;
  const double blend = std::min(1.0, std::max(0.0, dt) / options_.motor_scale_time_constant_s);
  for (int i = 0; i < n_; ++i) {
    if (IsIsolated(rotors_[i].health)) continue;
    mean_measured_[i] += blend * (measured_thrust_[i] - mean_measured_[i]);
    mean_modelled_[i] += blend * (expected_thrust_[i] - mean_modelled_[i]);
  }
  // The telemetry a window ago: the latest sample kept at or before t - W, and its actual age.
  const std::optional<std::size_t> start = measured_history_.LatestAtOrBefore(t_ns - window_ns);
  const TimeNs delay_ns = FromSeconds(options_.command_delay_s + options_.motor_delay_span_s);
  const bool judged = start && commands_.LowestOver(measured_history_.time(*start) - delay_ns, t_ns, &lowest_command_);
  const double min_thrust = options_.min_thrust_fraction * hover_thrust_per_rotor_n_;
  for (int i = 0; i < n_ && judged; ++i) {
    if (IsIsolated(rotors_[i].health)) continue;
    const double ratio = mean_modelled_[i] > min_thrust ? mean_measured_[i] / mean_modelled_[i] : 1.0;
    const double command =
        std::clamp(lowest_command_[i], 0.0, vehicle_.rotors[i].max_thrust_n) * ratio * (1.0 - options_.motor_scale_margin);
    const double floor = HealthyThrustFloor(measured_history_.values(*start)[i], command,
                                            ToSeconds(t_ns - measured_history_.time(*start)),
                                            (1.0 - options_.motor_lag_fraction) * vehicle_.motor_time_constant_s);
    if (floor < min_thrust) {
      shortfall_count_[i] = 0;
      recent_shortfall_[i].Clear();
      continue;
    }
    const double shortfall = 1.0 - measured_thrust_[i] / floor;
    if (!first_isolated_) {
      SampleRing& recent = recent_shortfall_[i];
      recent.Push(t, shortfall);
      if (static_cast<int>(recent.size()) == options_.motor_index_samples) {
        extremes_.debounced_motor_shortfall = std::max(extremes_.debounced_motor_shortfall, recent.Min());
      }
    }
    shortfall_count_[i] = shortfall > options_.motor_shortfall_threshold ? shortfall_count_[i] + 1 : 0;
    if (shortfall_count_[i] == 1) shortfall_since_s_[i] = t;
    if (shortfall_count_[i] >= options_.motor_index_samples) {
      Isolate(i, RotorHealth::kMotorFailed, t, "motor_shortfall", shortfall_since_s_[i]);
    }
  }
  if (!judged) {  // the history does not reach back a window and the delay span yet
    std::fill(shortfall_count_.begin(), shortfall_count_.end(), 0);
    for (SampleRing& recent : recent_shortfall_) recent.Clear();
  }
  // Keep this sample when an eighth of the window has passed since the last one kept.
  if (measured_history_.empty() || t_ns - measured_history_.newest_time() >= window_ns / 8) {
    measured_history_.Push(t_ns, measured_thrust_);
  }
}

void CompositeFdd::OnImu(const ImuSample& imu) {
  if (!imu.specific_force_B.allFinite() || !imu.w_B.allFinite()) return;
  const double dt = last_imu_ns_ ? ToSeconds(imu.t_ns - *last_imu_ns_) : 1.0 / options_.imu_rate_hz;
  last_imu_ns_ = imu.t_ns;
  if (!have_esc_) return;
  force_filter_.Step(imu.specific_force_B);
  rate_filter_.Step(imu.w_B);
  alpha_filter_.Step(imu.w_B, dt);
  for (int i = 0; i < n_; ++i) working_[i] = IsIsolated(rotors_[i].health) ? 0.0 : 1.0;
  // An isolated rotor gives no thrust, whatever its motor's speed (a lost propeller spins freely).
  const Eigen::Vector4d wrench = wrench_notch_.Filter(effectiveness_ * measured_thrust_.cwiseProduct(working_));
  wrench_filter_.Step(wrench);
  RunObserver(ToSeconds(imu.t_ns), dt);
}

void CompositeFdd::RunObserver(double t, double dt) {
  // The observer's force balance holds once the ground no longer carries the vehicle: in the air,
  // or when the rotors (by their measured speeds) lift at least kLiftFraction of the weight. The
  // latter starts the take-off window at lift-off rather than at some altitude.
  constexpr double kLiftFraction = 0.9;
  // The ground in contact carries what the rotors do not: the rotors then lift less than the
  // weight (by kContactFraction of it) while the accelerometer reads that much more support than
  // they give, whatever the estimate's height says (a drifted estimate, a landing on a step). The
  // detector stays armed, and judges the air only. Both conditions: in the air a spinning vehicle's
  // force balance alone swings by a quarter of the weight (its thrust model errors at strongly
  // unequal rotor speeds), but its rotors then carry the weight.
  constexpr double kContactFraction = 0.25;
  const double support = vehicle_.mass_kg * force_filter_.value().z() - wrench_filter_.value()[0];
  const bool contact = support > kContactFraction * vehicle_.weight_n() &&
                       wrench_filter_.value()[0] < (1.0 - kContactFraction) * vehicle_.weight_n();
  // A touchdown: once the flight has risen above the take-off detector's altitude, coming back into
  // the ground band is a landing. The feet may touch anywhere in the band (the estimate's error is
  // centimetres and never goes below the ground), and a vehicle rocking on its legs turns as a lost
  // rotor would while the rotors, helped by the ground effect, still lift most of the weight: the
  // contact rule cannot see it. The motor index keeps watching; a rotor lost higher up has had the
  // whole fall to be seen. A take-off (whose estimate may cross the band's edge more than once)
  // climbs through the band with the observer and the take-off detector judging.
  constexpr double kGroundBandM = 0.05;
  const bool in_band = estimate_.p_W.z() <= kGroundBandM;
  if (have_estimate_ && estimate_.p_W.z() > options_.takeoff_max_altitude_m) been_above_takeoff_ = true;
  const bool touching_down = been_above_takeoff_ && in_band;
  const bool flying = have_estimate_ && !contact && !touching_down &&
                      (!in_band || wrench_filter_.value()[0] > kLiftFraction * vehicle_.weight_n());
  if (flying && !airborne_since_s_) {
    airborne_since_s_ = t;
    // A take-off is the flight's first lift-off (or its start in the air), or a lift-off from
    // rest: a touchdown's bounce leaves the ground for a moment and rocks the vehicle on its feet
    // as a lost rotor would turn it, so it does not open the take-off detector's window (the
    // observer judges it).
    takeoff_armed_ = !been_airborne_ || (grounded_since_s_ && t - *grounded_since_s_ >= options_.takeoff_rest_s);
    been_airborne_ = true;
  }
  if (flying) {
    grounded_since_s_.reset();
  } else {
    airborne_since_s_.reset();
    if (have_estimate_ && !grounded_since_s_) grounded_since_s_ = t;
  }
  takeoff_index_ = 0.0;
  if (!airborne_since_s_) {
    std::fill(above_since_s_.begin(), above_since_s_.end(), -1.0);
    for (SampleRing& recent : recent_propeller_index_) recent.Clear();
    return;
  }
  // After an isolation the observer keeps watching the rotors still working, for a second complete
  // loss: the isolated rotors leave its wrench and its allocation, and it learns the reconfigured
  // vehicle's residual (the spin's) afresh for post_isolation_relearn_s before it judges again.
  // Partial losses and the take-off detector are single-failure tools (paper 000): they stop.
  const int isolated = static_cast<int>(n_ - working_.sum());
  if (isolated != isolated_seen_) {
    isolated_seen_ = isolated;
    relearn_since_s_ = t;
    Eigen::MatrixXd working_effectiveness = effectiveness_ * working_.asDiagonal();
    pinv_ = working_effectiveness.completeOrthogonalDecomposition().pseudoInverse();
    std::fill(above_since_s_.begin(), above_since_s_.end(), -1.0);
    std::fill(degraded_since_s_.begin(), degraded_since_s_.end(), -1.0);
    for (SampleRing& recent : recent_propeller_index_) recent.Clear();
  }
  const vehicle::VehicleParams& vp = vehicle_;
  const Vector3& w = rate_filter_.value();
  const Vector3& alpha = alpha_filter_.value();
  const Vector3& r = options_.imu_position_m;
  // Specific force at the centre of gravity: remove the IMU's lever-arm accelerations.
  const Vector3 f_cog = force_filter_.value() - alpha.cross(r) - w.cross(w.cross(r));
  const Eigen::Vector4d& wrench = wrench_filter_.value();
  const Matrix3 R = estimate_.q_WB.normalized().toRotationMatrix();
  const Vector3 v_B = R.transpose() * estimate_.v_W;
  // eq. (14) along the thrust axis (body z): thrust the rotors should give minus what the
  // accelerometer sees (drag included). Signed, where the paper takes the norm.
  const double force_loss = wrench[0] - (vp.mass_kg * f_cog.z() + vp.rotor_drag_kg_s.z() * v_B.z());
  // eq. (15): torque the rotors should give minus what the body's rotation shows.
  const Matrix3& I = vp.inertia_kg_m2;
  const Vector3 torque_loss = wrench.tail<3>() - I * alpha - w.cross(I * w) -
                              Vector3(0.0, 0.0, vp.yaw_damping_n_m_s * w.z());
  // eq. (16): per-rotor losses, counted from the healthy residual learnt so far.
  Eigen::Vector4d residual;
  residual << force_loss, torque_loss;
  const Eigen::Vector4d lost = residual - baseline_;
  thrust_loss_ = pinv_ * lost;

  // Take-off detector (eq. 18): a strong roll/pitch angular acceleration shortly after lift-off,
  // pointing like the loss of one rotor's thrust: alpha ~ -I^-1 (r_i x T e3).
  const bool takeoff = isolated == 0 && takeoff_armed_ && t - *airborne_since_s_ <= options_.takeoff_window_s &&
                       estimate_.p_W.z() <= options_.takeoff_max_altitude_m;
  if (takeoff) {
    takeoff_index_ = alpha.head<2>().norm() / one_rotor_alpha_;
    int best = -1;
    double best_cos = options_.takeoff_direction_cosine;
    for (int i = 0; i < n_; ++i) {
      const double c = loss_signature_[static_cast<std::size_t>(i)].dot(alpha.head<2>().normalized());
      if (c > best_cos) {
        best_cos = c;
        best = i;
      }
    }
    // The rotor it points at must miss thrust: by telemetry, or by the force balance. Which of
    // the two sees it tells the kind: a slowing motor's loss shows in its telemetry (and so not in
    // the force balance, which counts measured thrusts); a lost propeller's only in the balance.
    const double by_telemetry = best >= 0 ? expected_thrust_[best] - measured_thrust_[best] : 0.0;
    const bool gates_hold = best >= 0 && std::max(by_telemetry, lost[0]) >=
                                             options_.takeoff_missing_thrust_fraction * expected_thrust_[best];
    if (gates_hold) extremes_.gated_takeoff_index = std::max(extremes_.gated_takeoff_index, takeoff_index_);
    extremes_.max_takeoff_index = std::max(extremes_.max_takeoff_index, takeoff_index_);
    if (gates_hold && takeoff_index_ > options_.takeoff_index_threshold) {
      Isolate(best, by_telemetry > lost[0] ? RotorHealth::kMotorFailed : RotorHealth::kPropellerFailed, t, "takeoff");
    }
  }

  const bool learning = t - *airborne_since_s_ < 3.0 * options_.baseline_time_constant_s ||
                        (relearn_since_s_ && t - *relearn_since_s_ < options_.post_isolation_relearn_s);
  // eq. (17): P_i = lost thrust / thrust the rotor should give; persistent -> propeller failure.
  const double min_thrust = options_.min_thrust_fraction * hover_thrust_per_rotor_n_;
  for (int i = 0; i < n_; ++i) {
    const double p = measured_thrust_[i] > min_thrust ? thrust_loss_[i] / measured_thrust_[i] : 0.0;
    rotors_[i].propeller_index = p;
    if (isolated == 0) {
      extremes_.max_propeller_index = std::max(extremes_.max_propeller_index, p);
      // The rule below fires once P_i has stayed above gamma_P from a sample at least
      // propeller_persistence_s old to now, that is when the smallest P_i over that span does.
      if (const auto held = recent_propeller_index_[i].HeldOver(t, p, options_.propeller_persistence_s)) {
        extremes_.persistent_propeller_index = std::max(extremes_.persistent_propeller_index, *held);
      }
    }
    if (working_[i] == 0.0) continue;  // isolated already
    if (learning && isolated > 0) continue;
    // After an isolation the spinning vehicle's torque residual (inertia errors times the spin)
    // can point at a rotor; a lost propeller also costs thrust, which the force balance sees
    // whatever the inertia: at least a fraction of the rotor's thrust, and of the loss the
    // observer puts on it (a rotor the controller has turned nearly off has a large index for a
    // torque residual the force balance does not show).
    const bool costs_thrust =
        isolated == 0 ||
        (lost[0] >= options_.second_failure_missing_thrust_fraction * std::max(measured_thrust_[i], thrust_loss_[i]) &&
         measured_thrust_[i] >= options_.second_failure_min_thrust_fraction * hover_thrust_per_rotor_n_);
    // The rotor the observer blames must be the one losing the most thrust in newtons: P_i divides
    // by the rotor's own thrust, and the rotors beside a lost one, which the controller turns down
    // to hold the attitude, have the smallest; a torque residual's error (the vibration's, the
    // filters' lag) then reads as a large index on one of them (docs/fdd.md).
    bool largest_loss = true;
    for (int j = 0; j < n_; ++j) largest_loss = largest_loss && (j == i || working_[j] == 0.0 || thrust_loss_[j] <= thrust_loss_[i]);
    if (isolated > 0) {
      // A second failure: the lower median of the gated P_i over the persistence exceeds gamma_P.
      SampleRing& recent = recent_propeller_index_[i];
      const auto median = recent.MedianOver(t, costs_thrust && largest_loss ? p : 0.0,
                                            options_.second_failure_persistence_s, &median_scratch_);
      if (median) {
        extremes_.second_failure_index = std::max(extremes_.second_failure_index, *median);
        if (*median > options_.propeller_index_threshold) {
          std::size_t first = 0;  // the onset: the window's first sample over gamma_P
          while (recent.value(first) <= options_.propeller_index_threshold) ++first;
          Isolate(i, RotorHealth::kPropellerFailed, t, "thrust_loss_observer", recent.time(first));
        }
      }
    } else if (p > options_.propeller_index_threshold && costs_thrust && largest_loss) {
      if (above_since_s_[i] < 0.0) above_since_s_[i] = t;
      if (t - above_since_s_[i] >= options_.propeller_persistence_s) {
        Isolate(i, RotorHealth::kPropellerFailed, t, "thrust_loss_observer", above_since_s_[i]);
      }
    } else {
      above_since_s_[i] = -1.0;
    }
    // Partial loss: a persistent intermediate index, reported with its mean as eta.
    if (!learning && isolated == 0 && p > options_.degraded_threshold && p <= options_.propeller_index_threshold) {
      if (degraded_since_s_[i] < 0.0) {
        degraded_since_s_[i] = t;
        degraded_sum_[i] = 0.0;
        degraded_count_[i] = 0;
      }
      degraded_sum_[i] += p;
      ++degraded_count_[i];
      if (t - degraded_since_s_[i] >= options_.degraded_persistence_s && rotors_[i].health == RotorHealth::kOk) {
        Isolate(i, RotorHealth::kDegraded, t, "thrust_loss_observer", degraded_since_s_[i]);
        rotors_[i].eta = degraded_sum_[i] / degraded_count_[i];
      } else if (rotors_[i].health == RotorHealth::kDegraded) {
        rotors_[i].eta = degraded_sum_[i] / degraded_count_[i];
      }
    } else {
      degraded_since_s_[i] = -1.0;
    }
  }
  // The healthy residual: learnt while nothing looks wrong, frozen from the first suspicion on, so
  // that a fault is measured against the vehicle as it flew before it.
  // For its first three time constants in the air it learns regardless (the file's errors are
  // all there is to see), and no partial loss is diagnosed then.
  bool quiet = true;
  for (int i = 0; i < n_; ++i) {
    const RotorStatus& status = rotors_[i];
    if (working_[i] > 0.0 &&
        (status.health != RotorHealth::kOk || std::abs(status.propeller_index) > options_.degraded_threshold)) {
      quiet = false;
    }
  }
  if (options_.baseline_time_constant_s > 0.0 && (quiet || learning) && dt > 0.0) {
    baseline_ += std::min(1.0, dt / options_.baseline_time_constant_s) * (residual - baseline_);
  }
}

}  // namespace rotorguard::fdd
