#include "convert.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace rotorguard::ros1::internal {

namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;

/// Empty when every value is finite, else the name of the first that is not.
template <typename Range>
std::string NonFinite(const char* name, const Range& values) {
  for (const double v : values) {
    if (!std::isfinite(v)) return std::string("a non-finite value (") + std::to_string(v) + ") in " + name;
  }
  return {};
}

geometry_msgs::Vector3 ToVector3(const Vec3& v) {
  geometry_msgs::Vector3 r;
  r.x = v[0];
  r.y = v[1];
  r.z = v[2];
  return r;
}
Vec3 FromVector3(const geometry_msgs::Vector3& r) { return {r.x, r.y, r.z}; }

geometry_msgs::Pose ToPose(const Pose& p) {
  geometry_msgs::Pose r;
  r.position.x = p.position[0];
  r.position.y = p.position[1];
  r.position.z = p.position[2];
  r.orientation.x = p.orientation_xyzw[0];
  r.orientation.y = p.orientation_xyzw[1];
  r.orientation.z = p.orientation_xyzw[2];
  r.orientation.w = p.orientation_xyzw[3];
  return r;
}
Pose FromPose(const geometry_msgs::Pose& r) {
  return {{r.position.x, r.position.y, r.position.z}, {r.orientation.x, r.orientation.y, r.orientation.z, r.orientation.w}};
}

std_msgs::Header Header(Stamp stamp, const std::string& frame_id) {
  std_msgs::Header h;
  h.stamp = ToRosTime(stamp);
  h.frame_id = frame_id;
  return h;
}

// The cloud's layout (FAST-LIO2's Velodyne points: x, y, z, intensity, time as float32, ring as
// uint16), 24 bytes a point.
constexpr std::uint32_t kPointStep = 24;
sensor_msgs::PointField Field(const char* name, std::uint32_t offset, std::uint8_t type) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = type;
  f.count = 1;
  return f;
}

