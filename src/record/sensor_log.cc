#include "rotorguard/record/sensor_log.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <sstream>

#include <fmt/format.h>

#include "rotorguard/io/config_node.h"

namespace rotorguard::record {

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
    int kind = 0, expected = 0;  // kind: the message's index in SensorRecord
    if (type == "imu") {
      kind = 0;
      expected = 6;
    } else if (type == "esc") {
      kind = 1;
      expected = num_rotors;
    } else if (type == "odom") {
      kind = 2;
      expected = 10;
    } else if (type == "cmd") {
      kind = 3;
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
    if (t < last_t[kind]) {
      fail(fmt::format("{} time stamp {} ns is before the previous one ({} ns)", type, t, last_t[kind]));
    }
    last_t[kind] = t;
    const Eigen::Map<const Eigen::VectorXd> vv(values.data(), static_cast<Eigen::Index>(values.size()));
    switch (kind) {
      case 0:
        records.emplace_back(ImuSample{t, vv.head<3>(), vv.tail<3>()});
        break;
      case 1:
        records.emplace_back(EscTelemetry{t, vv});
        break;
      case 2:
        records.emplace_back(OdometrySample{t, vv.head<3>(), Quaternion(vv[3], vv[4], vv[5], vv[6]), vv.segment<3>(7)});
        break;
      default:
        records.emplace_back(RotorCommand{t, vv});
        break;
    }
    offset = end + 1;
  }
  if (line_no == 0) throw io::InputFileError(path, "line 1 (byte 0): empty file; expected the sensor log header");
  return records;
}

}  // namespace rotorguard::record
