#pragma once
/// State estimators of the flight stack. They see sensor messages only.
#include <memory>
#include <optional>
#include <span>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/core/ring_buffer.h"
#include "rotorguard/perception/lio.h"

namespace rotorguard::stack {

class Estimator {
 public:
  virtual ~Estimator() = default;
  virtual void OnImu(const ImuSample& imu) = 0;
  /// External odometry (motion capture, or a LiDAR-inertial odometry outside the stack).
  virtual void OnOdometry(const OdometrySample& odometry) = 0;
  virtual void OnLidar(const LidarFrame& /*frame*/) {}
  void OnEscTelemetry(const EscTelemetry& esc);
  /// The newest estimate, for a consumer at time t (valid once enough data arrived). It is not
  /// extrapolated to t: the stack asks right after the IMU sample that brought it. t decides
  /// which of the estimator's sources is stale (the external odometry's dead reckoning).
  virtual StateEstimate Estimate(TimeNs t) const = 0;
  /// The estimate the LiDAR mapper places `frame` with: at the frame's end.
  virtual StateEstimate FrameEstimate(const LidarFrame& frame) const { return Estimate(frame.t_end_ns); }
  /// Seconds since the last pose fix at time t (an odometry sample, a LiDAR frame registered);
  /// the supervisor lands when it grows too old.
  virtual double odometry_age_s(TimeNs t) const = 0;

 protected:
  /// k_n with motor speed in rad/s (> 0).
  explicit Estimator(double thrust_coefficient_n_s2) : thrust_coefficient_(thrust_coefficient_n_s2) {}
  /// Thrust each motor drives [N], from the latest ESC telemetry through T = k_n ω² (paper 000,
  /// Sec. III-B); empty before any.
  const RotorVector& motor_thrust() const { return motor_thrust_; }

 private:
  double thrust_coefficient_;
  RotorVector motor_thrust_;
};

/// Where the stack's pose comes from (docs/navigation.md).
enum class EstimatorKind {
  kOdometry,  ///< external odometry samples, carried to the present by the IMU (OdometryImuEstimator)
  kLio,       ///< the stack's own LiDAR-inertial odometry (LioEstimator)
};
inline constexpr EnumName<EstimatorKind> kEstimatorKindNames[] = {{EstimatorKind::kOdometry, "odometry"},
                                                                  {EstimatorKind::kLio, "lio"}};
constexpr std::span<const EnumName<EstimatorKind>> NamesOf(const EstimatorKind*) { return kEstimatorKindNames; }

struct EstimatorOptions {
  EstimatorKind kind = EstimatorKind::kOdometry;
  /// The IMU's mounting point relative to the centre of gravity, body frame [m]: the centripetal
  /// acceleration it feels while the vehicle spins is removed before dead-reckoning.
  Vector3 imu_position_m = Vector3::Zero();
  /// Odometry older than this [s] is carried forward by integrating the IMU, > 0.
  double dead_reckoning_after_s = 0.05;
  /// IMU samples kept to carry a late odometry sample from its capture to its arrival [s], > 0:
  /// longer than the odometry's latency.
  double imu_history_s = 0.25;
  /// The LiDAR-inertial odometry (kind lio); its mounts are set from the sensors.
  perception::LioOptions lio;
  /// Throws ValidationError naming the field.
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("kind", &kind,
             {.meaning = "odometry (external, e.g. motion capture) or lio (the stack's own LiDAR-inertial odometry)"});
    a->Visit("lio", &lio, {.meaning = "the LiDAR-inertial odometry (docs/navigation.md)"});
  }
};

