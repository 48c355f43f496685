#pragma once
/// LiDAR-inertial odometry: the stack's own pose from its LiDAR frames and IMU samples, after
/// FAST-LIO2 (Xu et al., T-RO 2022), which paper 000's vehicle flies on.
///
/// An iterated error-state Kalman filter on the state of the IMU's mounting point and the LiDAR's
/// calibration
///   x = (p, R, v, b_g, b_a, R_IL, t_d)   position, attitude (body to world), velocity, gyro and
///   accelerometer biases, the LiDAR's axes in the IMU's and the LiDAR clock's offset (its stamps
///   minus the capture times),
/// error state δx = (δp, δθ, δv, δb_g, δb_a, δφ, δt_d) with R = R̂ Exp(δθ), R_IL = R̂_IL Exp(δφ)
/// (19 dimensions). A LiDAR is never mounted exactly as drawn nor its clock exactly the IMU's:
/// FAST-LIO2 estimates the extrinsic rotation online the same way, and LI-Init the time offset; at
/// 11 rad/s a 2 ms offset turns a frame by 1.3°.
/// - Propagation at every IMU sample (the mean of two consecutive samples held over their interval):
///     ω = ω_m − b_g,  a = R (f_m − b_a) + g,  p ← p + v dt + ½ a dt²,  v ← v + a dt,  R ← R Exp(ω dt),
///   and P ← F P Fᵀ + Q with the IMU's noise densities (FAST-LIO2 eqs. 2-8).
/// - Every LiDAR point s, captured at its stamp minus t_d, is moved to the IMU frame at its frame's
///   end, q = R_eᵀ (R_j (l + R_IL s) + p_j − p_e), through the poses the propagation passed
///   (backward propagation, FAST-LIO2 Sec. IV-C), the frame down-sampled on a voxel grid, then
///   registered to the map: each point's five nearest map points define a plane (n, d) and the
///   residual is n·(p + R q) + d (point to plane), q linear in δφ and δt_d about the deskewing's.
/// - The update is iterated (FAST-LIO2 eq. 18, a Gauss-Newton on the MAP cost): at the k-th
///   iterate x_k with e_k = x_k ⊟ x̂,
///     (P⁻¹ + Hᵀ R⁻¹ H) δ = −P⁻¹ e_k − Hᵀ R⁻¹ r_k,   x_{k+1} = x_k ⊞ δ,
///   the neighbours searched again at each iterate, until |δ| is small; then P ← (P⁻¹ + Hᵀ R⁻¹ H)⁻¹.
///   Directions the frame does not constrain (a corridor, open ground) keep the prior there, so
///   the estimate rests on the IMU along them while its covariance grows.
/// - The registered points go into the map (PointMap), which follows the vehicle.
///
/// The world frame is the one the stack starts in: its z axis is up (gravity (0, 0, −g), g known),
/// its origin and yaw the start pose's. So gravity is not a state (FAST-LIO2 estimates its
/// direction because its world frame is the first IMU frame). On the ground the tilt and the gyro
/// bias are measured over the first samples (Initialise), and the filter re-runs from the first
/// sample; in the air the start is level and the filter learns the bias. The first frames
/// (seed_frames) are placed with the IMU's pose: the map starts without registering to itself.
///
/// Timing: LiDAR frames arrive after their end, IMU samples as they are measured. The filter
/// stays at the last frame's end with the later samples queued; each frame first takes the filter
/// through the queued samples up to its end. The estimate (Estimate) is the filter propagated
/// through the whole queue, updated at every sample.
#include <array>
#include <deque>
#include <numbers>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/perception/point_map.h"

