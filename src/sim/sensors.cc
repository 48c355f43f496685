#include "rotorguard/sim/sensors.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/core/math.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::sim {

namespace {
void RequireRate(const char* owner, double rate_hz, double physics_rate_hz) {
  if (!std::isfinite(rate_hz) || rate_hz < kMinRateHz || rate_hz > physics_rate_hz) {
    ThrowValidation(owner, "rate_hz", rate_hz,
                    fmt::format("a rate in [{:g}, {}] Hz (the physics rate)", kMinRateHz, physics_rate_hz));
  }
}
void RequireNonNegative(const char* owner, const std::string& field, double v) {
  if (!std::isfinite(v) || v < 0.0) ThrowValidation(owner, field, v, "a finite value >= 0");
}
Vector3 NormalVector(Rng& rng, double stddev) {
  const double x = rng.Normal(), y = rng.Normal(), z = rng.Normal();
  return stddev * Vector3(x, y, z);
}
}  // namespace

void ImuOptions::Validate(double physics_rate_hz) const {
  CheckDeclaredRanges("ImuOptions", *this);
  RequireRate("ImuOptions", rate_hz, physics_rate_hz);
  RequireNonNegative("ImuOptions", "vibration_m_s2", vibration_m_s2);
  if (!(vibration_reference_speed_rad_s > 0.0)) {
    ThrowValidation("ImuOptions", "vibration_reference_speed_rad_s", vibration_reference_speed_rad_s, "a speed > 0");
  }
  RequireNonNegative("ImuOptions", "vibration_fault_factor", vibration_fault_factor);
  RequireNonNegative("ImuOptions", "axial_vibration_m_s2", axial_vibration_m_s2);
  RequireNonNegative("ImuOptions", "gyro_vibration_gain", gyro_vibration_gain);
  if (!(airframe_mass_kg > 0.0) || !std::isfinite(airframe_mass_kg)) {
    ThrowValidation("ImuOptions", "airframe_mass_kg", airframe_mass_kg, "a mass > 0 [kg]");
  }
  if (!airframe_inverse_inertia.allFinite()) {
    ThrowValidation("ImuOptions", "airframe_inverse_inertia", "(non-finite)", "a finite matrix");
  }
  for (std::size_t i = 0; i < rotor_positions_m.size(); ++i) {
    if (!rotor_positions_m[i].allFinite()) {
      ThrowValidation("ImuOptions", fmt::format("rotor_positions_m.{}", i), "(non-finite)", "a finite position [m]");
    }
  }
}

void EscOptions::Validate(double physics_rate_hz) const {
  CheckDeclaredRanges("EscOptions", *this);
  RequireRate("EscOptions", rate_hz, physics_rate_hz);
  for (std::size_t k = 0; k < gain.size(); ++k) {
    if (!(gain[k] > 0.0) || !std::isfinite(gain[k])) {
      ThrowValidation("EscOptions", fmt::format("gain.{}", k), gain[k], "a positive finite ratio");
    }
  }
  if (!(dropout_probability >= 0.0 && dropout_probability < 1.0)) {
    ThrowValidation("EscOptions", "dropout_probability", dropout_probability, "a probability in [0, 1)");
  }
  if (!(command_latency_s >= 0.0 && command_latency_s < 0.5)) {
    ThrowValidation("EscOptions", "command_latency_s", command_latency_s, "a latency in [0, 0.5) s");
  }
}

void OdometryOptions::Validate(double physics_rate_hz) const {
  CheckDeclaredRanges("OdometryOptions", *this);  // the outages' times too
  RequireRate("OdometryOptions", rate_hz, physics_rate_hz);
  if (!std::isfinite(latency_s) || latency_s < 0.0 || latency_s >= 0.5) {
    ThrowValidation("OdometryOptions", "latency_s", latency_s, "a value in [0, 0.5) s");
  }
  RequireNonNegative("OdometryOptions", "drift_m_per_sqrt_s", drift_m_per_sqrt_s);
  RequireNonNegative("OdometryOptions", "yaw_drift_rad_per_sqrt_s", yaw_drift_rad_per_sqrt_s);
  RequireNonNegative("OdometryOptions", "few_features_gain", few_features_gain);
  if (features_reference < 1)
    ThrowValidation("OdometryOptions", "features_reference", features_reference, "a count >= 1");
  RequireNonNegative("OdometryOptions", "feature_range_m", feature_range_m);
  RequireNonNegative("OdometryOptions", "outage_rate_hz", outage_rate_hz);
  RequireNonNegative("OdometryOptions", "outage_min_s", outage_min_s);
  if (!(outage_max_s >= outage_min_s) || !std::isfinite(outage_max_s)) {
    ThrowValidation("OdometryOptions", "outage_max_s", outage_max_s,
                    fmt::format("a time >= outage_min_s = {}", outage_min_s));
  }
}

