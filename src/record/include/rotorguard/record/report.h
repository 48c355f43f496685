#pragma once
/// Reports: the pages io::RenderReportHtml writes for a flight (header, 3D replay, the paper-style
/// plots) and for a benchmark (its tables and distributions). docs/report.md shows both.
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "rotorguard/record/flight_log.h"

namespace rotorguard::record {

struct FlightReportOptions {
  /// The log is thinned to at most this many rows per second and `max_rows` rows in all, so that
  /// a long flight's page stays small (a 60 s flight: 1.7-2.4 MB with the bundle,
  /// docs/report.md).
  double max_rate_hz = 50.0;  ///< > 0
  int max_rows = 6000;        ///< >= 2
};

/// What the viewer draws for a flight (kind "flight"; docs/report.md, "Files"): the summary, the
/// scene and the log's columns thinned and rounded.
nlohmann::json FlightReportData(const FlightLog& log, const FlightReportOptions& options = {});

/// Writes report.html for a flight atomically. Throws std::runtime_error when the program has no
/// viewer (io::HasViewer) or the file cannot be written.
void WriteFlightReport(const FlightLog& log, const std::string& path, const FlightReportOptions& options = {});

/// Writes the page of a benchmark's result (kind "bench"): `result` is the JSON that
/// `rotorguard bench NAME --json` prints.
void WriteBenchReport(std::string_view name, const nlohmann::json& result, const std::string& path);

}  // namespace rotorguard::record