namespace rotorguard::perception {

struct LioOptions {
  /// Mounting points relative to the centre of gravity, body frame, axes aligned with it [m]:
  /// hardware facts (the stack sets them from the vehicle's sensors).
  Vector3 imu_position_m = Vector3::Zero();
  Vector3 lidar_position_m = Vector3(0.0, 0.0, 0.06);
  /// The LiDAR's calibration the filter estimates: prior stds of its axes' rotation from the
  /// IMU's [rad] (> 0) and of its clock's offset [s] (> 0), and their random walks [rad/√s],
  /// [s/√s] (>= 0). estimate_lidar_calibration false: both held at the mount as given.
  bool estimate_lidar_calibration = true;
  double lidar_rotation_std_rad = 0.02;
  double lidar_time_offset_std_s = 0.005;
  double lidar_rotation_random_walk = 1.0e-4;
  double lidar_time_offset_random_walk = 1.0e-5;
  /// The noise the filter assumes, continuous-time densities. The accelerometer's is the
  /// airframe's vibration (a few tenths of m/s² at the rotor frequencies) more than the sensor's.
  double accel_noise_density = 0.1;        ///< [m/s²/√Hz], > 0
  double gyro_noise_density = 2.0e-3;      ///< [rad/s/√Hz], > 0
  double accel_bias_random_walk = 1.0e-3;  ///< [m/s³/√Hz], > 0
  double gyro_bias_random_walk = 1.0e-4;   ///< [rad/s²/√Hz], > 0
  /// Prior stds at the start: biases, and the start pose and velocity.
  double accel_bias_initial = 0.05;        ///< [m/s²], > 0
  double gyro_bias_initial = 5.0e-3;       ///< [rad/s], > 0
  double initial_position_std_m = 0.01;    ///< > 0
  double initial_attitude_std_rad = 0.01;  ///< > 0
  double initial_velocity_std_m_s = 0.05;  ///< > 0
  /// IMU samples averaged at a start on the ground for the tilt (from the specific force) and the
  /// gyro bias (when the vehicle does not turn), in [1, 1000]; in the air the filter learns both.
  int initial_samples = 15;
  /// The first seed_frames frames (in [1, 50]) after the rest initialisation are not registered:
  /// they are placed with the IMU's pose and start the map. A map of a few down-sampled frames
  /// gives a plane few points spread over a frame's voxel, and the trunks' noisy normals then read
  /// as height and tilt: registered from the second frame on, the forest flight's estimate was
  /// turned by up to 10 mrad in roll or pitch, or lifted by 8 cm, in one of its first frames, and
  /// the map built on with the error for good (0.13 m of height 14 m away). After eight frames
  /// on the IMU alone the tilt is off by 1.9 mrad at the median over 39 forest flights, 4.6 at
  /// most (registered from the second frame: 2.5 and 15.7), and the map holds the ground
  /// (docs/navigation.md, "Starting the map").
  int seed_frames = 8;
  /// A frame's points nearer than this to the sensor are dropped (the airframe, the propellers) [m], >= 0.
  double min_range_m = 0.3;
  /// A frame keeps every point_stride-th return (in [1, 100]; FAST-LIO2's point_filter_num, 3
  /// in its MID-360 configuration): consecutive returns of a scan lie centimetres apart, and
  /// the grid below keeps one point per cell of them anyway.
  int point_stride = 3;
  /// The frame's down-sampling grid [m], in [0.05, 5]: one point per cell, the one nearest its centre.
  double frame_voxel_m = 0.5;
  /// Map points a plane is fitted to, in [3, 16], the nearest within plane_search_radius_m (in
  /// (0, PointMapOptions::voxel_m]); the plane is kept when each lies within plane_tolerance_m of
  /// it (> 0) and the points spread across it: the std along its second direction at least
  /// min_plane_width_m (>= 0) and thrice their std off it (not a line of points).
  int plane_points = 5;
  double plane_search_radius_m = 0.5;
  double plane_tolerance_m = 0.1;
  double min_plane_width_m = 0.05;
  /// A point whose residual exceeds this [m] (> 0) is left out of the update (an outlier: a new
  /// surface, a moving object).
  double max_residual_m = 0.5;
  /// The std of a point-to-plane residual [m], > 0: the range noise and the surfaces' roughness.
  double point_std_m = 0.05;
  /// Iterated update: at most max_iterations (in [1, 20]), stopping once the step is below
  /// convergence_m in position and convergence_rad in attitude.
  int max_iterations = 5;
  double convergence_m = 1e-3;
  double convergence_rad = 1e-3;
  /// A frame with fewer matched points than this (>= 6) is not used: the IMU carries the estimate.
  int min_points = 30;
  /// A frame is degenerate when the position std along its weakest direction, from the frame's
  /// points alone, exceeds this [m] (> 0): 1 / sqrt(the least eigenvalue of their information,
  /// less what the fitted normals' noise adds). A direction no surface constrains has none left
  /// (an infinite std: walls without floor or ceiling, for the height); a forest's frame
  /// constrains its weakest one to a few centimetres.
  double degenerate_std_m = 0.2;
  /// IMU samples queued without a frame are taken into the filter once older than this [s], > 0
  /// (the LiDAR is late or has stopped: the IMU alone carries the filter on).
  double max_queue_s = 0.3;
  /// Map pruning runs every this many frames, >= 1.
  int prune_every_frames = 10;
  PointMapOptions map;

