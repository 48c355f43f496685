#include "rotorguard/perception/lio.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/core/math.h"

namespace rotorguard::perception {

namespace {
// The error state's blocks.
constexpr int kP = 0, kTheta = 3, kV = 6, kBg = 9, kBa = 12, kPhi = 15, kDt = 18;
// A calibration held fixed keeps a prior this tight (the filter's information must stay finite).
constexpr double kFixedRotationStdRad = 1e-7, kFixedTimeOffsetStdS = 1e-8;
const Vector3 kGravityW(0.0, 0.0, -kGravity);
// The world's ground is z = 0: a start this close to it rests on the landing gear.
constexpr double kOnGroundM = 0.05;
}  // namespace

void LioOptions::Validate() const {
  CheckDeclaredRanges("LioOptions", *this);  // its keys; the map validates itself below
  if (!imu_position_m.allFinite()) ThrowValidation("LioOptions", "imu_position_m", "(non-finite)", "finite numbers");
  if (!lidar_position_m.allFinite())
    ThrowValidation("LioOptions", "lidar_position_m", "(non-finite)", "finite numbers");
  if (!(plane_search_radius_m <= map.voxel_m)) {
    ThrowValidation("LioOptions", "plane_search_radius_m", plane_search_radius_m, "a radius in (0, map.voxel_m] m");
  }
  map.Validate();
}

Lio::Lio(const LioOptions& options, const Vector3& start_position_W, double start_yaw_rad)
    : options_(options),
      start_position_W_(start_position_W),
      start_yaw_rad_(start_yaw_rad),
      lidar_in_imu_(options.lidar_position_m - options.imu_position_m),
      map_(options.map) {
  options_.Validate();
  if (!start_position_W.allFinite() || !std::isfinite(start_yaw_rad)) {
    ThrowValidation("Lio", "start pose", "(non-finite)", "finite numbers");
  }
}

void Lio::Start(const ImuSample& imu) {
  // The start pose, level, at rest, the biases unknown; the filter runs from the first sample.
  filter_ = LioState{};
  filter_.t_ns = imu.t_ns;
  filter_.q_WB = QuaternionFromYaw(start_yaw_rad_);
  filter_.p_W = start_position_W_ + filter_.q_WB * options_.imu_position_m;
  filter_P_.setZero();
  filter_P_.block<3, 3>(kP, kP).diagonal().setConstant(std::pow(options_.initial_position_std_m, 2));
  filter_P_.block<3, 3>(kTheta, kTheta).diagonal().setConstant(std::pow(options_.initial_attitude_std_rad, 2));
  filter_P_.block<3, 3>(kV, kV).diagonal().setConstant(std::pow(options_.initial_velocity_std_m_s, 2));
  filter_P_.block<3, 3>(kBg, kBg).diagonal().setConstant(std::pow(options_.gyro_bias_initial, 2));
  filter_P_.block<3, 3>(kBa, kBa).diagonal().setConstant(std::pow(options_.accel_bias_initial, 2));
  const bool calibrate = options_.estimate_lidar_calibration;
  filter_P_.block<3, 3>(kPhi, kPhi).diagonal().setConstant(
      std::pow(calibrate ? options_.lidar_rotation_std_rad : kFixedRotationStdRad, 2));
  filter_P_(kDt, kDt) = std::pow(calibrate ? options_.lidar_time_offset_std_s : kFixedTimeOffsetStdS, 2);
  filter_imu_ = imu;
  started_ = true;
}

void Lio::Initialise() {
  // The gyro's mean over the first samples is its bias when the vehicle does not turn. The
  // accelerometer's mean gives the tilt only on the ground: there it reads gravity alone (plus its
  // bias, whose part across gravity is indistinguishable from a tilt and is left to the filter).
  // In the air it reads thrust and drag, and the thrust is along the body's z axis whatever the
  // tilt, so a vehicle that starts in the air starts level, as the start pose says (a wind's drag
  // of 0.3 m/s² would otherwise tilt the whole map by 0.03 rad).
  // The gyro's mean is its bias only on the ground too: a vehicle that starts hovering is turned
  // by its controller from the first samples, slowly enough to pass the test below (about
  // 0.04 rad/s over the first 45 ms of a forest flight), and that rate taken for a bias turns the
  // estimate by it until the map is started, and the map with it, for good (7-9 mrad, 0.13 m of
  // height 14 m away). In the air the filter learns the bias (its prior, gyro_bias_initial,
  // covers a MEMS gyro's).
  // Still: the rates' mean below 0.05 rad/s and their spread below 0.1 rad/s (a sway that
  // averages out is not rest; the gyro's own noise is a few hundredths).
  Vector3 f = filter_imu_.specific_force_B, w = filter_imu_.w_B;
  Matrix3 w_moment = w * w.transpose();
  for (const ImuSample& s : queue_) {
    f += s.specific_force_B;
    w += s.w_B;
    w_moment.noalias() += s.w_B * s.w_B.transpose();
  }
  const double n = static_cast<double>(queue_.size() + 1);
  f /= n;
  w /= n;
  const double w_spread2 = std::max(0.0, (w_moment / n - w * w.transpose()).trace());
  const bool still = w.norm() < 0.05 && w_spread2 < 0.1 * 0.1;
  const bool on_ground = start_position_W_.z() <= kOnGroundM;
  if (still && on_ground && std::abs(f.norm() - kGravity) < 0.5 * kGravity) {
    // q_WB = R_z(ψ) · tilt, the tilt taking the measured up onto the world's, its own yaw removed
    // so that the start's yaw holds.
    const Quaternion tilt = Quaternion::FromTwoVectors(f.normalized(), Vector3::UnitZ());
    filter_.q_WB = (QuaternionFromYaw(start_yaw_rad_) * QuaternionFromYaw(-YawOf(tilt)) * tilt).normalized();
    filter_.p_W = start_position_W_ + filter_.q_WB * options_.imu_position_m;
  }
  if (still && on_ground) filter_.gyro_bias = w;
  initialised_ = true;
  // The samples since the start again, with the tilt and the bias.
  RebuildHead();
}

namespace internal {

void LioTransition(const LioState& x, const Vector3& f_m, const Vector3& w_m, double dt, LioState* next,
                   LioMatrix* F) {
  const Vector3 w = w_m - x.gyro_bias;
  const Vector3 f = f_m - x.accel_bias;
  const Matrix3 R = x.q_WB.toRotationMatrix();
  const Vector3 a = R * f + kGravityW;
  if (F) {
    // δp' = δp + δv dt,  δθ' = Exp(−ω dt) δθ − δb_g dt,  δv' = δv − R [f]× δθ dt − R δb_a dt
    // (first order in dt; the biases and the LiDAR's calibration are random walks).
    F->setIdentity();
    F->block<3, 3>(kP, kV) = Matrix3::Identity() * dt;
    F->block<3, 3>(kTheta, kTheta) = ExpSO3(-w * dt);
    F->block<3, 3>(kTheta, kBg) = -Matrix3::Identity() * dt;
    F->block<3, 3>(kV, kTheta) = -R * Skew(f) * dt;
    F->block<3, 3>(kV, kBa) = -R * dt;
  }
  *next = x;
  next->p_W += x.v_W * dt + 0.5 * a * dt * dt;
  next->v_W += a * dt;
  next->q_WB = (x.q_WB * Quaternion(ExpSO3(w * dt))).normalized();
}

Eigen::Matrix<double, 1, 6> PointToPlaneJacobian(const Vector3& n, const Matrix3& R, const Vector3& q) {
  // R Exp(δθ) q ≈ R q + R (δθ × q) = R q − R [q]× δθ.
  Eigen::Matrix<double, 1, 6> h;
  h.head<3>() = n.transpose();
  h.tail<3>() = -(n.transpose() * R * Skew(q));
  return h;
}

Eigen::Matrix<double, 1, 4> PointToPlaneCalibrationJacobian(const Vector3& n, const Matrix3& R, const Matrix3& M,
                                                            const Matrix3& R_IL, const Vector3& s, const Vector3& u) {
  // q(δφ, δt_d) = q − M R_IL [s]× δφ − u δt_d (R_IL Exp(δφ) s ≈ R_IL s − R_IL [s]× δφ; a later
  // capture, t_d smaller, moves the point along its velocity).
  const Eigen::Matrix<double, 1, 3> nR = n.transpose() * R;
  Eigen::Matrix<double, 1, 4> h;
  h.head<3>() = -(nR * M * R_IL * Skew(s));
  h(3) = -nR.dot(u);
  return h;
}

}  // namespace internal

void LioHead::Propagate(const ImuSample& imu) {
  // Lio::PropagateBetween's mean: the interval's two samples averaged and held over it. A sample
  // the state's time has passed (it came after a frame that ended later) only starts the next
  // interval, as it does for the filter.
  const double dt = ToSeconds(imu.t_ns - state_.t_ns);
  if (imu.t_ns <= imu_.t_ns) return;
  if (dt > 0.0) {
    LioState next;
    const internal::IntervalMeasurement m(imu_, imu);
    internal::LioTransition(state_, m.f_m, m.w_m, dt, &next, nullptr);
    state_ = next;
    state_.t_ns = imu.t_ns;
  }
  imu_ = imu;
}

void LioHeadFollower::OnImu(const ImuSample& imu) {
  if (!imu.w_B.allFinite() || !imu.specific_force_B.allFinite()) return;
  if (count_ > 0 && imu.t_ns <= ring_[static_cast<std::size_t>((next_ + kSamples - 1) % kSamples)].t_ns) return;
  ring_[static_cast<std::size_t>(next_)] = imu;
  next_ = (next_ + 1) % kSamples;
  count_ = std::min(count_ + 1, kSamples);
  if (valid()) head_.Propagate(imu);
}

void LioHeadFollower::OnPosterior(const LioPosterior& posterior) {
  if (posterior.serial <= serial_) return;
  serial_ = posterior.serial;
  head_.Reset(posterior.state, posterior.imu);
  // The samples since the posterior's held one, oldest first.
  const int oldest = (next_ + kSamples - count_) % kSamples;
  if (count_ == kSamples && ring_[static_cast<std::size_t>(oldest)].t_ns > posterior.imu.t_ns) ++gaps_;
  for (int k = 0; k < count_; ++k) {
    const ImuSample& s = ring_[static_cast<std::size_t>((oldest + k) % kSamples)];
    if (s.t_ns > posterior.imu.t_ns) head_.Propagate(s);
  }
}

void Lio::Propagate(const Vector3& f_m, const Vector3& w_m, TimeNs t_ns, LioState* x, Matrix* P,
                    std::vector<Pose>* poses) const {
  const double dt = ToSeconds(t_ns - x->t_ns);
  if (dt <= 0.0) return;
  if (poses) {
    const Matrix3 R = x->q_WB.toRotationMatrix();
    poses->push_back({x->t_ns, x->p_W, x->v_W, R * (f_m - x->accel_bias) + kGravityW, w_m - x->gyro_bias, R});
  }
  Matrix F;
  LioState next;
  internal::LioTransition(*x, f_m, w_m, dt, &next, P ? &F : nullptr);
  if (P) {
    Matrix Pn = F * (*P) * F.transpose();
    // White noise densities integrate to variances σ² dt; the bias walks likewise.
    Pn.block<3, 3>(kTheta, kTheta).diagonal().array() += std::pow(options_.gyro_noise_density, 2) * dt;
    Pn.block<3, 3>(kV, kV).diagonal().array() += std::pow(options_.accel_noise_density, 2) * dt;
    Pn.block<3, 3>(kBg, kBg).diagonal().array() += std::pow(options_.gyro_bias_random_walk, 2) * dt;
    Pn.block<3, 3>(kBa, kBa).diagonal().array() += std::pow(options_.accel_bias_random_walk, 2) * dt;
    if (options_.estimate_lidar_calibration) {
      Pn.block<3, 3>(kPhi, kPhi).diagonal().array() += std::pow(options_.lidar_rotation_random_walk, 2) * dt;
      Pn(kDt, kDt) += std::pow(options_.lidar_time_offset_random_walk, 2) * dt;
    }
    *P = 0.5 * (Pn + Pn.transpose());
  }
  *x = next;
  x->t_ns = t_ns;
}

void Lio::OnImu(const ImuSample& imu) {
  if (!imu.w_B.allFinite() || !imu.specific_force_B.allFinite()) return;
  if (!started_) {
    Start(imu);
    RebuildHead();
    return;
  }
  if (imu.t_ns <= head_.imu().t_ns) return;
  if (initialised_ && imu.t_ns <= filter_.t_ns) {
    // A sample the last frame's end has passed (it came after that frame): the filter crossed
    // its interval on the sample before; it starts the filter's next interval.
    filter_imu_ = imu;
    head_.Propagate(imu);  // the head, at the frame's end too, only holds it
    return;
  }
  queue_.push_back(imu);
  head_.Propagate(imu);
  if (!initialised_) {
    // The filter stays at the start until the rest initialisation has its samples.
    if (static_cast<int>(queue_.size()) + 1 >= options_.initial_samples) Initialise();
    return;
  }
  // Without frames the filter follows the IMU alone, so that the queue stays short; the poses
  // it passes stay for the deskewing of a frame that started before them.
  const TimeNs keep = FromSeconds(options_.max_queue_s);
  if (imu.t_ns - queue_.front().t_ns > keep) {
    AdvanceFilter(imu.t_ns - keep, &poses_);
    DropPosesBefore(filter_.t_ns - keep);
  }
}

void Lio::DropPosesBefore(TimeNs t_ns) {
  // The last pose at or before t_ns stays: a point at t_ns is placed from it.
  std::size_t first = 0;
  while (first + 1 < poses_.size() && poses_[first + 1].t_ns <= t_ns) ++first;
  poses_.erase(poses_.begin(), poses_.begin() + static_cast<std::ptrdiff_t>(first));
}

void Lio::AdvanceFilter(TimeNs t_ns, std::vector<Pose>* poses) {
  while (!queue_.empty() && queue_.front().t_ns <= t_ns) {
    const ImuSample& s = queue_.front();
    PropagateBetween(filter_imu_, s, &filter_, &filter_P_, poses);
    filter_imu_ = s;
    queue_.pop_front();
  }
  // The rest of the way on the last sample (the next one is not measured yet, or lies beyond).
  Propagate(filter_imu_.specific_force_B, filter_imu_.w_B, t_ns, &filter_, &filter_P_, poses);
}

void Lio::PropagateBetween(const ImuSample& previous, const ImuSample& next, LioState* x, Matrix* P,
                           std::vector<Pose>* poses) const {
  const internal::IntervalMeasurement m(previous, next);
  Propagate(m.f_m, m.w_m, next.t_ns, x, P, poses);
}

void Lio::PropagateQueue(LioState* x, Matrix* P) const {
  *x = filter_;
  if (P) *P = filter_P_;
  ImuSample previous = filter_imu_;
  for (const ImuSample& s : queue_) {
    PropagateBetween(previous, s, x, P, nullptr);
    previous = s;
  }
}

void Lio::RebuildHead() {
  head_.Reset(filter_, filter_imu_);
  for (const ImuSample& s : queue_) head_.Propagate(s);
  posterior_.state = filter_;
  posterior_.imu = filter_imu_;
  ++posterior_.serial;
}

Lio::Matrix Lio::covariance() const {
  LioState x;
  Matrix P;
  PropagateQueue(&x, &P);
  return P;
}

StateEstimate LioBodyEstimate(const LioState& x, const Vector3& w_m, const Vector3& imu_position_m, bool valid) {
  // The filter's state is the IMU's mount: the centre of gravity is l behind it, and moves with
  // v − R (ω × l).
  StateEstimate e;
  e.t_ns = x.t_ns;
  e.valid = valid;
  const Matrix3 R = x.q_WB.toRotationMatrix();
  const Vector3 w = w_m - x.gyro_bias;
  const Vector3& l = imu_position_m;
  e.p_W = x.p_W - R * l;
  e.q_WB = x.q_WB;
  e.v_W = x.v_W - R * w.cross(l);
  e.w_B = w;
  return e;
}

StateEstimate Lio::BodyEstimate(const LioState& x, const Vector3& w_m) const {
  return LioBodyEstimate(x, w_m, options_.imu_position_m, started_);
}

StateEstimate Lio::Estimate() const { return BodyEstimate(head_.state(), head_.imu().w_B); }

StateEstimate Lio::FrameEstimate() const { return BodyEstimate(filter_, filter_imu_.w_B); }

void Lio::DeskewAndDownsample(const LidarFrame& frame, const std::vector<Pose>& poses, std::vector<Deskewed>* out,
                              LioFrameSummary* summary) {
  // Each point to the IMU frame at the frame's end: q = R_eᵀ (R_j (t_IL + R_IL s) + p_j − p_e),
  // the pose at its capture (its stamp minus the clock's offset) from the last propagated pose
  // before it, its rate and acceleration held.
  const Matrix3 R_end_T = filter_.q_WB.toRotationMatrix().transpose();
  const Vector3& p_end = filter_.p_W;
  const Matrix3 R_IL = filter_.q_IL.toRotationMatrix();
  const TimeNs offset_ns = FromSeconds(filter_.lidar_time_offset_s);
  const double cell = options_.frame_voxel_m, min_range2 = options_.min_range_m * options_.min_range_m;
  // One point per down-sampling cell: the one nearest the cell's centre (in the sensor frame at
  // the frame's end, where the map sees them).
  cell_index_.Clear(cell_best_.size());  // about the last frame's count
  cell_best_.clear();
  std::size_t k = 0;
  const std::size_t stride = static_cast<std::size_t>(options_.point_stride);
  for (std::size_t i = 0; i < frame.points_S.size(); i += stride) {
    const Vector3 s = frame.points_S[i].cast<double>();
    if (!s.allFinite() || s.squaredNorm() < min_range2) continue;
    const TimeNs t = frame.t_start_ns + static_cast<TimeNs>(frame.offset_ns[i]) - offset_ns;
    if (poses.empty()) continue;
    // The frame's points come in time order: step the pose forward, back only if needed.
    while (k + 1 < poses.size() && poses[k + 1].t_ns <= t) ++k;
    while (k > 0 && poses[k].t_ns > t) --k;
    const Pose& a = poses[k];
    const double dt = ToSeconds(t - a.t_ns);
    const Vector3 p = a.p + a.v * dt + 0.5 * a.a_W * dt * dt;
    const Matrix3 R_j = a.R * ExpSO3(a.w * dt);
    const Vector3 arm = lidar_in_imu_ + R_IL * s;  // the point from the IMU, in the IMU's frame
    const Vector3 q = R_end_T * (R_j * arm + p - p_end);
    const Vector3 scaled = q / cell;
    const Eigen::Vector3d fl = scaled.array().floor();
    const double d2 = (scaled - fl - Vector3::Constant(0.5)).squaredNorm();
    bool added = false;
    const std::uint32_t c =
        cell_index_.FindOrAdd(KeyOfCell(fl.cast<int>()), static_cast<std::uint32_t>(cell_best_.size()), &added);
    if (!added && d2 >= cell_best_[c].d2) continue;
    // What the calibration's Jacobian needs: the point's rotation to the frame's end, and its
    // velocity there from the body's motion at its capture (v + R (ω x arm)).
    const Matrix3 M = R_end_T * R_j;
    const Vector3 u = R_end_T * (a.v + a.a_W * dt) + M * a.w.cross(arm);
    if (added) {
      cell_best_.push_back({d2, {q, s, u, M}});
    } else {
      cell_best_[c] = {d2, {q, s, u, M}};
    }
  }
  // In the order the cells were first seen: the points' (time) order, reproducible.
  out->clear();
  for (const CellBest& best : cell_best_) out->push_back(best.point);
  summary->points_downsampled = static_cast<int>(out->size());
}

void Lio::FindPlanes(const std::vector<Vector3>& points_I, const LioState& x) {
  planes_.clear();
  const Matrix3 R = x.q_WB.toRotationMatrix();
  const double min_width2 = options_.min_plane_width_m * options_.min_plane_width_m;
  for (std::size_t i = 0; i < points_I.size(); ++i) {
    const Vector3 w = x.p_W + R * points_I[i];
    if (map_.Nearest(w, options_.plane_points, options_.plane_search_radius_m, &neighbours_) < options_.plane_points)
      continue;
    // The plane through the neighbours: their centroid, and the normal along the least
    // eigenvector of their scatter (any plane, the world origin's too).
    Vector3 centroid = Vector3::Zero();
    for (const Vector3& y : neighbours_) centroid += y;
    centroid /= static_cast<double>(neighbours_.size());
    Matrix3 scatter = Matrix3::Zero();
    for (const Vector3& y : neighbours_) scatter.noalias() += (y - centroid) * (y - centroid).transpose();
    Eigen::SelfAdjointEigenSolver<Matrix3> eig;
    eig.computeDirect(scatter);
    // A plane needs width across its two directions: neighbours along a line (a thin branch, a
    // trunk's edge) fit every plane through it, and its normal would be noise. The second
    // direction's spread must reach min_plane_width_m and thrice the thickness.
    const double k = static_cast<double>(neighbours_.size());
    const double thickness2 = eig.eigenvalues()(0) / k, width2 = eig.eigenvalues()(1) / k;
    if (width2 < min_width2 || width2 < 9.0 * thickness2) continue;
    const Vector3 n = eig.eigenvectors().col(0);
    const double d = -n.dot(centroid);
    bool planar = true;
    for (const Vector3& y : neighbours_) planar = planar && std::abs(n.dot(y) + d) <= options_.plane_tolerance_m;
    if (!planar) continue;
    // The fitted normal's noise: its tilt toward in-plane direction j has variance σ² / λ_j, σ²
    // the points' scatter off the plane, λ₀ / (k − 3) (the fit's own estimate: two of a plane's
    // three degrees are the normal's), times 1.3: with five points, E[1 / λ_j] exceeds 1 / E[λ_j]
    // and the estimate falls short on average (21 % in a simulation of 20 000 patches of five
    // points, 0.7 m across with 2 cm of noise: 0.0061 against a mean n_z² of 0.0077).
    // A wall's normal tilts up and down by it, which reads as information on the height that
    // the wall does not give (the health removes it).
    const double noise = 1.3 * eig.eigenvalues()(0) / std::max(k - 3.0, 1.0);
    Matrix3 normal_cov = Matrix3::Zero();
    for (int j = 1; j <= 2; ++j) {
      const Vector3 t = eig.eigenvectors().col(j);
      normal_cov.noalias() += (noise / eig.eigenvalues()(j)) * t * t.transpose();
    }
    planes_.push_back({static_cast<int>(i), n, d, normal_cov});
  }
}

void Lio::Update(const std::vector<Deskewed>& points, LioFrameSummary* summary) {
  const LioState prior = filter_;
  const Eigen::LDLT<Matrix> prior_factor(filter_P_);
  const Matrix P_inv = prior_factor.solve(Matrix::Identity());
  const double inv_var = 1.0 / (options_.point_std_m * options_.point_std_m);
  // The measurement's states: (δp, δθ) and the calibration's (δφ, δt_d).
  constexpr int kH = 10;
  using MatrixH = Eigen::Matrix<double, kH, kH>;
  using VectorH = Eigen::Matrix<double, kH, 1>;
  const auto to_state = [](int k) { return k < 6 ? k : kPhi + (k - 6); };
  LioState x = prior;
  MatrixH HtH = MatrixH::Zero();
  Matrix3 normal_noise = Matrix3::Zero();  // Σ of the matched planes' normal covariances
  Matrix A;
  bool used = false;
  // The points as the iterate's calibration places them, linear in its change since the deskewing
  // (the prior's calibration): q + ∂q/∂(δφ, δt_d) (φ, τ).
  const Matrix3 R_IL0 = prior.q_IL.toRotationMatrix();
  const auto place = [&](const LioState& at) {
    const Vector3 phi = LogSO3(prior.q_IL.conjugate() * at.q_IL);
    const double tau = at.lidar_time_offset_s - prior.lidar_time_offset_s;
    points_.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Deskewed& d = points[i];
      points_[i] = d.q - d.M * (R_IL0 * d.s.cross(phi)) - d.u * tau;  // R_IL0 Exp(φ) s ≈ R_IL0 (s − s × φ)
    }
  };
  // The planes are searched at the first iterate and again only once the pose has moved enough
  // to change a point's neighbourhood (a tenth of the search radius, or the angle that moves a
  // point 20 m away as much): the later iterates move millimetres, and the search is most of
  // the update's cost.
  LioState searched_at = x;
  const double research_m = 0.1 * options_.plane_search_radius_m, research_rad = research_m / 20.0;
  for (int iteration = 1; iteration <= options_.max_iterations; ++iteration) {
    place(x);
    if (iteration == 1 || (x.p_W - searched_at.p_W).norm() > research_m ||
        LogSO3(searched_at.q_WB.conjugate() * x.q_WB).norm() > research_rad) {
      FindPlanes(points_, x);
      searched_at = x;
    }
    MatrixH HtH_k = MatrixH::Zero();
    VectorH Htr = VectorH::Zero();
    Matrix3 normal_noise_k = Matrix3::Zero();
    const Matrix3 R = x.q_WB.toRotationMatrix();
    const Matrix3 R_IL = x.q_IL.toRotationMatrix();
    int matched = 0;
    double sum_r2 = 0.0;
    for (const Plane& plane : planes_) {
      const Vector3& q = points_[plane.point];
      const double r = plane.n.dot(x.p_W + R * q) + plane.d;
      if (!(std::abs(r) <= options_.max_residual_m)) continue;
      const Deskewed& d = points[static_cast<std::size_t>(plane.point)];
      VectorH h;
      h.head<6>() = internal::PointToPlaneJacobian(plane.n, R, q).transpose();
      h.tail<4>() = internal::PointToPlaneCalibrationJacobian(plane.n, R, d.M, R_IL, d.s, d.u).transpose();
      HtH_k.noalias() += h * h.transpose();
      normal_noise_k += plane.normal_cov;
      Htr += h * r;
      sum_r2 += r * r;
      ++matched;
    }
    // An iterate that lost its matches ends the iterations; the last one that had them stands,
    // with its figures (the first iterate's are reported either way).
    if (matched < options_.min_points && used) break;
    summary->iterations = iteration;
    summary->points_matched = matched;
    summary->residual_rms_m = matched > 0 ? std::sqrt(sum_r2 / matched) : 0.0;
    HtH = HtH_k;
    normal_noise = normal_noise_k;
    if (matched < options_.min_points) break;
    // The MAP cost in the error e = x ⊟ x̂ and its Gauss-Newton step in δ, x ← x ⊞ δ: the prior
    // term's Jacobian is J = ∂e/∂δ, the identity but for the rotations' J_r⁻¹(e) (the IEKF's
    // prior on the manifold; it is the identity at the first iterate, where x = x̂).
    Vector e;
    e.segment<3>(kP) = x.p_W - prior.p_W;
    e.segment<3>(kTheta) = LogSO3(prior.q_WB.conjugate() * x.q_WB);
    e.segment<3>(kV) = x.v_W - prior.v_W;
    e.segment<3>(kBg) = x.gyro_bias - prior.gyro_bias;
    e.segment<3>(kBa) = x.accel_bias - prior.accel_bias;
    e.segment<3>(kPhi) = LogSO3(prior.q_IL.conjugate() * x.q_IL);
    e(kDt) = x.lidar_time_offset_s - prior.lidar_time_offset_s;
    Matrix J = Matrix::Identity();
    J.block<3, 3>(kTheta, kTheta) = InverseRightJacobianSO3(e.segment<3>(kTheta));
    J.block<3, 3>(kPhi, kPhi) = InverseRightJacobianSO3(e.segment<3>(kPhi));
    const Matrix JtP_inv = J.transpose() * P_inv;
    A.noalias() = JtP_inv * J;
    Vector b = -JtP_inv * e;
    for (int r = 0; r < kH; ++r) {
      b(to_state(r)) -= inv_var * Htr(r);
      for (int c = 0; c < kH; ++c) A(to_state(r), to_state(c)) += inv_var * HtH(r, c);
    }
    const Vector delta = A.ldlt().solve(b);
    if (!delta.allFinite()) {
      used = false;
      break;
    }
    used = true;
    x.p_W += delta.segment<3>(kP);
    x.q_WB = (x.q_WB * Quaternion(ExpSO3(delta.segment<3>(kTheta)))).normalized();
    x.v_W += delta.segment<3>(kV);
    x.gyro_bias += delta.segment<3>(kBg);
    x.accel_bias += delta.segment<3>(kBa);
    x.q_IL = (x.q_IL * Quaternion(ExpSO3(delta.segment<3>(kPhi)))).normalized();
    x.lidar_time_offset_s += delta(kDt);
    if (delta.segment<3>(kP).norm() < options_.convergence_m &&
        delta.segment<3>(kTheta).norm() < options_.convergence_rad) {
      break;
    }
  }
  // Health: the position information of the frame's points alone (the Schur complement over the
  // attitude would be stricter; the position block is what a corridor or open ground leaves weak),
  // Σ n nᵀ / σ², less what the normals' noise adds to it: E[n nᵀ] = n̄ n̄ᵀ + Σ_n, so walls alone
  // leave the height with none (not the hundredths their noisy normals would sum to).
  const Matrix3 information = inv_var * (HtH.topLeftCorner<3, 3>() - normal_noise);
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(information, Eigen::EigenvaluesOnly);
  const double least = eig.eigenvalues()(0);
  summary->weakest_std_m = least > 0.0 ? 1.0 / std::sqrt(least) : std::numeric_limits<double>::infinity();
  summary->degenerate = summary->weakest_std_m > options_.degenerate_std_m;
  summary->used = used;
  if (!used) {
    place(prior);  // the map takes the points as the prior placed them
    return;
  }
  filter_ = x;
  place(filter_);  // and as the update's calibration places them
  // The posterior's covariance in the tangent space at x (the cost's Hessian's inverse there).
  const Matrix P = A.ldlt().solve(Matrix::Identity());
  filter_P_ = 0.5 * (P + P.transpose());
}