bool OdometryOptions::InOutage(double t) const {
  for (const Outage& o : outages) {
    if (t >= o.start_s && t < o.start_s + o.duration_s) return true;
  }
  return false;
}

ImuModel::ImuModel(const ImuOptions& options, std::uint64_t seed)
    : options_(options), rng_(seed), dt_(1.0 / options.rate_hz) {
  accel_bias_ = NormalVector(rng_, options_.accel_bias_initial);
  gyro_bias_ = NormalVector(rng_, options_.gyro_bias_initial);
  vibrates_ = options_.vibration_m_s2 > 0.0 || options_.axial_vibration_m_s2 > 0.0;
}

ImuSample ImuModel::Sample(const TruthSample& truth) {
  const vehicle::StateView s(*truth.x);
  const Vector3 w = s.w_B();
  const Vector3& r = options_.position_m;
  // Specific force at the CoG, plus the tangential (alpha x r) and centripetal (w x (w x r))
  // accelerations of a point r away from it: a spinning vehicle's IMU feels them.
  const Vector3 f_cog_B = s.q_WB().conjugate() * (truth.acc.a_W + Vector3(0.0, 0.0, kGravity));
  const Vector3 f_B = f_cog_B + truth.acc.alpha_B.cross(r) + w.cross(w.cross(r));
  // Discrete white noise std = density / sqrt(dt); bias random walk std = rw * sqrt(dt).
  accel_bias_ += NormalVector(rng_, options_.accel_bias_random_walk * std::sqrt(dt_));
  gyro_bias_ += NormalVector(rng_, options_.gyro_bias_random_walk * std::sqrt(dt_));
  ImuSample out;
  out.t_ns = truth.t_ns;
  out.specific_force_B =
      f_B + accel_bias_ + NormalVector(rng_, options_.accel_noise_density / std::sqrt(dt_));
  out.w_B = w + gyro_bias_ + NormalVector(rng_, options_.gyro_noise_density / std::sqrt(dt_));
  if (vibrates_) AddVibration(truth, &out);
  // A MEMS sensor saturates: each axis reads at most its range.
  const double a = options_.accel_range_m_s2, g = options_.gyro_range_rad_s;
  out.specific_force_B = out.specific_force_B.cwiseMax(Vector3::Constant(-a)).cwiseMin(Vector3::Constant(a));
  out.w_B = out.w_B.cwiseMax(Vector3::Constant(-g)).cwiseMin(Vector3::Constant(g));
  return out;
}

