#include "rotorguard/benchmarks/fdd_calibration.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "rotorguard/core/error.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/json_archive.h"
#include "rotorguard/io/yaml_writer.h"
#include "rotorguard/record/sensor_log.h"
#include "rotorguard/stack/estimator.h"

namespace rotorguard::benchmarks {

namespace {

namespace fs = std::filesystem;

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw io::InputFileError(path, fs::exists(path) ? "cannot open" : "no such file");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw io::InputFileError(path, fmt::format("not valid JSON: {}", e.what()));
  }
}

double FirstOnset(const CalibrationLog& log) {
  double onset = std::numeric_limits<double>::infinity();
  for (const harness::FaultRecord& f : log.faults) onset = std::min(onset, f.onset_s);
  return onset;
}

/// The scored replay of one log for one set of thresholds.
struct Scored {
  ReplayOutcome outcome;
  harness::FddRecord record;
};

Scored ReplayAndScore(const CalibrationLog& log, const fdd::CompositeFddOptions& options) {
  Scored s;
  s.outcome = ReplayCompositeFdd(log, options);
  s.record = harness::ScoreFdd(s.outcome.statuses, FaultEvents(log));  // as the benchmarks score a run (harness/flight_metrics.h)
  return s;
}

struct Sweep {
  const char* name;
  double fdd::CompositeFddOptions::*field;
  double fdd::IndexExtremes::*extreme;  // the statistic it thresholds, at its fault-free extreme
  std::vector<double> values;
  bool alarm_when_low;  // the motor index alarms below its threshold, the others above
};

/// The detector's options with the IMU the log's run read.
fdd::CompositeFddOptions WithLogImu(fdd::CompositeFddOptions options, const CalibrationLog& log) {
  options.imu_rate_hz = log.imu_rate_hz;
  options.imu_position_m = log.imu_position_m;
  return options;
}

}  // namespace

std::vector<sim::FaultEvent> FaultEvents(const CalibrationLog& log) {
  std::vector<sim::FaultEvent> events;
  for (const harness::FaultRecord& f : log.faults) {
    events.push_back({f.rotor, vehicle::ParseFaultKind(f.kind).value_or(vehicle::FaultKind::kNone), f.onset_s});
  }
  return events;
}

CalibrationLog LoadCalibrationLog(const std::string& dir) {
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (status.type() == fs::file_type::not_found) throw io::InputFileError(dir, "no such folder");
  if (ec) throw io::InputFileError(dir, ec.message());
  if (status.type() != fs::file_type::directory) throw io::InputFileError(dir, "not a folder; expected a run folder");
  CalibrationLog log;
  log.dir = dir;
  const std::string summary_path = (fs::path(dir) / "summary.json").string();
  const nlohmann::json summary = ReadJson(summary_path);
  try {
    const nlohmann::json& sensors = summary.at("sensors");
    log.imu_rate_hz = sensors.at("imu_rate_hz").get<double>();
    const std::vector<double> p = sensors.at("imu_position_m").get<std::vector<double>>();
    if (p.size() != 3) throw std::runtime_error("sensors.imu_position_m: expected 3 numbers");
    log.imu_position_m = Vector3(p[0], p[1], p[2]);
    for (const nlohmann::json& f : summary.at("faults")) {
      log.faults.push_back({f.at("rotor").get<int>(), f.at("kind").get<std::string>(), f.at("onset_s").get<double>()});
    }
    if (summary.contains("composite_fdd") && !summary["composite_fdd"].is_null()) {
      fdd::CompositeFddOptions recorded;
      io::FromJson(summary["composite_fdd"], &recorded);
      log.recorded_fdd = recorded;
    }
    // The IMU setup must be one the detector accepts.
    WithLogImu(log.recorded_fdd.value_or(fdd::CompositeFddOptions{}), log).Validate();
  } catch (const std::exception& e) {
    throw io::InputFileError(summary_path, fmt::format("not a valid run summary: {}", e.what()));
  }
  const std::string vehicle_path = (fs::path(dir) / "vehicle.yaml").string();
  try {
    log.vehicle = harness::LoadVehicle(vehicle_path);
  } catch (const io::ConfigError& e) {
    // The run's own record of its vehicle: a bad one is a corrupt input, not a user's config.
    throw io::InputFileError(vehicle_path, e.what());
  }
  log.records = record::ReadSensorLog((fs::path(dir) / "sensors.csv").string(), log.vehicle.num_rotors());
  return log;
}