  /// Throws ValidationError naming the field.
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a);
};

/// What one frame did to the filter: the LiDAR odometry's health.
struct LioFrameSummary {
  TimeNs t_ns = 0;          ///< the frame's end
  bool used = false;        ///< the update ran (enough matched points, the filter initialised)
  bool degenerate = false;  ///< the frame left a direction unconstrained (degenerate_std_m)
  /// One of the first seed_frames frames: placed with the IMU's pose from the start pose, not
  /// registered (the map's reference, as the start pose is the filter's).
  bool seed = false;
  int points = 0;           ///< the frame's returns
  int points_downsampled = 0;
  /// With a plane and a residual within max_residual_m, at the last iterate that kept min_points
  /// (the first iterate's when none did).
  int points_matched = 0;
  int iterations = 0;
  double residual_rms_m = 0.0;  ///< over the matched points, at the last iterate
  /// 1 / sqrt of the least eigenvalue of the position block of the frame's information, less
  /// what the fitted normals' noise adds to it [m] (infinity when nothing is left along it).
  double weakest_std_m = 0.0;
  int map_points_added = 0;
  long map_points = 0;
  /// The LiDAR's calibration after the frame: its axes' rotation from the IMU's (rotation vector)
  /// [rad] and its clock's offset [s].
  Vector3 lidar_rotation_rad = Vector3::Zero();
  double lidar_time_offset_s = 0.0;
};

/// The filter's state of the IMU's mounting point, and of the LiDAR's calibration.
struct LioState {
  TimeNs t_ns = 0;
  Vector3 p_W = Vector3::Zero();
  Quaternion q_WB = Quaternion::Identity();
  Vector3 v_W = Vector3::Zero();
  Vector3 gyro_bias = Vector3::Zero();
  Vector3 accel_bias = Vector3::Zero();
  Quaternion q_IL = Quaternion::Identity();  ///< the LiDAR's axes in the IMU's
  double lidar_time_offset_s = 0.0;          ///< the LiDAR's stamps minus its capture times [s]
};

/// The error state's dimension and blocks.
inline constexpr int kLioStates = 19;
using LioMatrix = Eigen::Matrix<double, kLioStates, kLioStates>;
using LioVector = Eigen::Matrix<double, kLioStates, 1>;