/// A field's value as a double, any numeric type.
double ReadField(const std::uint8_t* p, std::uint8_t type) {
  switch (type) {
    case sensor_msgs::PointField::INT8: { std::int8_t v; std::memcpy(&v, p, 1); return v; }
    case sensor_msgs::PointField::UINT8: return *p;
    case sensor_msgs::PointField::INT16: { std::int16_t v; std::memcpy(&v, p, 2); return v; }
    case sensor_msgs::PointField::UINT16: { std::uint16_t v; std::memcpy(&v, p, 2); return v; }
    case sensor_msgs::PointField::INT32: { std::int32_t v; std::memcpy(&v, p, 4); return v; }
    case sensor_msgs::PointField::UINT32: { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
    case sensor_msgs::PointField::FLOAT32: { float v; std::memcpy(&v, p, 4); return v; }
    case sensor_msgs::PointField::FLOAT64: { double v; std::memcpy(&v, p, 8); return v; }
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}
std::uint32_t FieldSize(std::uint8_t type) {
  static constexpr std::uint32_t kSize[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
  return type < 9 ? kSize[type] : 0;
}

}  // namespace

ros::Time ToRosTime(Stamp t) {
  ros::Time r;
  r.fromNSec(static_cast<std::uint64_t>(std::max<Stamp>(t, 0)));
  return r;
}
Stamp FromRosTime(const ros::Time& t) { return static_cast<Stamp>(t.toNSec()); }

sensor_msgs::Imu ToRos(const Imu& m) {
  sensor_msgs::Imu r;
  r.header = Header(m.stamp, m.frame_id);
  r.orientation_covariance[0] = -1.0;  // no orientation (REP-145)
  r.angular_velocity = ToVector3(m.angular_velocity);
  r.linear_acceleration = ToVector3(m.linear_acceleration);
  return r;
}
std::string FromRos(const sensor_msgs::Imu& r, Imu* m) {
  m->stamp = FromRosTime(r.header.stamp);
  m->frame_id = r.header.frame_id;
  m->angular_velocity = FromVector3(r.angular_velocity);
  m->linear_acceleration = FromVector3(r.linear_acceleration);
  if (auto e = NonFinite("angular_velocity", m->angular_velocity); !e.empty()) return e;
  return NonFinite("linear_acceleration", m->linear_acceleration);
}

rotorguard_msgs::EscTelemetry ToRos(const Esc& m) {
  rotorguard_msgs::EscTelemetry r;
  r.header = Header(m.stamp, "base_link");
  r.motor_speed_rad_s = m.motor_speed_rad_s;
  return r;
}
std::string FromRos(const rotorguard_msgs::EscTelemetry& r, Esc* m) {
  m->stamp = FromRosTime(r.header.stamp);
  m->motor_speed_rad_s = r.motor_speed_rad_s;
  return NonFinite("motor_speed_rad_s", m->motor_speed_rad_s);
}

sensor_msgs::BatteryState ToRos(const Battery& m) {
  sensor_msgs::BatteryState r;
  r.header = Header(m.stamp, "base_link");
  r.voltage = static_cast<float>(m.voltage);
  r.current = static_cast<float>(m.current);
  r.percentage = static_cast<float>(m.percentage);
  r.present = true;
  return r;
}
std::string FromRos(const sensor_msgs::BatteryState& r, Battery* m) {
  m->stamp = FromRosTime(r.header.stamp);
  m->voltage = r.voltage;
  m->current = r.current;  // NaN when unmeasured (sensor_msgs/BatteryState)
  m->percentage = r.percentage;
  if (!std::isfinite(m->voltage)) return "a non-finite voltage (mandatory in sensor_msgs/BatteryState)";
  return {};
}

nav_msgs::Odometry ToRos(const Odometry& m) {
  nav_msgs::Odometry r;
  r.header = Header(m.stamp, m.frame_id);
  r.child_frame_id = m.child_frame_id;
  r.pose.pose = ToPose(m.pose);
  r.twist.twist.linear = ToVector3(m.linear);
  r.twist.twist.angular = ToVector3(m.angular);
  return r;
}
std::string FromRos(const nav_msgs::Odometry& r, Odometry* m) {
  m->stamp = FromRosTime(r.header.stamp);
  m->frame_id = r.header.frame_id;
  m->child_frame_id = r.child_frame_id;
  m->pose = FromPose(r.pose.pose);
  m->linear = FromVector3(r.twist.twist.linear);
  m->angular = FromVector3(r.twist.twist.angular);
  if (auto e = NonFinite("pose.position", m->pose.position); !e.empty()) return e;
  if (auto e = NonFinite("pose.orientation", m->pose.orientation_xyzw); !e.empty()) return e;
  double norm2 = 0.0;
  for (const double q : m->pose.orientation_xyzw) norm2 += q * q;
  if (std::abs(norm2 - 1.0) > 1e-3) return "pose.orientation is not a unit quaternion (|q|² = " + std::to_string(norm2) + ")";
  if (auto e = NonFinite("twist.linear", m->linear); !e.empty()) return e;
  return NonFinite("twist.angular", m->angular);
}

sensor_msgs::PointCloud2 ToRos(const Cloud& m) {
  sensor_msgs::PointCloud2 r;
  r.header = Header(m.stamp, m.frame_id);
  r.height = 1;
  r.width = static_cast<std::uint32_t>(m.points.size());
  r.fields = {Field("x", 0, sensor_msgs::PointField::FLOAT32), Field("y", 4, sensor_msgs::PointField::FLOAT32),
              Field("z", 8, sensor_msgs::PointField::FLOAT32), Field("intensity", 12, sensor_msgs::PointField::FLOAT32),
              Field("time", 16, sensor_msgs::PointField::FLOAT32)};
  if (m.has_ring) r.fields.push_back(Field("ring", 20, sensor_msgs::PointField::UINT16));
  r.is_bigendian = false;
  r.point_step = kPointStep;
  r.row_step = kPointStep * r.width;
  r.is_dense = true;
  r.data.assign(static_cast<std::size_t>(r.row_step), 0);
  for (std::size_t i = 0; i < m.points.size(); ++i) {
    const CloudPoint& p = m.points[i];
    std::uint8_t* d = r.data.data() + i * kPointStep;
    const float f[5] = {p.x, p.y, p.z, p.intensity, p.time_s};
    std::memcpy(d, f, sizeof(f));
    std::memcpy(d + 20, &p.ring, sizeof(p.ring));
  }
  return r;
}
sensor_msgs::PointCloud2 ToRos(const PointSet& m) {
  sensor_msgs::PointCloud2 r;
  r.header = Header(m.stamp, m.frame_id);
  r.height = 1;
  r.width = static_cast<std::uint32_t>(m.points.size());
  r.fields = {Field("x", 0, sensor_msgs::PointField::FLOAT32), Field("y", 4, sensor_msgs::PointField::FLOAT32),
              Field("z", 8, sensor_msgs::PointField::FLOAT32)};
  r.point_step = 12;
  r.row_step = 12 * r.width;
  r.is_dense = true;
  r.data.resize(static_cast<std::size_t>(r.row_step));
  if (!m.points.empty()) std::memcpy(r.data.data(), m.points.data(), r.data.size());
  return r;
}

std::string FromRos(const sensor_msgs::PointCloud2& r, Cloud* m) {
  m->stamp = FromRosTime(r.header.stamp);
  m->frame_id = r.header.frame_id;
  m->points.clear();
  if (r.is_bigendian) return "a big-endian PointCloud2 (only little-endian clouds are read)";
  const std::uint64_t n = static_cast<std::uint64_t>(r.width) * r.height;
  if (r.row_step != r.width * r.point_step || r.data.size() != n * r.point_step) {
    return "a PointCloud2 whose data (" + std::to_string(r.data.size()) + " bytes) is not width x height x point_step (" +
           std::to_string(r.width) + " x " + std::to_string(r.height) + " x " + std::to_string(r.point_step) + ")";
  }
  // The per-point time: `time` [s after the stamp] (Velodyne, FAST-LIO2), or `t` [ns] (Ouster),
  // or `offset_time` [ns] (Livox).
  const sensor_msgs::PointField *x = nullptr, *y = nullptr, *z = nullptr, *intensity = nullptr, *time = nullptr, *ring = nullptr;
  double time_scale = 1.0;
  for (const sensor_msgs::PointField& f : r.fields) {
    if (f.offset + FieldSize(f.datatype) > r.point_step || FieldSize(f.datatype) == 0) {
      return "a PointCloud2 field '" + f.name + "' outside its point (offset " + std::to_string(f.offset) +
             ", point_step " + std::to_string(r.point_step) + ") or of an unknown type";
    }
    if (f.name == "x") x = &f;
    if (f.name == "y") y = &f;
    if (f.name == "z") z = &f;
    if (f.name == "intensity") intensity = &f;
    if (f.name == "ring") ring = &f;
    if (f.name == "time") time = &f, time_scale = 1.0;
    if ((f.name == "t" || f.name == "offset_time") && time == nullptr) time = &f, time_scale = 1e-9;
  }
  if (!x || !y || !z) return "a PointCloud2 without x, y and z fields";
  if (!time) return "a PointCloud2 without a per-point time field (time [s], t or offset_time [ns]): a frame's motion cannot be undone";
  m->has_ring = ring != nullptr;
  m->points.reserve(static_cast<std::size_t>(n));
  for (std::uint64_t i = 0; i < n; ++i) {
    const std::uint8_t* d = r.data.data() + i * r.point_step;
    CloudPoint p;
    const double px = ReadField(d + x->offset, x->datatype), py = ReadField(d + y->offset, y->datatype),
                 pz = ReadField(d + z->offset, z->datatype), pt = ReadField(d + time->offset, time->datatype) * time_scale;
    if (!std::isfinite(px) || !std::isfinite(py) || !std::isfinite(pz)) continue;  // no return (not dense)
    if (!std::isfinite(pt)) return "a non-finite per-point time at point " + std::to_string(i);
    p.x = static_cast<float>(px);
    p.y = static_cast<float>(py);
    p.z = static_cast<float>(pz);
    p.time_s = static_cast<float>(pt);
    if (intensity) p.intensity = static_cast<float>(ReadField(d + intensity->offset, intensity->datatype));
    if (ring) p.ring = static_cast<std::uint16_t>(ReadField(d + ring->offset, ring->datatype));
    m->points.push_back(p);
  }
  return {};
}

rotorguard_msgs::RotorCommand ToRos(const Command& m) {
  rotorguard_msgs::RotorCommand r;
  r.header = Header(m.stamp, "base_link");
  r.cycle = m.cycle;
  r.sent = ToRosTime(m.sent);
  r.compute_s = m.compute_s;
  r.held = m.held;
  r.thrust_n = m.thrust_n;
  r.release_parachute = m.release_parachute;
  return r;
}
std::string FromRos(const rotorguard_msgs::RotorCommand& r, Command* m) {
  m->stamp = FromRosTime(r.header.stamp);
  m->cycle = r.cycle;
  m->sent = FromRosTime(r.sent);
  m->compute_s = r.compute_s;
  m->held = r.held;
  m->thrust_n = r.thrust_n;
  m->release_parachute = r.release_parachute;
  return NonFinite("thrust_n", m->thrust_n);
}

rotorguard_msgs::FddHealth ToRos(const Health& m) {
  rotorguard_msgs::FddHealth r;
  r.header = Header(m.stamp, "base_link");
  r.mode = m.mode;
  r.health = m.health;
  r.loss_of_effectiveness = m.loss_of_effectiveness;
  r.motor_index = m.motor_index;
  r.propeller_index = m.propeller_index;
  return r;
}
std::string FromRos(const rotorguard_msgs::FddHealth& r, Health* m) {
  m->stamp = FromRosTime(r.header.stamp);
  m->mode = r.mode;
  m->health = r.health;
  m->loss_of_effectiveness = r.loss_of_effectiveness;
  m->motor_index = r.motor_index;
  m->propeller_index = r.propeller_index;
  return {};
}

rotorguard_msgs::ControlCycle ToRos(const Cycle& m) {
  rotorguard_msgs::ControlCycle r;
  r.command = ToRos(m.command);
  r.inputs = m.inputs;
  r.lio_serial = m.lio_serial;
  r.estimate_valid = m.estimate_valid;
  r.estimate = ToRos(m.estimate);
  r.reference.position.x = m.reference.position[0];
  r.reference.position.y = m.reference.position[1];
  r.reference.position.z = m.reference.position[2];
  r.reference.velocity = ToVector3(m.reference.velocity);
  r.reference.acceleration = ToVector3(m.reference.acceleration);
  r.reference.jerk = ToVector3(m.reference.jerk);
  r.reference.snap = ToVector3(m.reference.snap);
  r.reference.yaw = m.reference.yaw;
  r.reference.yaw_rate = m.reference.yaw_rate;
  r.health = ToRos(m.health);
  return r;
}
std::string FromRos(const rotorguard_msgs::ControlCycle& r, Cycle* m) {
  if (auto e = FromRos(r.command, &m->command); !e.empty()) return "command: " + e;
  m->inputs = r.inputs;
  m->lio_serial = r.lio_serial;
  m->estimate_valid = r.estimate_valid;
  if (auto e = FromRos(r.estimate, &m->estimate); !e.empty()) return "estimate: " + e;
  m->reference.position = {r.reference.position.x, r.reference.position.y, r.reference.position.z};
  m->reference.velocity = FromVector3(r.reference.velocity);
  m->reference.acceleration = FromVector3(r.reference.acceleration);
  m->reference.jerk = FromVector3(r.reference.jerk);
  m->reference.snap = FromVector3(r.reference.snap);
  m->reference.yaw = r.reference.yaw;
  m->reference.yaw_rate = r.reference.yaw_rate;
  return FromRos(r.health, &m->health);
}

tf2_msgs::TFMessage ToRos(const Transforms& m) {
  tf2_msgs::TFMessage r;
  for (const Transform& t : m) {
    geometry_msgs::TransformStamped s;
    s.header = Header(t.stamp, t.parent);
    s.child_frame_id = t.child;
    s.transform.translation.x = t.pose.position[0];
    s.transform.translation.y = t.pose.position[1];
    s.transform.translation.z = t.pose.position[2];
    s.transform.rotation = ToPose(t.pose).orientation;
    r.transforms.push_back(s);
  }
  return r;
}

nav_msgs::Path ToRos(const Path& m) {
  nav_msgs::Path r;
  r.header = Header(m.stamp, m.frame_id);
  for (std::size_t i = 0; i < m.poses.size(); ++i) {
    geometry_msgs::PoseStamped p;
    p.header = Header(i < m.stamps.size() ? m.stamps[i] : m.stamp, m.frame_id);
    p.pose = ToPose(m.poses[i]);
    r.poses.push_back(p);
  }
  return r;
}

std_msgs::String ToRos(const Text& m) {
  std_msgs::String r;
  r.data = m.data;
  return r;
}
std::string FromRos(const std_msgs::String& r, Text* m) {
  m->data = r.data;
  return {};
}

rosgraph_msgs::Clock ToRos(const ClockTick& m) {
  rosgraph_msgs::Clock r;
  r.clock = ToRosTime(m.clock);
  return r;
}
visualization_msgs::MarkerArray ToRos(const Markers& m) {
  visualization_msgs::MarkerArray r;
  for (const Marker& k : m.markers) {
    visualization_msgs::Marker v;
    v.header = Header(m.stamp, m.frame_id);
    v.ns = "rotorguard";
    v.id = k.id;
    v.type = k.shape == Marker::Shape::kSphere ? visualization_msgs::Marker::SPHERE : visualization_msgs::Marker::TEXT_VIEW_FACING;
    v.action = visualization_msgs::Marker::ADD;
    v.pose.position.x = k.position[0];
    v.pose.position.y = k.position[1];
    v.pose.position.z = k.position[2];
    v.pose.orientation.w = 1.0;
    v.scale.x = v.scale.y = v.scale.z = k.size;
    v.color.r = k.rgba[0];
    v.color.g = k.rgba[1];
    v.color.b = k.rgba[2];
    v.color.a = k.rgba[3];
    v.text = k.text;
    r.markers.push_back(v);
  }
  return r;
}

std::string FromRos(const rosgraph_msgs::Clock& r, ClockTick* m) {
  m->clock = FromRosTime(r.clock);
  return {};
}

}  // namespace rotorguard::ros1::internal