fdd::CompositeFddOptions RecordedFddOptions(const std::vector<CalibrationLog>& logs, std::string* note) {
  const CalibrationLog* first = nullptr;
  for (const CalibrationLog& log : logs) {
    if (!log.recorded_fdd) continue;
    if (!first) {
      first = &log;
    } else if (io::ToJson(*log.recorded_fdd) != io::ToJson(*first->recorded_fdd)) {
      if (note) {
        *note = fmt::format("{} and {} were flown with different FDD settings; all are replayed with those of {}",
                            first->dir, log.dir, first->dir);
      }
      break;
    }
  }
  return first ? *first->recorded_fdd : fdd::CompositeFddOptions{};
}

ReplayOutcome ReplayCompositeFdd(const CalibrationLog& log, const fdd::CompositeFddOptions& options) {
  fdd::CompositeFdd detector(log.vehicle, WithLogImu(options, log));
  // The stack's estimator, fed as the stack fed it: the estimate the detector saw.
  stack::OdometryImuEstimator estimator(log.vehicle.thrust_coefficient_n_s2);
  const double onset = FirstOnset(log);
  ReplayOutcome out;
  for (const record::SensorRecord& r : log.records) {
    if (const auto* imu = std::get_if<ImuSample>(&r)) {
      estimator.OnImu(*imu);
      detector.OnImu(*imu);
    } else if (const auto* esc = std::get_if<EscTelemetry>(&r)) {
      estimator.OnEscTelemetry(*esc);
      detector.OnEscTelemetry(*esc);
    } else if (const auto* odometry = std::get_if<OdometrySample>(&r)) {
      estimator.OnOdometry(*odometry);
    } else {
      // A control cycle: FlightStack::Update hands the estimate, then the command, to the
      // detector, and neither while the estimate is not valid.
      const RotorCommand& command = std::get<RotorCommand>(r);
      const StateEstimate e = estimator.Estimate(command.t_ns);
      if (e.valid) {
        detector.SetEstimate(e);
        detector.SetCommand(command.thrust_n);
      }
    }
    // Extremes from flight before the fault (the detector itself stops at its first isolation).
    const bool before_onset = ToSeconds(record::RecordTime(r)) < onset;
    if (before_onset) out.extremes = detector.healthy_extremes();
    if (detector.first_isolated_rotor() && !before_onset) break;  // nothing left to learn
  }
  out.isolated_rotor = detector.first_isolated_rotor();
  out.statuses = detector.rotors();
  return out;
}

void FddCalibrationOptions::Validate() const {
  fdd.Validate();
  if (!(margin > 1.0) || !std::isfinite(margin)) ThrowValidation("FddCalibrationOptions", "margin", margin, "> 1");
}