void ImuModel::AddVibration(const TruthSample& truth, ImuSample* sample) {
  const RotorVector& speed = truth.motor_speed_rad_s;
  rotor_phase_.resize(static_cast<std::size_t>(speed.size()), 0.0);
  for (int i = 0; i < speed.size(); ++i) {
    double& phase = rotor_phase_[static_cast<std::size_t>(i)];
    // The phase advances by ω dt between samples: at the IMU's rate the rotor's frequency and its
    // harmonic alias, as they do on a sensor without an anti-aliasing filter.
    phase = std::fmod(phase + speed[i] * dt_, 2.0 * std::numbers::pi);
    const double ratio = speed[i] / options_.vibration_reference_speed_rad_s;
    double scale = ratio * ratio;  // a centrifugal force: the imbalance's grows with ω²
    if (truth.faults != nullptr && i < static_cast<int>(truth.faults->size())) {
      const vehicle::FaultKind kind = (*truth.faults)[static_cast<std::size_t>(i)].kind;
      if (kind == vehicle::FaultKind::kPropellerLoss || kind == vehicle::FaultKind::kLossOfEffectiveness) {
        scale *= options_.vibration_fault_factor;
      }
    }
    const double c1 = std::cos(phase), s1 = std::sin(phase), c2 = std::cos(2.0 * phase), s2 = std::sin(2.0 * phase);
    const double a = scale * options_.vibration_m_s2, b = scale * options_.axial_vibration_m_s2;
    sample->specific_force_B += Vector3(a * c1, a * s1, b * c2);
    // The same forces' moment about the centre of gravity rocks the airframe: angular
    // acceleration I⁻¹ (r x m f), whose rate oscillates as its integral over the force's period
    // (cos -> sin / Ω), read by the gyro; the accelerometer off the centre feels α x p.
    const double omega = speed[i];
    if (options_.gyro_vibration_gain > 0.0 && omega > 0.0 && i < static_cast<int>(options_.rotor_positions_m.size())) {
      const Vector3& r = options_.rotor_positions_m[static_cast<std::size_t>(i)];
      const Matrix3& I_inv = options_.airframe_inverse_inertia;
      const double k = options_.gyro_vibration_gain * options_.airframe_mass_kg;
      const Vector3 force(a * c1, a * s1, b * c2), force_integral(a * s1 / omega, -a * c1 / omega, b * s2 / (2.0 * omega));
      sample->w_B += k * (I_inv * r.cross(force_integral));
      sample->specific_force_B += (k * (I_inv * r.cross(force))).cross(options_.position_m);
    }
  }
}

EscModel::EscModel(const EscOptions& options, int num_rotors, std::uint64_t seed)
    : options_(options), rng_(seed), num_rotors_(num_rotors), delay_ns_(FromSeconds(options.delay_s)) {
  if (!options_.gain.empty() && static_cast<int>(options_.gain.size()) != num_rotors) {
    ThrowInvalidArgument("EscModel", "gain", fmt::format("{} entries", options_.gain.size()),
                         fmt::format("one per motor ({})", num_rotors));
  }
  // Enough slots for every sample in flight during the delay, plus margin.
  const auto slots = static_cast<std::size_t>(std::ceil(options.delay_s * options.rate_hz)) + 2;
  ring_.resize(slots);
  for (auto& m : ring_) m.motor_speed_rad_s.resize(num_rotors);
}

void EscModel::Measure(const TruthSample& truth) {
  // A lost frame never arrives (drawn only when frames can be lost: no other noise moves).
  if (options_.dropout_probability > 0.0 && rng_.Uniform() < options_.dropout_probability) return;
  if (count_ == ring_.size()) {  // full: drop the oldest (cannot happen with the sizing above)
    head_ = (head_ + 1) % ring_.size();
    --count_;
  }
  EscTelemetry& m = ring_[(head_ + count_) % ring_.size()];
  m.t_ns = truth.t_ns;
  for (int i = 0; i < num_rotors_; ++i) {
    const double gain = options_.gain.empty() ? 1.0 : options_.gain[static_cast<std::size_t>(i)];
    double rpm = vehicle::RadPerSecondToRpm(gain * truth.motor_speed_rad_s[i]) + options_.noise_rpm * rng_.Normal();
    if (options_.quantization_rpm > 0.0) {
      rpm = options_.quantization_rpm * std::round(rpm / options_.quantization_rpm);
    }
    m.motor_speed_rad_s[i] = vehicle::RpmToRadPerSecond(std::max(0.0, rpm));
  }
  ++count_;
}

bool EscModel::Deliver(TimeNs t, EscTelemetry* delivered) {
  // Deliver the newest sample whose delay has elapsed; older ones are superseded.
  bool found = false;
  while (count_ > 0 && ring_[head_].t_ns + delay_ns_ <= t) {
    *delivered = ring_[head_];
    head_ = (head_ + 1) % ring_.size();
    --count_;
    found = true;
  }
  return found;
}

namespace {
// The odometry model's streams beside its noise: drawing drift or outages never shifts the noise.
constexpr std::uint64_t kDriftStream = 1, kOutageStream = 2;
}  // namespace