/// Pose and velocity from the latest odometry (assumed to be LiDAR-inertial odometry's output),
/// body rates from the latest gyro sample, motor thrusts from ESC telemetry through k_n. Odometry
/// arrives late, stamped when its scan was captured: on arrival it is carried to the newest IMU
/// sample by integrating the IMU samples since its capture (kept for imu_history_s). When the
/// odometry stops (its front end lost track), the last odometry is carried forward by strapdown
/// integration of the IMU: attitude by the gyro, velocity and position by the specific force
/// rotated to the world with gravity added (the IMU's lever arm removed), never below the ground
/// (z = 0). The estimate stays usable for the seconds an emergency landing takes (it drifts with
/// the accelerometer's bias and the gyro's, docs/navigation.md); `odometry_age_s` tells the
/// supervisor.
class OdometryImuEstimator final : public Estimator {
 public:
  /// `thrust_coefficient_n_s2`: k_n with motor speed in rad/s (> 0).
  OdometryImuEstimator(double thrust_coefficient_n_s2, const EstimatorOptions& options = {});
  void OnImu(const ImuSample& imu) override;
  void OnOdometry(const OdometrySample& odometry) override;
  StateEstimate Estimate(TimeNs t) const override;
  /// Seconds since the last odometry at time t (infinity before the first).
  double odometry_age_s(TimeNs t) const override;

 private:
  /// A strapdown state: pose and velocity at an instant.
  struct Strapdown {
    TimeNs t_ns = 0;
    Vector3 p = Vector3::Zero(), v = Vector3::Zero();
    Quaternion q = Quaternion::Identity();
  };
  /// Carries `s` to the instant of `imu` (a later one).
  void Integrate(const ImuSample& imu, Strapdown* s) const;

  EstimatorOptions options_;
  bool have_odometry_ = false;
  bool have_imu_ = false;
  OdometrySample odometry_;
  Vector3 w_B_ = Vector3::Zero();
  TimeNs imu_history_ns_ = 0;          ///< options_.imu_history_s
  RingBuffer<ImuSample> imu_history_;  ///< the last imu_history_s of valid samples, oldest first
  Strapdown arrived_;                  ///< the latest odometry carried to its arrival
  Strapdown dead_reckoned_;            ///< restarted at every odometry sample, then integrated
};

/// How the LiDAR-inertial odometry fared over a flight (summary.json "odometry").
struct LioSummary {
  int frames = 0;             ///< frames received
  int frames_used = 0;        ///< registered (the first one starts the map and is not)
  int frames_degenerate = 0;  ///< registered with a direction left unconstrained
  double points_mean = 0.0;   ///< down-sampled points per registered frame
  double matched_mean = 0.0;  ///< of those, matched to a plane
  double residual_rms_m_mean = 0.0;
  double iterations_mean = 0.0;
  /// Wall-clock time per frame, registration and map update [ms] (the filter's IMU propagation,
  /// at every sample, is not in it).
  double frame_ms_mean = 0.0, frame_ms_p99 = 0.0;
  long map_points = 0;  ///< at the end
  /// The LiDAR's calibration the odometry learnt, at the end: its axes' rotation from the IMU's
  /// (rotation vector) [rad] and its clock's offset [s].
  Vector3 lidar_rotation_rad = Vector3::Zero();
  double lidar_time_offset_s = 0.0;
  /// The threshold the frames were judged degenerate by (LioOptions::degenerate_std_m), for
  /// whoever reads their weakest-direction stds (the log's lio_weakest_std_m).
  double degenerate_std_m = 0.0;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("frames", &frames);
    a->Visit("frames_used", &frames_used);
    a->Visit("frames_degenerate", &frames_degenerate);
    a->Visit("points_mean", &points_mean);
    a->Visit("matched_mean", &matched_mean);
    a->Visit("residual_rms_m_mean", &residual_rms_m_mean);
    a->Visit("iterations_mean", &iterations_mean);
    a->Visit("frame_ms_mean", &frame_ms_mean);
    a->Visit("frame_ms_p99", &frame_ms_p99);
    a->Visit("map_points", &map_points);
    a->Visit("lidar_rotation_rad", &lidar_rotation_rad);
    a->Visit("lidar_time_offset_s", &lidar_time_offset_s);
    a->Visit("degenerate_std_m", &degenerate_std_m);
  }
};

