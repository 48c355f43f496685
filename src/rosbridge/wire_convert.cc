#include "rotorguard/rosbridge/wire_convert.h"

#include <algorithm>
#include <cmath>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/stack/supervisor.h"

namespace rotorguard::rosbridge {

namespace {
ros1::Vec3 ToVec3(const Vector3& v) { return {v.x(), v.y(), v.z()}; }
Vector3 FromVec3(const ros1::Vec3& v) { return {v[0], v[1], v[2]}; }
}  // namespace

ros1::Pose ToWirePose(const Vector3& p, const Quaternion& q) {
  return {ToVec3(p), {q.x(), q.y(), q.z(), q.w()}};  // ROS stores x, y, z, w; Eigen's constructor takes w first
}

void FromWirePose(const ros1::Pose& pose, Vector3* p, Quaternion* q) {
  *p = FromVec3(pose.position);
  const auto& o = pose.orientation_xyzw;
  *q = Quaternion(o[3], o[0], o[1], o[2]).normalized();
}

ros1::Imu ToWire(const ImuSample& m, const TimeBase& base) {
  return {base.ToStamp(m.t_ns), frames::kImu, ToVec3(m.w_B), ToVec3(m.specific_force_B)};
}
ImuSample FromWire(const ros1::Imu& m, const TimeBase& base) {
  ImuSample s;
  s.t_ns = base.ToTime(m.stamp);
  s.w_B = FromVec3(m.angular_velocity);
  s.specific_force_B = FromVec3(m.linear_acceleration);
  return s;
}

ros1::Esc ToWire(const EscTelemetry& m, const TimeBase& base) {
  return {base.ToStamp(m.t_ns), {m.motor_speed_rad_s.begin(), m.motor_speed_rad_s.end()}};
}
std::optional<EscTelemetry> FromWire(const ros1::Esc& m, const TimeBase& base) {
  if (m.motor_speed_rad_s.size() > static_cast<std::size_t>(kMaxRotors)) return std::nullopt;
  EscTelemetry e;
  e.t_ns = base.ToTime(m.stamp);
  e.motor_speed_rad_s = Eigen::Map<const Eigen::VectorXd>(m.motor_speed_rad_s.data(), static_cast<Eigen::Index>(m.motor_speed_rad_s.size()));
  return e;
}

namespace {
/// nav_msgs/Odometry of the body in `odom`: the twist in the child frame, the body's.
ros1::Odometry BodyOdometry(ros1::Stamp stamp, const Vector3& p_W, const Quaternion& q_WB, const Vector3& v_W, const Vector3& w_B) {
  return {stamp, frames::kOdom, frames::kBase, ToWirePose(p_W, q_WB), ToVec3(q_WB.conjugate() * v_W), ToVec3(w_B)};
}
}  // namespace

ros1::Odometry ToWire(const OdometrySample& m, const TimeBase& base) {
  return BodyOdometry(base.ToStamp(m.t_ns), m.p_W, m.q_WB, m.v_W, Vector3::Zero());
}
OdometrySample FromWireOdometry(const ros1::Odometry& m, const TimeBase& base) {
  OdometrySample s;
  s.t_ns = base.ToTime(m.stamp);
  FromWirePose(m.pose, &s.p_W, &s.q_WB);
  s.v_W = s.q_WB * FromVec3(m.linear);
  return s;
}

ros1::Cloud ToWire(const LidarFrame& m, const TimeBase& base) {
  ros1::Cloud c;
  c.stamp = base.ToStamp(m.t_start_ns);
  c.frame_id = frames::kLidar;
  c.points.resize(m.points_S.size());
  for (std::size_t i = 0; i < m.points_S.size(); ++i) {
    ros1::CloudPoint& p = c.points[i];
    p.x = m.points_S[i].x();
    p.y = m.points_S[i].y();
    p.z = m.points_S[i].z();
    p.intensity = 100.0f;  // the simulated sensor measures no reflectivity
    p.time_s = LidarOffsetToSeconds32(m.offset_ns[i]);
  }
  return c;
}
LidarFrame FromWire(const ros1::Cloud& m, const TimeBase& base, TimeNs frame_period_ns) {
  LidarFrame f;
  f.t_start_ns = base.ToTime(m.stamp);
  f.t_end_ns = f.t_start_ns + frame_period_ns;
  f.points_S.reserve(m.points.size());
  f.offset_ns.reserve(m.points.size());
  for (const ros1::CloudPoint& p : m.points) {
    // A point stamped outside the sweep is not one of its returns (a driver's wrap-around).
    const double offset = LidarOffsetFromSeconds32(p.time_s);
    if (!(offset >= 0.0 && offset < static_cast<double>(frame_period_ns))) {
      ++f.dropped;
      continue;
    }
    f.points_S.emplace_back(p.x, p.y, p.z);
    f.offset_ns.push_back(static_cast<std::uint32_t>(offset));
  }
  return f;
}

ros1::Odometry EstimateToWire(const StateEstimate& m, const TimeBase& base) {
  return BodyOdometry(base.ToStamp(m.t_ns), m.p_W, m.q_WB, m.v_W, m.w_B);
}
StateEstimate EstimateFromWire(const ros1::Odometry& m, const TimeBase& base, bool valid) {
  StateEstimate e;
  e.t_ns = base.ToTime(m.stamp);
  e.valid = valid;
  FromWirePose(m.pose, &e.p_W, &e.q_WB);
  e.v_W = e.q_WB * FromVec3(m.linear);
  e.w_B = FromVec3(m.angular);
  return e;
}

ros1::Health HealthToWire(const runtime::CycleTelemetry& c, const TimeBase& base) {
  ros1::Health h;
  h.stamp = base.ToStamp(c.command.state_t_ns);
  h.mode = ToName(c.mode);
  for (int i = 0; i < c.fdd_rotors; ++i) {
    const runtime::RotorHealthSample& r = c.health[static_cast<std::size_t>(i)];
    h.health.emplace_back(ToName(r.health));
    h.loss_of_effectiveness.push_back(r.loss_of_effectiveness);
    h.motor_index.push_back(r.motor_index);
    h.propeller_index.push_back(r.propeller_index);
  }
  return h;
}

ros1::Cycle ToWire(const runtime::CycleTelemetry& c, const TimeBase& base) {
  ros1::Cycle w;
  w.command = {base.ToStamp(c.command.state_t_ns), c.command.cycle, base.ToStamp(c.command.sent_t_ns), c.command.compute_s,
               c.command.held, {c.command.thrust_n.begin(), c.command.thrust_n.end()}, c.command.release_parachute};
  w.inputs = c.command.inputs;
  w.lio_serial = c.command.lio_serial;
  w.estimate_valid = c.estimate.valid;
  w.estimate = EstimateToWire(c.estimate, base);
  w.reference = {ToVec3(c.reference.p_W), ToVec3(c.reference.v_W), ToVec3(c.reference.a_W), ToVec3(c.reference.j_W),
                 c.reference.yaw, c.reference.yaw_rate, ToVec3(c.reference.s_W)};
  w.health = HealthToWire(c, base);
  return w;
}

runtime::CycleTelemetry FromWire(const ros1::Cycle& w, const TimeBase& base) {
  runtime::CycleTelemetry c;
  c.command.state_t_ns = base.ToTime(w.command.stamp);
  c.command.cycle = w.command.cycle;
  c.command.sent_t_ns = base.ToTime(w.command.sent);
  c.command.compute_s = w.command.compute_s;
  c.command.held = w.command.held;
  c.command.release_parachute = w.command.release_parachute;
  c.command.inputs = w.inputs;
  c.command.lio_serial = w.lio_serial;
  const std::size_t n = std::min<std::size_t>(w.command.thrust_n.size(), kMaxRotors);
  c.command.thrust_n = Eigen::Map<const Eigen::VectorXd>(w.command.thrust_n.data(), static_cast<Eigen::Index>(n));
  c.mode = FromName<stack::FlightMode>(w.health.mode).value_or(stack::FlightMode::kNominal);
  c.estimate = EstimateFromWire(w.estimate, base, w.estimate_valid);
  c.reference = {FromVec3(w.reference.position), FromVec3(w.reference.velocity), FromVec3(w.reference.acceleration),
                 FromVec3(w.reference.jerk), w.reference.yaw, w.reference.yaw_rate, FromVec3(w.reference.snap)};
  c.fdd_rotors = static_cast<int>(std::min<std::size_t>(w.health.health.size(), kMaxRotors));
  for (int i = 0; i < c.fdd_rotors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    runtime::RotorHealthSample& r = c.health[k];
    r.health = FromName<fdd::RotorHealth>(w.health.health[k]).value_or(fdd::RotorHealth::kOk);
    if (k < w.health.loss_of_effectiveness.size()) r.loss_of_effectiveness = static_cast<float>(w.health.loss_of_effectiveness[k]);
    if (k < w.health.motor_index.size()) r.motor_index = static_cast<float>(w.health.motor_index[k]);
    if (k < w.health.propeller_index.size()) r.propeller_index = static_cast<float>(w.health.propeller_index[k]);
  }
  return c;
}

}  // namespace rotorguard::rosbridge
