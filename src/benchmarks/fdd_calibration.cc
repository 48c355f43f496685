#include "rotorguard/benchmarks/fdd_calibration.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "rotorguard/campaign_kinds/scenario_sweep.h"
#include "rotorguard/campaign/merge.h"
#include "rotorguard/core/error.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/json_archive.h"
#include "rotorguard/io/json_file.h"
#include "rotorguard/io/yaml_writer.h"
#include "rotorguard/record/sensor_log.h"
#include "rotorguard/stack/estimator.h"

namespace rotorguard::benchmarks {

namespace {

namespace fs = std::filesystem;

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

/// Did fault-free flight move this statistic from where every flight starts it (IndexExtremes'
/// defaults: the motor index at 1, the others at 0)?
bool Moved(const fdd::IndexExtremes& e, double fdd::IndexExtremes::*member) {
  return e.*member != fdd::IndexExtremes{}.*member;
}

struct Sweep {
  const char* name;
  double fdd::CompositeFddOptions::*field;
  double fdd::IndexExtremes::*statistic;  // what the rule compares with the threshold
  double fdd::IndexExtremes::*raw;        // the index itself: did fault-free flight move it at all?
  std::vector<double> values;
  bool alarm_when_low;  // the motor index alarms at or below its threshold, the others above

  /// Would the rule fire at `value` on a flight with these statistics?
  bool Alarms(const fdd::IndexExtremes& e, double value) const {
    return alarm_when_low ? e.*statistic <= value : e.*statistic > value;
  }
  bool Exercised(const fdd::IndexExtremes& e) const { return Moved(e, raw); }
  /// How far `value` sits beyond the statistic's extreme; infinite when the rule's statistic never
  /// moved (no sample passed the take-off gates, say).
  double Margin(const fdd::IndexExtremes& e, double value) const {
    if (!Moved(e, statistic)) return std::numeric_limits<double>::infinity();
    return alarm_when_low ? e.*statistic / value : value / e.*statistic;
  }
};

/// The detector's options with the IMU the log's run read and the command delay it expected.
fdd::CompositeFddOptions WithLogImu(fdd::CompositeFddOptions options, const CalibrationLog& log) {
  options.imu_rate_hz = log.imu_rate_hz;
  options.imu_position_m = log.imu_position_m;
  options.command_delay_s = log.command_delay_s;
  options.imu_notch = log.imu_notch;
  return options;
}

}  // namespace

std::vector<sim::FaultEvent> FaultEvents(const CalibrationLog& log) {
  std::vector<sim::FaultEvent> events;
  for (const harness::FaultRecord& f : log.faults) {
    events.push_back({f.rotor, FromName<vehicle::FaultKind>(f.kind).value_or(vehicle::FaultKind::kNone), f.onset_s});
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
  const nlohmann::json summary = io::ReadJsonObject(summary_path);
  try {
    const nlohmann::json& sensors = summary.at("sensors");
    log.imu_rate_hz = sensors.at("imu_rate_hz").get<double>();
    const std::vector<double> p = sensors.at("imu_position_m").get<std::vector<double>>();
    if (p.size() != 3) throw std::runtime_error("sensors.imu_position_m: expected 3 numbers");
    log.imu_position_m = Vector3(p[0], p[1], p[2]);
    if (sensors.contains("command_delay_s")) log.command_delay_s = sensors.at("command_delay_s").get<double>();
    if (sensors.contains("imu_notch")) io::FromJson(sensors.at("imu_notch"), &log.imu_notch);
    log.imu_notch.sample_rate_hz = log.imu_rate_hz;
    log.imu_notch.Validate();
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

CampaignFlights LoadCampaignFlights(const std::string& dir) {
  nlohmann::json manifest;
  const std::vector<nlohmann::json> records = campaign::ReadCampaignRecords({dir}, &manifest);
  std::vector<std::string> needed = {"fdd.false_alarm"};
  for (const auto& [name, member] : fdd::kIndexExtremesFields)
    needed.push_back("fdd.healthy_extremes." + std::string(name));
  std::vector<std::string> recorded;
  for (const nlohmann::json& m : manifest.value("metrics", nlohmann::json::array())) {
    if (m.is_string()) recorded.push_back(m.get<std::string>());
  }
  for (const std::string& m : needed) {
    if (std::find(recorded.begin(), recorded.end(), m) == recorded.end()) {
      throw io::InputFileError(dir, fmt::format("the campaign does not record the metric '{}'; fdd-calibrate needs "
                                                "{} in its spec's metrics: list",
                                                m, fmt::join(needed, ", ")));
    }
  }
  CampaignFlights out;
  out.dir = dir;
  // The manifest's name and seed, for the record of the seeds used (a bad one is a corrupt input).
  if (manifest.contains("campaign")) {
    if (!manifest["campaign"].is_string())
      throw io::InputFileError(dir, "manifest.json: 'campaign' is not a string; expected the campaign's name");
    out.campaign = manifest["campaign"].get<std::string>();
  }
  if (manifest.contains("seed")) {
    if (!manifest["seed"].is_number_unsigned())
      throw io::InputFileError(dir, "manifest.json: 'seed' is not an unsigned integer; expected the campaign's seed");
    out.seed = manifest["seed"].get<std::uint64_t>();
  }
  for (const nlohmann::json& r : records) {
    // ReadCampaignRecords checked each record's fields and their types; the metrics are the kind's.
    const int trial = r.at("trial").get<int>();
    if (r.at("status") != "ok") {
      throw io::InputFileError(dir, fmt::format("trial {} did not finish ({}: {}); every flight must count", trial,
                                                r["status"].get<std::string>(), r.value("message", "")));
    }
    const nlohmann::json& metrics = r.at("metrics");
    const auto metric = [&metrics](const std::string& key) {
      return metrics.is_object() && metrics.contains(key) ? metrics.at(key) : nlohmann::json();
    };
    FlightExtremes f;
    for (const auto& [name, member] : fdd::kIndexExtremesFields) {
      const nlohmann::json v = metric("fdd.healthy_extremes." + std::string(name));
      if (!v.is_number()) {
        throw io::InputFileError(dir, fmt::format("trial {} has no fdd.healthy_extremes.{} (flown without the "
                                                  "composite FDD? set stack.fdd: composite)",
                                                  trial, name));
      }
      f.extremes.*member = v.get<double>();
    }
    const nlohmann::json alarm = metric("fdd.false_alarm");
    if (!alarm.is_boolean())
      throw io::InputFileError(dir, fmt::format("trial {}: fdd.false_alarm is not a boolean", trial));
    f.false_alarm = alarm.get<bool>();
    out.flights.push_back(f);
    const nlohmann::json& params = r.at("params");
    if (params.contains("seed") && params.at("seed").is_string()) {
      try {
        out.trial_seeds.push_back(std::stoull(params.at("seed").get<std::string>()));
      } catch (const std::exception&) {
        throw io::InputFileError(dir, fmt::format("trial {}: its seed '{}' is not an unsigned integer", trial,
                                                  params.at("seed").get<std::string>()));
      }
    }
  }
  return out;
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
  RpmNotchBank<6> imu_filter(log.vehicle.num_rotors(), log.imu_notch);  // as the stack filtered
  // The stack's estimator, fed as the stack fed it: the estimate the detector saw.
  stack::OdometryImuEstimator estimator(log.vehicle.thrust_coefficient_n_s2);
  const double onset = FirstOnset(log);
  ReplayOutcome out;
  // Records are in delivery order, so a sensor's delay can bring a sample stamped before the onset
  // after one stamped at it: fault-free flight ends at the first record stamped at the onset.
  bool before_onset = true;
  for (const record::SensorRecord& r : log.records) {
    if (const auto* raw = std::get_if<ImuSample>(&r)) {
      // As the stack does: the estimator integrates the raw samples, the detector reads them notched.
      estimator.OnImu(*raw);
      Eigen::Matrix<double, 6, 1> x;
      x << raw->specific_force_B, raw->w_B;
      const Eigen::Matrix<double, 6, 1> y = imu_filter.Filter(x);
      ImuSample imu = *raw;
      imu.specific_force_B = y.head<3>();
      imu.w_B = y.tail<3>();
      detector.OnImu(imu);
    } else if (const auto* esc = std::get_if<EscTelemetry>(&r)) {
      imu_filter.OnRotorSpeeds(esc->t_ns, esc->motor_speed_rad_s);
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
        detector.SetCommand(command);
      }
    }
    // Extremes from flight before the fault (the detector itself stops at its first isolation).
    before_onset = before_onset && ToSeconds(record::RecordTime(r)) < onset;
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

nlohmann::json CalibrateCompositeFdd(const std::vector<CalibrationLog>& logs,
                                     const std::vector<CampaignFlights>& campaigns,
                                     const FddCalibrationOptions& options) {
  options.Validate();
  std::size_t campaign_flights = 0;
  for (const CampaignFlights& c : campaigns) campaign_flights += c.flights.size();
  if (logs.empty() && campaign_flights == 0) {
    ThrowInvalidArgument("CalibrateCompositeFdd", "logs", "(none)", "at least one run folder or campaign flight");
  }
  // The fault-free extremes of the logs: replays with the thresholds out of reach, so that no
  // isolation stops the statistics early (a false alarm would otherwise hide how far the indices go).
  const fdd::CompositeFddOptions disarmed = options.fdd.Disarmed();
  fdd::IndexExtremes extremes;  // over all logs and campaign flights
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
  nlohmann::json campaign_docs = nlohmann::json::array();
  for (const CampaignFlights& c : campaigns) {
    int alarms = 0;
    for (const FlightExtremes& f : c.flights) {
      extremes.Merge(f.extremes);
      alarms += f.false_alarm ? 1 : 0;
    }
    // The seeds it used, so that an evaluation set can be shown to share no vehicle with it.
    campaign_docs.push_back({{"dir", c.dir},
                             {"campaign", c.campaign},
                             {"seed", c.seed},
                             {"seed_stream", CampaignSeedStream(c.campaign)},
                             {"trial_seeds", c.trial_seeds},
                             {"flights", c.flights.size()},
                             {"false_alarms", alarms}});
  }
  const std::vector<Sweep> sweeps = {
      {"motor_index_threshold",
       &fdd::CompositeFddOptions::motor_index_threshold,
       &fdd::IndexExtremes::debounced_motor_index,
       &fdd::IndexExtremes::min_motor_index,
       {0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99},
       true},
      {"propeller_index_threshold",
       &fdd::CompositeFddOptions::propeller_index_threshold,
       &fdd::IndexExtremes::persistent_propeller_index,
       &fdd::IndexExtremes::max_propeller_index,
       {0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0},
       false},
      {"takeoff_index_threshold",
       &fdd::CompositeFddOptions::takeoff_index_threshold,
       &fdd::IndexExtremes::gated_takeoff_index,
       &fdd::IndexExtremes::max_takeoff_index,
       {0.02, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.47, 0.6, 0.8, 1.0, 1.2, 1.5},
       false},
      // The shortfall rule's statistic is its own index, debounced (no gates to pass).
      {"motor_shortfall_threshold",
       &fdd::CompositeFddOptions::motor_shortfall_threshold,
       &fdd::IndexExtremes::debounced_motor_shortfall,
       &fdd::IndexExtremes::debounced_motor_shortfall,
       {0.02, 0.03, 0.04, 0.05, 0.07, 0.1, 0.15, 0.2, 0.3, 0.5},
       false},
  };
  const auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json sweep_docs = nlohmann::json::array();
  for (const Sweep& sw : sweeps) {
    // An index no fault-free flight moved (the motor index stays 1, the others 0) gives no margin.
    const bool exercised = sw.Exercised(extremes);
    nlohmann::json rows = nlohmann::json::array();
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
      // A campaign flight alarms at this value when the rule's statistic passes it: the statistic is
      // exactly what the rule compares. (Each threshold answers for its own rule's alarms; a flight
      // that alarmed as flown has statistics up to that alarm only, which "campaigns" counts.)
      for (const CampaignFlights& c : campaigns) {
        for (const FlightExtremes& f : c.flights) false_alarms += sw.Alarms(f.extremes, value) ? 1 : 0;
      }
      const double margin = exercised ? sw.Margin(extremes, value) : std::numeric_limits<double>::quiet_NaN();
      double mean = std::numeric_limits<double>::quiet_NaN(), max = mean;
      if (!latencies.empty()) {
        mean = 0.0;
        for (double l : latencies) mean += l;
        mean /= static_cast<double>(latencies.size());
        max = *std::max_element(latencies.begin(), latencies.end());
      }
      rows.push_back({{"value", value},
                      {"detected", detected},
                      {"missed", missed},
                      {"false_alarms", false_alarms},
                      {"latency_s_mean", finite_or_null(mean)},
                      {"latency_s_max", finite_or_null(max)},
                      {"margin", finite_or_null(margin)}});
    }
    // Suggested: the fastest value with the margin, no false alarm and no more misses than the
    // fewest of any value (a fault another detector misdiagnoses is missed at every value); ties go
    // to the value with the larger margin (earlier in the list for the motor index, later otherwise).
    int fewest_missed = std::numeric_limits<int>::max();
    for (const auto& r : rows) fewest_missed = std::min(fewest_missed, r["missed"].get<int>());
    std::optional<std::size_t> best, fastest_clear;
    double best_latency = std::numeric_limits<double>::infinity(), clear_latency = best_latency;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const nlohmann::json& r = rows[i];
      if (r["false_alarms"].get<int>() > 0 || r["missed"].get<int>() > fewest_missed || r["latency_s_mean"].is_null()) {
        continue;
      }
      const double mean = r["latency_s_mean"].get<double>();
      if (mean < clear_latency - 1e-9) {
        clear_latency = mean;
        fastest_clear = i;
      }
      // An unbounded margin (the rule's gates held in every fault-free flight) bounds nothing: no
      // suggestion rests on it.
      const bool tie_with_larger_margin = !sw.alarm_when_low && std::abs(mean - best_latency) <= 1e-9;
      if (r["margin"].is_number() && r["margin"].get<double>() >= options.margin &&
          (mean < best_latency - 1e-9 || tie_with_larger_margin)) {
        best_latency = mean;
        best = i;
      }
    }
    const auto brief = [&](std::optional<std::size_t> row) {
      if (!row) return nlohmann::json(nullptr);
      const nlohmann::json& r = rows[*row];
      return nlohmann::json{{"value", r["value"]}, {"margin", r["margin"]}, {"latency_s_mean", r["latency_s_mean"]}};
    };
    const auto margin_text = [](const nlohmann::json& m) {
      return m.is_null() ? std::string("unbounded") : fmt::format("{:.2f}x", m.get<double>());
    };
    nlohmann::json doc = {{"threshold", sw.name},     {"configured", options.fdd.*sw.field},
                          {"exercised", exercised},   {"rows", rows},
                          {"suggested", brief(best)}, {"fastest_without_alarm", brief(fastest_clear)}};
    if (best) {
      const nlohmann::json& r = rows[*best];
      const nlohmann::json& c = rows[*fastest_clear];  // the suggestion is itself clear
      doc["note"] = fmt::format(
          "{} = {:g}: {} beyond the fault-free extreme {:.3g}, mean latency {:.3f} s over {} faulty logs; "
          "the margin costs {:.3f} s against the fastest value without an alarm ({:g}, {})",
          sw.name, r["value"].get<double>(), margin_text(r["margin"]), extremes.*sw.statistic,
          r["latency_s_mean"].get<double>(), faulty_logs,
          r["latency_s_mean"].get<double>() - c["latency_s_mean"].get<double>(), c["value"].get<double>(),
          margin_text(c["margin"]));
    } else {
      doc["note"] = faulty_logs == 0 ? std::string("no faulty logs: latency cannot be measured (add runs with faults)")
                    : !exercised     ? std::string(
                                           "no fault-free flight exercised this index (a take-off, for the take-off "
                                               "detector): no margin can be stated")
                    : !Moved(extremes, sw.statistic)
                        ? std::string(
                              "the rule's gates held in every fault-free flight (its statistic never moved): "
                              "no margin bounds this threshold; keep the configured value")
                        : fmt::format(
                              "no value keeps a {:g}x margin with no false alarm and the fewest misses; "
                              "add flights or relax --margin",
                              options.margin);
    }
    sweep_docs.push_back(doc);
  }
  // The statistics' extremes; null for one no fault-free flight moved from its neutral value.
  nlohmann::json extremes_doc = nlohmann::json::object();
  for (const auto& [name, member] : fdd::kIndexExtremesFields) {
    extremes_doc[std::string(name)] = Moved(extremes, member) ? nlohmann::json(extremes.*member) : nullptr;
  }
  return {{"logs", log_docs},
          {"campaigns", campaign_docs},
          {"margin_required", options.margin},
          {"fault_free_extremes", extremes_doc},
          {"sweeps", sweep_docs}};
}

std::string CalibrationMarkdown(const nlohmann::json& c) {
  std::string out;
  auto it = std::back_inserter(out);
  int faulty = 0;
  for (const auto& l : c["logs"]) faulty += l["faulty"].get<bool>() ? 1 : 0;
  fmt::format_to(it, "FDD threshold calibration: {} logs ({} faulty, {} fault-free)", c["logs"].size(), faulty,
                 c["logs"].size() - static_cast<std::size_t>(faulty));
  for (const auto& k : c["campaigns"]) {
    fmt::format_to(it, ", {} flights of {} (false alarms as flown: {})", k["flights"].get<int>(),
                   k["dir"].get<std::string>(), k["false_alarms"].get<int>());
  }
  const auto num = [](const nlohmann::json& v, const char* f) {
    return v.is_null() ? std::string("/") : fmt::format(fmt::runtime(f), v.get<double>());
  };
  const auto& x = c["fault_free_extremes"];
  fmt::format_to(it,
                 "\n\nFault-free extremes (/: not moved), each rule's statistic (the index itself):\n"
                 "debounced M_i {} ({}), persistent P_i {} ({}), gated take-off index {} ({}), debounced motor "
                 "shortfall {}\n",
                 num(x["debounced_motor_index"], "{:.3f}"), num(x["min_motor_index"], "{:.3f}"),
                 num(x["persistent_propeller_index"], "{:.3f}"), num(x["max_propeller_index"], "{:.3f}"),
                 num(x["gated_takeoff_index"], "{:.3f}"), num(x["max_takeoff_index"], "{:.3f}"),
                 num(x["debounced_motor_shortfall"], "{:.3f}"));
  for (const auto& sw : c["sweeps"]) {
    fmt::format_to(it, "\n### {} (configured {:g})\n\n", sw["threshold"].get<std::string>(), sw["configured"].get<double>());
    fmt::format_to(it, "| value | detected | missed | false alarms | latency mean (s) | latency max (s) | margin |\n");
    fmt::format_to(it, "|---|---|---|---|---|---|---|\n");
    const bool exercised = sw["exercised"].get<bool>();
    for (const auto& r : sw["rows"]) {
      const std::string margin = !exercised ? "/" : r["margin"].is_null() ? "unbounded" : num(r["margin"], "{:.2f}x");
      fmt::format_to(it, "| {:g} | {} | {} | {} | {} | {} | {} |\n", r["value"].get<double>(), r["detected"].get<int>(),
                     r["missed"].get<int>(), r["false_alarms"].get<int>(), num(r["latency_s_mean"], "{:.3f}"),
                     num(r["latency_s_max"], "{:.3f}"), margin);
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
    if (name == "motor_shortfall_threshold") base.motor_shortfall_threshold = value;
    applied += fmt::format("#   {}\n", sw["note"].get<std::string>());
  }
  base.Validate();
  io::YamlWriter writer;
  base.Serialize(&writer);
  int faulty = 0;
  for (const auto& log : calibration.at("logs")) faulty += log["faulty"].get<bool>() ? 1 : 0;
  int flights = 0;
  for (const auto& k : calibration.at("campaigns")) flights += k["flights"].get<int>();
  std::string keys = writer.text();
  if (!keys.empty() && keys.back() != '\n') keys += '\n';
  return fmt::format(
      "# Composite FDD thresholds written by rotorguard fdd-calibrate from {} logs ({} faulty) and {} campaign\n"
      "# flights; name this file from the vehicle file with `fdd: FILE` (docs/fdd.md). Suggested values\n"
      "# applied:\n{}{}",
      calibration.at("logs").size(), faulty, flights, applied.empty() ? "#   none\n" : applied, keys);
}

}  // namespace rotorguard::benchmarks