namespace internal {
/// The measurement held over the interval between two consecutive IMU samples: their mean
/// (second order in the rates' change). The filter and every head propagate with it.
struct IntervalMeasurement {
  Vector3 f_m, w_m;
  IntervalMeasurement(const ImuSample& previous, const ImuSample& next)
      : f_m(0.5 * (previous.specific_force_B + next.specific_force_B)), w_m(0.5 * (previous.w_B + next.w_B)) {}
};
/// One propagation step (the filter's mean and its error-state transition): `x` carried over dt
/// with the IMU measurement (f_m, w_m) held, into `next`; F = ∂δx_next/∂δx into `F` if not null.
void LioTransition(const LioState& x, const Vector3& f_m, const Vector3& w_m, double dt, LioState* next,
                   LioMatrix* F);
/// The row of ∂r/∂(δp, δθ) of the point-to-plane residual r = n·(p + R q) + d, R = R̂ Exp(δθ).
Eigen::Matrix<double, 1, 6> PointToPlaneJacobian(const Vector3& n, const Matrix3& R, const Vector3& q);
/// ∂r/∂(δφ, δt_d) of the same residual through q(δφ, δt_d) = q − M R_IL [s]× δφ − u δt_d: M the
/// point's rotation from its capture to the frame's end (R_eᵀ R_j), s the point in the LiDAR's
/// frame, u its velocity in the frame-end IMU frame from the body's motion at its capture.
Eigen::Matrix<double, 1, 4> PointToPlaneCalibrationJacobian(const Vector3& n, const Matrix3& R, const Matrix3& M,
                                                            const Matrix3& R_IL, const Vector3& s, const Vector3& u);
}  // namespace internal

/// The filter's mean carried from a posterior through the IMU samples after it: the odometry's
/// estimate at the newest sample ("the head"). Each interval between two samples takes their mean
/// (Lio's propagation, without the covariance). Lio keeps one over its own queue.
class LioHead {
 public:
  /// Starts at `posterior`, `posterior_imu` being the sample it holds beyond its time.
  void Reset(const LioState& posterior, const ImuSample& posterior_imu) {
    state_ = posterior;
    imu_ = posterior_imu;
  }
  /// Carries the head to a newer sample (one not newer than the last is ignored; one the state's
  /// time has passed is only held).
  void Propagate(const ImuSample& imu);
  const LioState& state() const { return state_; }
  /// The newest sample taken (its rates are the estimate's).
  const ImuSample& imu() const { return imu_; }

 private:
  LioState state_;
  ImuSample imu_;
};

/// What a consumer on another thread needs to follow a Lio (LioHeadFollower): the filter's
/// posterior (after a frame's update, the rest initialisation or the start), the sample it holds
/// beyond its time, and its serial number.
struct LioPosterior {
  LioState state;
  ImuSample imu;
  std::uint64_t serial = 0;  ///< 0: none yet
};

/// The body's estimate from a state of the IMU's mount and a gyro reading: position and velocity
/// of the centre of gravity (`imu_position_m` behind the mount), bias-corrected body rates;
/// `valid` as given.
StateEstimate LioBodyEstimate(const LioState& x, const Vector3& w_m, const Vector3& imu_position_m, bool valid);

/// A Lio's head kept by another thread, from the IMU samples it sees and the posteriors the Lio
/// publishes: the onboard runtime's control thread, while the odometry registers frames on its
/// own. A posterior that arrives late (the frame took long) is carried through the samples since
/// its time, so the head is the Lio's own, to the bit, once the follower has seen the same
/// samples and posteriors (tests/perception/lio_test.cc). Allocation-free: the samples are kept
/// in a ring of kSamples (0.77 s at 333 Hz), and a posterior older than the ring is carried from
/// its oldest sample (counted in gaps()).
class LioHeadFollower {
 public:
  static constexpr int kSamples = 256;
  /// One IMU sample, in the order the Lio took them (non-finite ones are ignored, as the Lio
  /// ignores them).
  void OnImu(const ImuSample& imu);
  /// A posterior the Lio published (an older serial than the last is ignored).
  void OnPosterior(const LioPosterior& posterior);
  /// No posterior yet: the head is not valid.
  bool valid() const { return serial_ > 0; }
  const LioHead& head() const { return head_; }
  /// Posteriors older than the oldest sample kept.
  int gaps() const { return gaps_; }