nlohmann::json CalibrateCompositeFdd(const std::vector<CalibrationLog>& logs, const FddCalibrationOptions& options) {
  options.Validate();
  if (logs.empty()) ThrowInvalidArgument("CalibrateCompositeFdd", "logs", "(none)", "at least one run folder");
  // The fault-free extremes: replays with the detectors disarmed, so that no isolation stops the
  // statistics early (a false alarm would otherwise hide how far the indices go).
  fdd::CompositeFddOptions disarmed = options.fdd;
  disarmed.motor_index_threshold = 1e-6;
  disarmed.motor_index_samples = std::numeric_limits<int>::max();
  disarmed.propeller_index_threshold = 1.0;
  disarmed.propeller_persistence_s = 10.0;
  disarmed.takeoff_index_threshold = 1e6;
  fdd::IndexExtremes extremes;  // over all logs
  nlohmann::json log_docs = nlohmann::json::array();
  int faulty_logs = 0;
  for (const CalibrationLog& log : logs) {
    const ReplayOutcome e = ReplayCompositeFdd(log, disarmed);
    extremes.Merge(e.extremes);
    const Scored recorded = ReplayAndScore(log, options.fdd);
    nlohmann::json fault = nullptr;
    if (!log.faults.empty()) {
      ++faulty_logs;
      fault = {{"rotor", log.faults.front().rotor}, {"kind", log.faults.front().kind},
               {"onset_s", log.faults.front().onset_s}};
    }
    log_docs.push_back({{"dir", log.dir},
                        {"faulty", !log.faults.empty()},
                        {"fault", fault},
                        {"with_configured_thresholds",
                         {{"detected", recorded.record.detected()},
                          {"correct", recorded.record.correct},
                          {"false_alarm", recorded.record.false_alarm},
                          {"latency_s", recorded.record.latency_s ? nlohmann::json(*recorded.record.latency_s)
                                                                  : nlohmann::json(nullptr)}}}});
  }
  const std::vector<Sweep> sweeps = {
      {"motor_index_threshold",
       &fdd::CompositeFddOptions::motor_index_threshold,
       &fdd::IndexExtremes::min_motor_index,
       {0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99},
       true},
      {"propeller_index_threshold",
       &fdd::CompositeFddOptions::propeller_index_threshold,
       &fdd::IndexExtremes::max_propeller_index,
       {0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0},
       false},
      {"takeoff_index_threshold",
       &fdd::CompositeFddOptions::takeoff_index_threshold,
       &fdd::IndexExtremes::max_takeoff_index,
       {0.02, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.47, 0.6, 0.8, 1.0, 1.2, 1.5},
       false},
  };
  nlohmann::json sweep_docs = nlohmann::json::array();
  for (const Sweep& sw : sweeps) {
    const double extreme = extremes.*sw.extreme;
    // An index no fault-free flight moved (the motor index stays 1, the others 0) gives no margin.
    const bool exercised = sw.alarm_when_low ? extreme < 1.0 : extreme > 0.0;
    nlohmann::json rows = nlohmann::json::array();
    std::optional<std::size_t> best;
    double best_latency = std::numeric_limits<double>::infinity();
    for (double value : sw.values) {
      fdd::CompositeFddOptions o = options.fdd;
      o.*sw.field = value;
      try {
        o.Validate();
      } catch (const ValidationError&) {
        continue;  // not allowed with the other thresholds (gamma_P must exceed the degraded threshold)
      }
      int detected = 0, missed = 0, false_alarms = 0;
      std::vector<double> latencies;
      for (const CalibrationLog& log : logs) {
        const Scored s = ReplayAndScore(log, o);
        false_alarms += s.record.false_alarm ? 1 : 0;
        if (log.faults.empty()) continue;
        // Missed: no correct diagnosis within 1 s of the onset (docs/metrics.md, MDR).
        if (s.record.latency_s && *s.record.latency_s <= 1.0) {
          ++detected;
          latencies.push_back(*s.record.latency_s);
        } else {
          ++missed;
        }
      }
      // Margin: how far the threshold sits beyond the most alarming fault-free value.
      double margin = std::numeric_limits<double>::quiet_NaN();
      if (exercised) margin = sw.alarm_when_low ? extreme / value : value / extreme;
      double mean = std::numeric_limits<double>::quiet_NaN(), max = mean;
      if (!latencies.empty()) {
        mean = 0.0;
        for (double l : latencies) mean += l;
        mean /= static_cast<double>(latencies.size());
        max = *std::max_element(latencies.begin(), latencies.end());
      }
      const auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
      rows.push_back({{"value", value},
                      {"detected", detected},
                      {"missed", missed},
                      {"false_alarms", false_alarms},
                      {"latency_s_mean", finite_or_null(mean)},
                      {"latency_s_max", finite_or_null(max)},
                      {"margin", finite_or_null(margin)}});
      // Suggested: the fastest value with the margin, no false alarm and no miss; ties go to the
      // value with the larger margin (earlier in the list for the motor index, later otherwise).
      const bool acceptable = std::isfinite(margin) && margin >= options.margin && false_alarms == 0 && missed == 0 && !latencies.empty();
      const bool tie_with_larger_margin = !sw.alarm_when_low && std::abs(mean - best_latency) <= 1e-9;
      if (acceptable && (mean < best_latency - 1e-9 || tie_with_larger_margin)) {
        best_latency = mean;
        best = rows.size() - 1;
      }
    }
    nlohmann::json doc = {{"threshold", sw.name}, {"configured", options.fdd.*sw.field}, {"rows", rows}};
    if (best) {
      const nlohmann::json& r = rows[*best];
      doc["suggested"] = {{"value", r["value"]}, {"margin", r["margin"]}, {"latency_s_mean", r["latency_s_mean"]}};
      doc["note"] = fmt::format("{} = {:g}: {:.2f}x beyond the fault-free extreme {:.3g}, mean latency {:.3f} s over {} faulty logs",
                                sw.name, r["value"].get<double>(), r["margin"].get<double>(), extreme,
                                r["latency_s_mean"].get<double>(), faulty_logs);
    } else {
      doc["suggested"] = nullptr;
      doc["note"] = faulty_logs == 0 ? std::string("no faulty logs: latency cannot be measured (add runs with faults)")
                    : !exercised
                        ? std::string("no fault-free flight exercised this index (a take-off, for the take-off "
                                      "detector): no margin can be stated")
                        : fmt::format("no value keeps a {:g}x margin with no miss and no false alarm; add flights "
                                      "or relax --margin",
                                      options.margin);
    }
    sweep_docs.push_back(doc);
  }
  return {{"logs", log_docs},
          {"margin_required", options.margin},
          {"fault_free_extremes",
           {{"min_motor_index", extremes.min_motor_index < 1.0 ? nlohmann::json(extremes.min_motor_index) : nullptr},
            {"max_propeller_index",
             extremes.max_propeller_index > 0.0 ? nlohmann::json(extremes.max_propeller_index) : nullptr},
            {"max_takeoff_index",
             extremes.max_takeoff_index > 0.0 ? nlohmann::json(extremes.max_takeoff_index) : nullptr}}},
          {"sweeps", sweep_docs}};
}

