#include "rotorguard/record/flight_log.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>

#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/json_file.h"
#include "rotorguard/record/flight_mcap.h"

namespace rotorguard::record {

namespace {

namespace fs = std::filesystem;

}  // namespace

std::vector<std::string> LogColumns(const LogLayout& layout) {
  std::vector<std::string> c = {"t"};
  if (layout.truth) {
    c.insert(c.end(), {"p_x", "p_y", "p_z", "q_w", "q_x", "q_y", "q_z", "v_x", "v_y", "v_z", "w_x", "w_y", "w_z"});
  }
  c.insert(c.end(), {"ref_p_x", "ref_p_y", "ref_p_z", "ref_v_x", "ref_v_y", "ref_v_z", "ref_yaw", "est_p_x", "est_p_y",
                     "est_p_z", "est_q_w", "est_q_x", "est_q_y", "est_q_z", "est_v_x", "est_v_y", "est_v_z", "est_w_x",
                     "est_w_y", "est_w_z"});
  if (layout.truth) c.insert(c.end(), {"wind_x", "wind_y", "wind_z", "landed"});
  c.emplace_back("mode");
  std::vector<const char*> prefixes = {"cmd_"};
  if (layout.truth) prefixes.insert(prefixes.end(), {"thrust_", "rpm_", "fault_"});
  if (layout.fdd) prefixes.insert(prefixes.end(), {"mi_", "pi_", "health_"});
  for (const char* prefix : prefixes) {
    for (int i = 0; i < layout.rotors; ++i) c.push_back(fmt::format("{}{}", prefix, i));
  }
  if (layout.nmpc) c.emplace_back("nmpc_ms");
  if (layout.lio) {
    c.insert(c.end(), {"lio_used", "lio_degenerate", "lio_matched", "lio_residual_rms_m", "lio_weakest_std_m"});
  }
  return c;
}

std::string FormatLogCsv(const io::NumericTable& table) {
  std::string out;
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    out += table.columns[c];
    out.push_back(c + 1 < table.columns.size() ? ',' : '\n');
  }
  auto it = std::back_inserter(out);
  for (std::size_t r = 0; r < table.rows(); ++r) {
    for (std::size_t c = 0; c < table.columns.size(); ++c) {
      fmt::format_to(it, "{:.9g}", table.values[c][r]);
      out.push_back(c + 1 < table.columns.size() ? ',' : '\n');
    }
  }
  return out;
}

void WriteFlightLogFiles(const FlightLog& log, const std::string& dir) {
  io::WriteFileAtomically((fs::path(dir) / "log.csv").string(), FormatLogCsv(log.table));
  io::WriteFileAtomically((fs::path(dir) / "scene.json").string(), log.scene.dump() + "\n");
}

FlightLog ReadFlightLog(const std::string& dir) {
  const fs::path d(dir);
  std::error_code ec;
  if (!fs::is_directory(d, ec)) throw io::InputFileError(dir, fs::exists(d, ec) ? "not a directory" : "no such directory");
  FlightLog log;
  log.summary = io::ReadJsonObject((d / "summary.json").string());
  if (fs::exists(d / "log.csv", ec) || !fs::exists(d / "flight.mcap", ec)) {
    log.table = io::ReadNumericCsv((d / "log.csv").string());
    log.scene = io::ReadJsonObject((d / "scene.json").string());
  } else {
    FlightLog from_mcap = ReadFlightMcap((d / "flight.mcap").string());
    log.table = std::move(from_mcap.table);
    log.scene = std::move(from_mcap.scene);
  }
  if (!log.table.Has("t")) {
    throw io::CorruptFileError((d / "log.csv").string(), 0, "the log has no column 't'");
  }
  return log;
}

}  // namespace rotorguard::record