 private:
  std::array<ImuSample, kSamples> ring_{};
  int count_ = 0, next_ = 0;  // samples kept, and where the next one goes
  LioHead head_;
  std::uint64_t serial_ = 0;
  int gaps_ = 0;
};

class Lio {
 public:
  using Matrix = LioMatrix;
  using Vector = LioVector;

  /// `start_position_W` and `start_yaw_rad`: the body's (centre of gravity's) pose at the start,
  /// which defines the world frame; the vehicle is at rest there.
  Lio(const LioOptions& options, const Vector3& start_position_W, double start_yaw_rad);

  /// Takes one IMU sample (non-finite or out-of-order samples are ignored).
  void OnImu(const ImuSample& imu);
  /// Registers one frame and adds it to the map. A frame that ends before the filter's time (it
  /// came too late) or before the filter is initialised is counted and not used.
  LioFrameSummary OnFrame(const LidarFrame& frame);

  /// An IMU sample came: the estimate runs from the start pose.
  bool started() const { return started_; }
  /// The rest initialisation is done (initial_samples taken): frames are registered from then on.
  bool initialised() const { return initialised_; }
  /// The estimate at the newest IMU sample, of the body: position and velocity of the centre of
  /// gravity, bias-corrected body rates. Valid from the first IMU sample (the start pose, then
  /// propagated).
  StateEstimate Estimate() const;
  /// The same at the end of the last frame (what the frame was registered at).
  StateEstimate FrameEstimate() const;
  /// The filter's state at the newest IMU sample, and its covariance there: the filter's, carried
  /// through the samples since the last frame (on each call: no consumer needs it at the IMU rate,
  /// so the samples propagate the mean only).
  const LioState& state() const { return head_.state(); }
  /// The filter's latest posterior (LioHeadFollower).
  const LioPosterior& posterior() const { return posterior_; }
  Matrix covariance() const;
  const PointMap& map() const { return map_; }
  const LioOptions& options() const { return options_; }

 private:
  /// A propagated pose the deskewing interpolates from.
  struct Pose {
    TimeNs t_ns;
    Vector3 p, v, a_W, w;  // a_W and w: held from t_ns to the next pose
    Matrix3 R;
  };
  /// Starts the filter at the first IMU sample; then, with initial_samples, the rest
  /// initialisation.
  void Start(const ImuSample& imu);
  void Initialise();
  /// The body's estimate from the mount's state and a gyro reading.
  StateEstimate BodyEstimate(const LioState& x, const Vector3& w_m) const;
  /// Propagates (x, P) from x->t_ns to t_ns with the measurement (f, w) held; P if not null,
  /// the pose at the start of the step into `poses` if not null.
  void Propagate(const Vector3& f_m, const Vector3& w_m, TimeNs t_ns, LioState* x, Matrix* P,
                 std::vector<Pose>* poses) const;
  /// Propagate over the interval between two consecutive samples, with their mean.
  void PropagateBetween(const ImuSample& previous, const ImuSample& next, LioState* x, Matrix* P,
                        std::vector<Pose>* poses) const;
  /// The filter (and its covariance, if P is not null) carried through the queued samples.
  void PropagateQueue(LioState* x, Matrix* P) const;
  /// Takes the filter through the queued samples up to t_ns (the last interval held to t_ns).
  void AdvanceFilter(TimeNs t_ns, std::vector<Pose>* poses);
  /// Drops the kept poses a point at t_ns or later does not need.
  void DropPosesBefore(TimeNs t_ns);
  /// The head: the filter through the whole queue.
  void RebuildHead();
  /// A deskewed point: q in the IMU frame at the frame's end, and what its calibration Jacobian
  /// needs (internal::PointToPlaneCalibrationJacobian).
  struct Deskewed {
    Vector3 q, s, u;
    Matrix3 M;
  };
  /// Points of the frame in the IMU frame at its end, deskewed and down-sampled.
  void DeskewAndDownsample(const LidarFrame& frame, const std::vector<Pose>& poses, std::vector<Deskewed>* out,
                           LioFrameSummary* summary);
  /// A point's plane in the map: n·y + d = 0, and the covariance of its fitted normal.
  struct Plane {
    int point;
    Vector3 n;
    double d;
    Matrix3 normal_cov;
  };
  /// The plane of each point of the frame placed with `x` that has one, into planes_.
  void FindPlanes(const std::vector<Vector3>& points_I, const LioState& x);
  /// The iterated update with the deskewed points; false if too few matched.
  void Update(const std::vector<Deskewed>& points, LioFrameSummary* summary);