std::string CalibrationMarkdown(const nlohmann::json& c) {
  std::string out;
  auto it = std::back_inserter(out);
  int faulty = 0;
  for (const auto& l : c["logs"]) faulty += l["faulty"].get<bool>() ? 1 : 0;
  const auto& x = c["fault_free_extremes"];
  fmt::format_to(it, "FDD threshold calibration: {} logs ({} faulty, {} fault-free)\n\n", c["logs"].size(), faulty,
                 c["logs"].size() - static_cast<std::size_t>(faulty));
  const auto num = [](const nlohmann::json& v, const char* f) {
    return v.is_null() ? std::string("/") : fmt::format(fmt::runtime(f), v.get<double>());
  };
  fmt::format_to(it, "Fault-free extremes (/: not exercised): min M_i {}, max P_i {}, max take-off index {}\n",
                 num(x["min_motor_index"], "{:.3f}"), num(x["max_propeller_index"], "{:.3f}"),
                 num(x["max_takeoff_index"], "{:.3f}"));
  for (const auto& sw : c["sweeps"]) {
    fmt::format_to(it, "\n### {} (configured {:g})\n\n", sw["threshold"].get<std::string>(), sw["configured"].get<double>());
    fmt::format_to(it, "| value | detected | missed | false alarms | latency mean (s) | latency max (s) | margin |\n");
    fmt::format_to(it, "|---|---|---|---|---|---|---|\n");
    for (const auto& r : sw["rows"]) {
      fmt::format_to(it, "| {:g} | {} | {} | {} | {} | {} | {} |\n", r["value"].get<double>(), r["detected"].get<int>(),
                     r["missed"].get<int>(), r["false_alarms"].get<int>(), num(r["latency_s_mean"], "{:.3f}"),
                     num(r["latency_s_max"], "{:.3f}"), num(r["margin"], "{:.2f}x"));
    }
    fmt::format_to(it, "\n{}: {}\n", sw["suggested"].is_null() ? "No suggestion" : "Suggested", sw["note"].get<std::string>());
  }
  return out;
}

std::string CalibratedFddYaml(const nlohmann::json& calibration, fdd::CompositeFddOptions base) {
  std::string applied;
  for (const auto& sw : calibration.at("sweeps")) {
    if (sw["suggested"].is_null()) continue;
    const std::string name = sw["threshold"];
    const double value = sw["suggested"]["value"];
    if (name == "motor_index_threshold") base.motor_index_threshold = value;
    if (name == "propeller_index_threshold") base.propeller_index_threshold = value;
    if (name == "takeoff_index_threshold") base.takeoff_index_threshold = value;
    applied += fmt::format("#   {}\n", sw["note"].get<std::string>());
  }
  base.Validate();
  io::YamlWriter writer;
  base.Serialize(&writer);
  int faulty = 0;
  for (const auto& log : calibration.at("logs")) faulty += log["faulty"].get<bool>() ? 1 : 0;
  std::string keys = writer.text();
  if (!keys.empty() && keys.back() != '\n') keys += '\n';
  return fmt::format(
      "# Composite FDD thresholds written by rotorguard fdd-calibrate from {} logs ({} faulty); name this\n"
      "# file from the vehicle file with `fdd: FILE` (docs/fdd.md). Suggested values applied:\n{}{}",
      calibration.at("logs").size(), faulty, applied.empty() ? "#   none\n" : applied, keys);
}

}  // namespace rotorguard::benchmarks
