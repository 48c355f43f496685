#include "rotorguard/bench/sensor_log.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <sstream>

#include <fmt/format.h>

#include "rotorguard/io/config_node.h"

namespace rotorguard::bench {

namespace {

void AppendValues(const char* type, TimeNs t, const double* v, int n, std::string* out) {
  auto it = std::back_inserter(*out);
  fmt::format_to(it, "{},{}", type, t);
  for (int i = 0; i < n; ++i) fmt::format_to(it, ",{}", v[i]);
  out->push_back('\n');
}

}  // namespace

void AppendImu(const ImuSample& m, std::string* out) {
  const double v[6] = {m.specific_force_B.x(), m.specific_force_B.y(), m.specific_force_B.z(),
                       m.w_B.x(),              m.w_B.y(),              m.w_B.z()};
  AppendValues("imu", m.t_ns, v, 6, out);
}

void AppendEsc(const EscTelemetry& m, std::string* out) {
  AppendValues("esc", m.t_ns, m.motor_speed_rad_s.data(), static_cast<int>(m.motor_speed_rad_s.size()), out);
}

void AppendOdometry(const OdometrySample& m, std::string* out) {
  const double v[10] = {m.p_W.x(),   m.p_W.y(),   m.p_W.z(),   m.q_WB.w(), m.q_WB.x(),
                        m.q_WB.y(),  m.q_WB.z(),  m.v_W.x(),   m.v_W.y(),  m.v_W.z()};
  AppendValues("odom", m.t_ns, v, 10, out);
}

void AppendCommand(const RotorCommand& m, std::string* out) {
  AppendValues("cmd", m.t_ns, m.thrust_n.data(), static_cast<int>(m.thrust_n.size()), out);
}

std::vector<SensorRecord> ReadSensorLog(const std::string& path, int num_rotors) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw io::InputFileError(path, "cannot open");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw io::InputFileError(path, "read error");
  std::vector<SensorRecord> records;
  std::size_t offset = 0;
  int line_no = 0;
  TimeNs last_t[4] = {INT64_MIN, INT64_MIN, INT64_MIN, INT64_MIN};
  std::vector<double> values;
  while (offset < text.size()) {
    ++line_no;
    const std::size_t end = text.find('\n', offset);
    const auto fail = [&](const std::string& why) {
      throw io::InputFileError(path, fmt::format("line {} (byte {}): {}", line_no, offset, why));
    };
    if (end == std::string::npos) fail("truncated: the last line has no end of line");
    const std::string_view line(text.data() + offset, end - offset);
    if (line_no == 1) {
      if (std::string(line) + "\n" != kSensorLogHeader) {
        fail(fmt::format("expected the header '{}'", kSensorLogHeader.substr(0, kSensorLogHeader.size() - 1)));
      }
      offset = end + 1;
      continue;
    }
    const std::size_t comma = line.find(',');
    if (comma == std::string_view::npos) fail("expected type,t_ns,values");
    const std::string_view type = line.substr(0, comma);
    SensorRecord r;
    int expected = 0;
    if (type == "imu") {
      r.type = SensorRecord::Type::kImu;
      expected = 6;
    } else if (type == "esc") {
      r.type = SensorRecord::Type::kEsc;
      expected = num_rotors;
    } else if (type == "odom") {
      r.type = SensorRecord::Type::kOdometry;
      expected = 10;
    } else if (type == "cmd") {
      r.type = SensorRecord::Type::kCommand;
      expected = num_rotors;
    } else {
      fail(fmt::format("unknown message type '{}'; expected imu, esc, odom or cmd", type));
    }
    // Time stamp, then the numbers.
    std::size_t pos = comma + 1;
    const std::size_t t_end = std::min(line.find(',', pos), line.size());
    TimeNs t = 0;
    {
      const auto [p, ec] = std::from_chars(line.data() + pos, line.data() + t_end, t);
      if (ec != std::errc() || p != line.data() + t_end) fail("t_ns is not an integer");
    }
    values.clear();
    pos = t_end;
    while (pos < line.size()) {
      ++pos;  // the comma
      const std::size_t v_end = std::min(line.find(',', pos), line.size());
      double v = 0.0;
      const auto [p, ec] = std::from_chars(line.data() + pos, line.data() + v_end, v);
      // nan and inf are kept: the stack ignores such messages, and so must a replay.
      if (ec != std::errc() || p != line.data() + v_end) fail(fmt::format("value {} is not a number", values.size() + 1));
      values.push_back(v);
      pos = v_end;
    }
    if (static_cast<int>(values.size()) != expected) {
      fail(fmt::format("{} has {} values; expected {}", type, values.size(), expected));
    }
    const int k = static_cast<int>(r.type);
    if (t < last_t[k]) fail(fmt::format("{} time stamp {} ns is before the previous one ({} ns)", type, t, last_t[k]));
    last_t[k] = t;
    const Eigen::Map<const Eigen::VectorXd> vv(values.data(), static_cast<Eigen::Index>(values.size()));
    switch (r.type) {
      case SensorRecord::Type::kImu:
        r.imu.t_ns = t;
        r.imu.specific_force_B = vv.head<3>();
        r.imu.w_B = vv.tail<3>();
        break;
      case SensorRecord::Type::kEsc:
        r.esc.t_ns = t;
        r.esc.motor_speed_rad_s = vv;
        break;
      case SensorRecord::Type::kOdometry:
        r.odometry.t_ns = t;
        r.odometry.p_W = vv.head<3>();
        r.odometry.q_WB = Quaternion(vv[3], vv[4], vv[5], vv[6]);
        r.odometry.v_W = vv.segment<3>(7);
        break;
      case SensorRecord::Type::kCommand:
        r.command.t_ns = t;
        r.command.thrust_n = vv;
        break;
    }
    records.push_back(std::move(r));
    offset = end + 1;
  }
  if (line_no == 0) throw io::InputFileError(path, "line 1 (byte 0): empty file; expected the sensor log header");
  return records;
}

}  // namespace rotorguard::bench
