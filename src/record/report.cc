#include "rotorguard/record/report.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "rotorguard/core/error.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/report_html.h"

namespace rotorguard::record {

namespace {

/// Decimal places kept per column: enough for millimetres, milliradians and a tenth of a
/// percent of an index, far below what a plot or a replay can show.
int DecimalsOf(const std::string& column) {
  if (column.rfind("rpm_", 0) == 0) return 0;
  if (column == "t") return 4;
  if (column.rfind("fault_", 0) == 0 || column.rfind("health_", 0) == 0 || column == "landed") return 0;
  return 4;
}

double Round(double v, int decimals) {
  // Beyond 2^53 a double has no decimals to round, and v * scale could overflow to inf.
  if (!(std::abs(v) < 0x1p53)) return v;
  const double scale = std::pow(10.0, decimals);
  const double r = std::round(v * scale) / scale;
  return r == 0.0 ? 0.0 : r;  // no "-0"
}

}  // namespace

nlohmann::json FlightReportData(const FlightLog& log, const FlightReportOptions& options) {
  if (!(options.max_rate_hz > 0.0)) ThrowInvalidArgument("FlightReportData", "max_rate_hz", options.max_rate_hz, "> 0");
  if (options.max_rows < 2) ThrowInvalidArgument("FlightReportData", "max_rows", options.max_rows, ">= 2");
  const io::NumericTable& table = log.table;
  const std::vector<double>& t = table.Column("t");
  const std::size_t rows = table.rows();
  std::size_t stride = 1;
  if (rows >= 2) {
    const double rate = static_cast<double>(rows - 1) / std::max(t.back() - t.front(), 1e-9);
    stride = std::max<std::size_t>(static_cast<std::size_t>(std::ceil(rate / options.max_rate_hz - 1e-9)),
                                   (rows + static_cast<std::size_t>(options.max_rows) - 1) / static_cast<std::size_t>(options.max_rows));
    stride = std::max<std::size_t>(stride, 1);
  }
  std::vector<std::size_t> picked;
  for (std::size_t r = 0; r < rows; r += stride) picked.push_back(r);
  if (rows > 0 && picked.back() != rows - 1) picked.push_back(rows - 1);  // the final state (or the crash)

  nlohmann::json series = nlohmann::json::object();
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    const int decimals = DecimalsOf(table.columns[c]);
    nlohmann::json column = nlohmann::json::array();
    for (const std::size_t r : picked) column.push_back(Round(table.values[c][r], decimals));
    series[table.columns[c]] = std::move(column);
  }
  nlohmann::json data;
  data["kind"] = "flight";
  data["format"] = 1;
  // A summary read back may hold anything under a key (found by fuzzing: an object as "scenario").
  const auto scenario = log.summary.find("scenario");
  data["title"] = scenario != log.summary.end() && scenario->is_string() ? scenario->get<std::string>() : "flight";
  data["summary"] = log.summary;
  data["scene"] = log.scene;
  data["series"] = std::move(series);
  return data;
}

void WriteFlightReport(const FlightLog& log, const std::string& path, const FlightReportOptions& options) {
  const nlohmann::json data = FlightReportData(log, options);
  io::WriteFileAtomically(path, io::RenderReportHtml(fmt::format("rotorguard: {}", data["title"].get<std::string>()), data));
}

void WriteBenchReport(std::string_view name, const nlohmann::json& result, const std::string& path) {
  nlohmann::json data;
  data["kind"] = "bench";
  data["format"] = 1;
  data["title"] = fmt::format("bench {}", name);
  data["bench"] = std::string(name);
  data["result"] = result;
  io::WriteFileAtomically(path, io::RenderReportHtml(fmt::format("rotorguard: {}", data["title"].get<std::string>()), data));
}

}  // namespace rotorguard::record