LioFrameSummary Lio::OnFrame(const LidarFrame& frame) {
  LioFrameSummary summary;
  summary.t_ns = frame.t_end_ns;
  summary.points = static_cast<int>(frame.points_S.size());
  summary.map_points = map_.size();
  if (!initialised_ || frame.t_end_ns <= filter_.t_ns || frame.offset_ns.size() != frame.points_S.size()) {
    return summary;
  }
  // The poses the deskewing needs run from the frame's start; the filter is at the last frame's
  // end (or later, when the queue overflowed: those points use the first pose, extrapolated).
  DropPosesBefore(frame.t_start_ns);
  AdvanceFilter(frame.t_end_ns, &poses_);
  DeskewAndDownsample(frame, poses_, &deskewed_, &summary);
  // The poses are the prior's; the next frame's run from the (updated) filter.
  poses_.clear();
  summary.seed = frames_ < options_.seed_frames;
  if (summary.seed) {
    points_.clear();
    for (const Deskewed& d : deskewed_) points_.push_back(d.q);
  } else {
    Update(deskewed_, &summary);  // leaves the points, as placed, in points_
  }
  // The frame's points, placed with the filter's pose at the frame's end (updated, or the IMU's
  // alone when the frame had too few matches), extend the map, as in FAST-LIO2: a frame into
  // unmapped space is how the map reaches it. Only a broken update (a non-finite step) keeps
  // its points out.
  const Matrix3 R = filter_.q_WB.toRotationMatrix();
  for (Vector3& q : points_) q = filter_.p_W + R * q;
  if (summary.seed || summary.used || summary.points_matched < options_.min_points) {
    summary.map_points_added = map_.Insert(points_);
  }
  if (++frames_ % options_.prune_every_frames == 0) map_.Prune(filter_.p_W);
  summary.map_points = map_.size();
  summary.lidar_rotation_rad = LogSO3(filter_.q_IL);
  summary.lidar_time_offset_s = filter_.lidar_time_offset_s;
  RebuildHead();
  return summary;
}

}  // namespace rotorguard::perception