OdometryModel::OdometryModel(const OdometryOptions& options, const World& world, std::uint64_t seed)
    : options_(options),
      world_(world),
      rng_(seed),
      drift_rng_(DeriveSeed(seed, kDriftStream)),
      outage_rng_(DeriveSeed(seed, kOutageStream)),
      dt_(1.0 / options.rate_hz),
      latency_ns_(FromSeconds(options.latency_s)) {}

double OdometryModel::FewFeaturesFactor(const Vector3& p_W, double t) const {
  if (options_.few_features_gain <= 0.0) return 1.0;
  // Obstacles within range are the structure a LiDAR front end registers its scans against; the
  // ground alone leaves the horizontal position and the yaw unobserved.
  int n = 0;
  const double range = options_.feature_range_m;
  for (const Box& b : world_.boxes) n += b.Distance(p_W) < range;
  for (const Cylinder& c : world_.cylinders) n += c.Distance(p_W) < range;
  for (const MovingBox& m : world_.moving_boxes) n += m.At(t).Distance(p_W) < range;
  const double missing = 1.0 - std::min(1.0, static_cast<double>(n) / options_.features_reference);
  return 1.0 + options_.few_features_gain * missing;
}

bool OdometryModel::InOutage(TimeNs t_ns) {
  if (options_.InOutage(ToSeconds(t_ns))) return true;
  if (options_.outage_rate_hz <= 0.0) return false;
  if (t_ns < random_outage_end_ns_) return true;
  // A Poisson process sampled once per odometry period: P(an outage starts) = 1 - exp(-rate dt).
  if (outage_rng_.Uniform(0.0, 1.0) < 1.0 - std::exp(-options_.outage_rate_hz * dt_)) {
    random_outage_end_ns_ = t_ns + FromSeconds(outage_rng_.Uniform(options_.outage_min_s, options_.outage_max_s));
    return true;
  }
  return false;
}

void OdometryModel::Measure(const TruthSample& truth) {
  const vehicle::StateView s(*truth.x);
  const double t = ToSeconds(truth.t_ns);
  const double scale = (1.0 + options_.rate_noise_gain * s.w_B().norm()) * FewFeaturesFactor(s.p_W(), t);
  OdometrySample out;
  out.t_ns = truth.t_ns;
  // The pose of the file's body frame, o = body_origin_m from the centre of gravity: p + R o, and
  // its velocity v + R (w x o).
  const Matrix3 R = s.q_WB().toRotationMatrix();
  const Vector3& o = options_.body_origin_m;
  out.p_W = s.p_W() + R * o + NormalVector(rng_, options_.position_noise_m * scale);
  out.v_W = s.v_W() + R * s.w_B().cross(o) + NormalVector(rng_, options_.velocity_noise_m_s * scale);
  const Vector3 dtheta = NormalVector(rng_, options_.attitude_noise_rad * scale);
  const double angle = dtheta.norm();
  const Quaternion dq = angle > 0.0 ? Quaternion(Eigen::AngleAxisd(angle, dtheta / angle))
                                    : Quaternion::Identity();
  out.q_WB = (s.q_WB() * dq).normalized();
  if (options_.drift_m_per_sqrt_s > 0.0 || options_.yaw_drift_rad_per_sqrt_s > 0.0) {
    // The front end's frame wanders from the world's (a random walk in position and yaw): what it
    // reports is the truth seen in that frame, p' = R_z(ψ_d) p + d, v' = R_z(ψ_d) v.
    const double root_dt = std::sqrt(dt_) * scale;
    drift_p_ += NormalVector(drift_rng_, options_.drift_m_per_sqrt_s * root_dt);
    drift_yaw_ += options_.yaw_drift_rad_per_sqrt_s * root_dt * drift_rng_.Normal();
    const Quaternion r(Eigen::AngleAxisd(drift_yaw_, Vector3::UnitZ()));
    out.p_W = r * out.p_W + drift_p_;
    out.v_W = r * out.v_W;
    out.q_WB = (r * out.q_WB).normalized();
  }
  pending_.push_back(out);
}

bool OdometryModel::Deliver(TimeNs t, OdometrySample* delivered) {
  if (pending_.empty() || pending_.front().t_ns + latency_ns_ > t) return false;
  *delivered = pending_.front();
  pending_.pop_front();
  return true;
}

}  // namespace rotorguard::sim