  LioOptions options_;
  Vector3 start_position_W_;
  double start_yaw_rad_;
  Vector3 lidar_in_imu_;  ///< the LiDAR's position in the IMU frame (axes aligned)
  PointMap map_;
  bool started_ = false, initialised_ = false;
  LioState filter_;
  Matrix filter_P_ = Matrix::Zero();
  ImuSample filter_imu_;         ///< the last sample the filter took (held beyond it)
  std::deque<ImuSample> queue_;  ///< samples after the filter's time, oldest first
  LioHead head_;                 ///< the filter through the queue (mean only)
  LioPosterior posterior_;       ///< the filter when the head was last rebuilt from it
  int frames_ = 0;
  // Scratch kept across frames (no allocation per frame once warm).
  std::vector<Pose> poses_;
  std::vector<Deskewed> deskewed_;
  std::vector<Vector3> points_, neighbours_;
  std::vector<Plane> planes_;
  /// The down-sampling grid's cells: each one's point nearest its centre (squared distance in
  /// cells, and the point).
  struct CellBest {
    double d2;
    Deskewed point;
  };
  CellIndex cell_index_;
  std::vector<CellBest> cell_best_;
};

template <typename Archive>
void LioOptions::Serialize(Archive* a) {
  // The filter's noise: up to ten times the vibration of a badly balanced airframe (docs/truth.md)
  // over the sensors' own (sensors.imu); beyond, the IMU would tell it nothing.
  a->Visit("estimate_lidar_calibration", &estimate_lidar_calibration,
           {.meaning = "estimate the LiDAR's rotation from the IMU and its clock's offset in flight"});
  a->Visit("lidar_rotation_std_rad", &lidar_rotation_std_rad,
           {.meaning = "prior std of the LiDAR's axes' rotation from the IMU's [rad]", .max = 0.5, .positive = true});
  a->Visit("lidar_time_offset_std_s", &lidar_time_offset_std_s,
           {.meaning = "prior std of the LiDAR clock's offset [s]", .max = 0.05, .positive = true});
  a->Visit("lidar_rotation_random_walk", &lidar_rotation_random_walk,
           {.meaning = "random walk of the LiDAR's rotation [rad/√s]", .min = 0.0, .max = 0.1});
  a->Visit("lidar_time_offset_random_walk", &lidar_time_offset_random_walk,
           {.meaning = "random walk of the LiDAR clock's offset [s/√s]", .min = 0.0, .max = 0.01});
  a->Visit("accel_noise_density", &accel_noise_density,
           {.meaning = "accelerometer noise the filter assumes, vibration included [m/s²/√Hz]",
            .max = 10.0,
            .positive = true});
  a->Visit("gyro_noise_density", &gyro_noise_density,
           {.meaning = "gyro noise the filter assumes [rad/s/√Hz]", .max = 1.0, .positive = true});
  a->Visit("accel_bias_random_walk", &accel_bias_random_walk, {.meaning = "[m/s³/√Hz]", .max = 1.0, .positive = true});
  a->Visit("gyro_bias_random_walk", &gyro_bias_random_walk, {.meaning = "[rad/s²/√Hz]", .max = 0.1, .positive = true});
  a->Visit("accel_bias_initial", &accel_bias_initial,
           {.meaning = "prior std of the accelerometer bias [m/s²]", .max = kGravity, .positive = true});
  a->Visit("gyro_bias_initial", &gyro_bias_initial,
           {.meaning = "prior std of the gyro bias [rad/s]", .max = 1.0, .positive = true});
  a->Visit("initial_position_std_m", &initial_position_std_m,
           {.meaning = "prior std of the start position [m]", .max = 10.0, .positive = true});
  a->Visit("initial_attitude_std_rad", &initial_attitude_std_rad,
           {.meaning = "prior std of the start attitude [rad]", .max = std::numbers::pi, .positive = true});
  a->Visit("initial_velocity_std_m_s", &initial_velocity_std_m_s,
           {.meaning = "prior std of the start velocity [m/s]", .max = 10.0, .positive = true});
  a->Visit(
      "initial_samples", &initial_samples,
      {.meaning = "IMU samples averaged at rest on the ground for the tilt and the gyro bias", .min = 1, .max = 1000});
  a->Visit("seed_frames", &seed_frames,
           {.meaning = "the first frames start the map at the IMU's pose, unregistered", .min = 1, .max = 50});
  a->Visit("min_range_m", &min_range_m,
           {.meaning = "nearer returns are dropped (the airframe) [m]", .min = 0, .max = 100});
  a->Visit("point_stride", &point_stride, {.meaning = "a frame keeps every this-many-th return", .min = 1, .max = 100});
  a->Visit("frame_voxel_m", &frame_voxel_m,
           {.meaning = "a frame keeps one point per cell of this edge [m]", .min = 0.05, .max = 5});
  a->Visit("plane_search_radius_m", &plane_search_radius_m,
           {.meaning = "a point's plane is fitted to map points within this [m], at most map.voxel_m",
            .max = 10.0,
            .positive = true});
  a->Visit("plane_points", &plane_points, {.meaning = "map points a plane is fitted to", .min = 3, .max = 16});
  a->Visit("plane_tolerance_m", &plane_tolerance_m,
           {.meaning = "a plane's points lie within this of it [m]", .max = 10.0, .positive = true});
  a->Visit("min_plane_width_m", &min_plane_width_m,
           {.meaning = "a plane's points spread at least this across it (std) [m]", .min = 0, .max = 1});
  a->Visit("max_residual_m", &max_residual_m,
           {.meaning = "larger point-to-plane residuals are outliers [m]", .max = 10.0, .positive = true});
  a->Visit("point_std_m", &point_std_m,
           {.meaning = "std of a point-to-plane residual [m]", .max = 10.0, .positive = true});
  a->Visit("max_iterations", &max_iterations, {.meaning = "iterations of the update", .min = 1, .max = 20});
  a->Visit("convergence_m", &convergence_m,
           {.meaning = "the update stops once a step moves the position less [m]", .max = 1.0, .positive = true});
  a->Visit("convergence_rad", &convergence_rad,
           {.meaning = "and the attitude less than this [rad]", .max = 1.0, .positive = true});
  a->Visit("min_points", &min_points,
           {.meaning = "a frame with fewer matched points is not used", .min = 6, .max = 100000});
  a->Visit("degenerate_std_m", &degenerate_std_m,
           {.meaning = "a frame is degenerate when its weakest direction's position std exceeds this [m]",
            .max = 100.0,
            .positive = true});
  a->Visit("max_queue_s", &max_queue_s,
           {.meaning = "IMU samples older than this without a frame enter the filter [s]", .min = 0.01, .max = 10});
  a->Visit("prune_every_frames", &prune_every_frames,
           {.meaning = "frames between prunings of the map's window", .min = 1, .max = 100000});
  a->Visit("map", &map, {.meaning = "the odometry's point map"});
}

}  // namespace rotorguard::perception