/// What the LiDAR-inertial odometry's frames tell the estimate the controller reads: the filter's
/// newest posterior (perception::LioPosterior) and its last fix.
struct LioUpdate {
  perception::LioPosterior posterior;
  std::optional<TimeNs> last_fix_ns;  ///< a frame used without an unconstrained direction, or the start
};

/// The stack's own LiDAR-inertial odometry (perception::Lio) from its IMU and LiDAR frames; an
/// external odometry sample is ignored. The world frame is the start pose's (the mission's
/// start, where the vehicle rests when the stack starts). A frame counts as a fix when the filter
/// used it and it left no direction unconstrained; without fixes for the supervisor's timeout
/// the IMU alone has carried the estimate too long and the vehicle lands.
class LioEstimator final : public Estimator {
 public:
  LioEstimator(double thrust_coefficient_n_s2, const EstimatorOptions& options, const Vector3& start_position_W,
               double start_yaw_rad);
  void OnImu(const ImuSample& imu) override;
  void OnOdometry(const OdometrySample& /*odometry*/) override {}
  void OnLidar(const LidarFrame& frame) override;
  StateEstimate Estimate(TimeNs t) const override;
  StateEstimate FrameEstimate(const LidarFrame& frame) const override;
  double odometry_age_s(TimeNs t) const override;
  /// Every frame's health, in order.
  const std::vector<perception::LioFrameSummary>& frames() const { return frames_; }
  const perception::Lio& lio() const { return lio_; }
  /// Its newest posterior and fix, for a LioHeadEstimator (a new serial after each frame used).
  LioUpdate update() const { return {lio_.posterior(), last_fix_ns_}; }
  LioSummary Summarize() const;

 private:
  perception::Lio lio_;
  std::vector<double> frame_ms_;       ///< wall-clock time of each frame
  std::optional<TimeNs> last_fix_ns_;  ///< the last frame used and not degenerate (or the start)
  std::vector<perception::LioFrameSummary> frames_;
  StateEstimate frame_estimate_;  ///< at the last frame's end
};

/// The estimate the controller reads when the stack localises on its own LiDAR-inertial odometry:
/// the odometry's head kept on the controller's side (perception::LioHeadFollower) from the IMU
/// samples and the odometry's updates, so that the frames may be registered elsewhere (the
/// perception task, on its own thread onboard: docs/runtime.md). Given each update as soon as it
/// is made, its estimate is the odometry's own, to the bit (FlightStack does so in lockstep).
class LioHeadEstimator final : public Estimator {
 public:
  /// `imu_position_m`: the IMU's mount from the centre of gravity, as the odometry's options say.
  LioHeadEstimator(double thrust_coefficient_n_s2, const Vector3& imu_position_m)
      : Estimator(thrust_coefficient_n_s2), imu_position_m_(imu_position_m) {}
  void OnImu(const ImuSample& imu) override { follower_.OnImu(imu); }
  void OnOdometry(const OdometrySample& /*odometry*/) override {}
  /// An update of the odometry (an older serial than the last one taken is ignored).
  void OnLioUpdate(const LioUpdate& update);
  /// The serial of the last update taken (0: none).
  std::uint64_t serial() const { return serial_; }
  StateEstimate Estimate(TimeNs t) const override;
  double odometry_age_s(TimeNs t) const override;

 private:
  perception::LioHeadFollower follower_;
  Vector3 imu_position_m_;
  std::uint64_t serial_ = 0;
  std::optional<TimeNs> last_fix_ns_;
};

/// The estimator the controller reads for `options.kind`: the external odometry carried by the
/// IMU, or the LiDAR-inertial odometry's head (LioHeadEstimator, whose frames the PerceptionTask
/// registers).
std::unique_ptr<Estimator> MakeControlEstimator(double thrust_coefficient_n_s2, const EstimatorOptions& options);

}  // namespace rotorguard::stack
