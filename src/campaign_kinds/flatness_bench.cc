#include "rotorguard/campaign_kinds/flatness_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/campaign/failure_list.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/planning/flatness.h"

namespace rotorguard::benchmarks {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

nlohmann::json OrNull(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(); }

/// Trial 0, part fig1: the closed forms of Fig. 1 and the facts of the Fig. 2 scenario the tables quote.
nlohmann::json FigureOne(const harness::Scenario& fig2) {
  const vehicle::PwmQuadModel model = vehicle::PwmQuadModel::FromVehicle(fig2.vehicle);
  const planning::FlatnessLimits& limits = fig2.stack.navigation.flatness.limits;
  const Eigen::Vector2d move = (fig2.stack.navigation.waypoints.front() - fig2.initial_position_m).head<2>();
  // The envelope-bound plan (eq. 16) and the actuator-bound plan (eq. 23) of the move.
  planning::FlatnessLimits actuator_only = limits;
  actuator_only.theta_max_rad = actuator_only.phi_max_rad = std::numeric_limits<double>::infinity();
  const planning::SettlingTime plan = planning::PlanSettlingTime(model, limits, move);
  const planning::SettlingTime actuator = planning::PlanSettlingTime(model, actuator_only, move);
  const sim::FaultSpec& fault = fig2.faults.front();
  return {{"ts_envelope_s", plan.envelope_s},
          {"ts_actuator_s", actuator.actuator_s},
          {"ts_plan_s", plan.t_s},
          {"ts_plan_binding", planning::ToString(plan.binding)},
          {"theta_max_deg", limits.theta_max_rad / kDeg},
          {"fault_rotor", fault.rotor},
          {"fault_w", fault.eta},
          {"fault_onset_s", fault.onset.value}};
}

/// A trial of part fig2: the faulty flight, then the same flight without its fault.
campaign::TrialOutcome FlyFigureTwo(harness::Scenario s) {
  const vehicle::PwmQuadModel model = vehicle::PwmQuadModel::FromVehicle(s.vehicle);
  const planning::FlatnessLimits& limits = s.stack.navigation.flatness.limits;
  const int faulty = s.faults.front().rotor;
  const double onset = s.faults.front().onset.value;
  campaign::TrialOutcome out;
  const harness::RunSummary r = harness::RunScenario(s, harness::RunOptions{});
  nlohmann::json& m = out.metrics;
  m["success"] = r.success;
  m["max_tilt_deg"] = r.max_tilt_rad / kDeg;
  m["w_estimate"] = nullptr;
  m["settle_s"] = nullptr;
  if (const std::optional<stack::UkfSummary>& ukf = r.stack.ukf) {
    if (faulty < static_cast<int>(ukf->w_hat.size())) m["w_estimate"] = ukf->w_hat[static_cast<std::size_t>(faulty)];
    if (ukf->settled_s) m["settle_s"] = *ukf->settled_s - onset;
  }
  m["detect_s"] =
      OrNull(r.fdd && r.fdd->diagnosis ? std::optional(r.fdd->diagnosis->detection_s - onset) : std::nullopt);
  m["replanned"] = false;
  for (const planning::FlatnessDecision& d : r.stack.flatness_decisions) {
    if (d.kind != "continue" && d.kind != "return" && d.kind != "land") continue;
    const planning::SettlingTime nominal = planning::PlanSettlingTime(model, limits, d.delta_m.head<2>());
    m["replanned"] = true;
    m["replan_decision"] = d.kind;
    m["replan_binding"] = d.binding;
    m["replan_ts_s"] = d.t_s;
    m["replan_actuator_s"] = d.actuator_s;
    m["replan_nominal_ts_s"] = std::max(nominal.t_s, s.stack.navigation.flatness.min_t_s);
    m["replan_nominal_actuator_s"] = nominal.actuator_s;
  }
  out.message = r.failure_reason.value_or("");
  s.faults.clear();  // the pitch the plan asks for
  m["fault_free_tilt_deg"] = harness::RunScenario(s, harness::RunOptions{}).max_tilt_rad / kDeg;
  return out;
}

}  // namespace

void FlatnessBenchOptions::Validate() const {
  if (trials < 1 || trials > 10000)
    ThrowInvalidArgument("FlatnessBenchOptions", "trials", trials, "a count in [1, 10000]");
  if (jobs < 1 || jobs > 256) ThrowInvalidArgument("FlatnessBenchOptions", "jobs", jobs, "a count in [1, 256]");
  if (fig2.stack.navigation.method != stack::NavigationMethod::kFlatness || fig2.faults.empty() || fig2.stack.navigation.waypoints.empty()) {
    ThrowInvalidArgument("FlatnessBenchOptions", "fig2", fig2.name, "a flatness navigate scenario with a fault");
  }
}

campaign::Campaign FlatnessCampaign(const FlatnessBenchOptions& o) {
  o.Validate();
  campaign::Campaign c;
  c.name = "bench_flatness";
  c.seed = o.seed;
  c.trials = 1 + o.trials;
  c.group_keys = {"part"};
  c.metrics = {"success", "w_estimate", "settle_s", "detect_s", "replanned", "replan_ts_s", "fault_free_tilt_deg"};
  const nlohmann::json options = {
      {"trials", o.trials}, {"seed", o.seed}, {"scenario", o.fig2.name}, {"truth", ToName(o.truth)}};
  c.bench = {{"name", "flatness"}, {"records", 1}, {"options", options}, {"seed_stream", "bench flatness"}};
  c.hash = campaign::Fingerprint(c.bench.dump() + "\n" + harness::ScenarioFingerprint(o.fig2));
  c.parameters = [o](int index) -> std::map<std::string, std::string> {
    if (index == 0) return {{"part", "fig1"}, {"seed", std::to_string(o.seed)}};
    return {{"part", "fig2"},
            {"trial", std::to_string(index - 1)},
            {"seed", std::to_string(TrialSeed(o.seed, "bench flatness", static_cast<std::uint64_t>(index - 1)))}};
  };
  harness::Scenario fig2 = o.fig2;
  fig2.truth.preset = o.truth;
  // Two flights a trial; the closed forms of trial 0 run without a budget.
  c.simulated_s = [fig2](int index, const std::map<std::string, std::string>&) {
    return index == 0 ? 0.0 : 2.0 * fig2.duration_s;
  };
  c.reproduce = [fig2](int, const std::map<std::string, std::string>& params) {
    return fmt::format("rotorguard run {} --seed {} --set truth={}", fig2.file.empty() ? fig2.name : fig2.file,
                       params.at("seed"), ToName(fig2.truth.preset));
  };
  c.run = [fig2](int index, const std::map<std::string, std::string>& params) {
    if (index == 0) return campaign::TrialOutcome{FigureOne(fig2), ""};
    harness::Scenario s = fig2;
    s.seed = std::stoull(params.at("seed"));
    return FlyFigureTwo(std::move(s));
  };
  return c;
}

nlohmann::json FlatnessResult(const nlohmann::json& options, const std::vector<nlohmann::json>& records) {
  const int trials = options.at("trials").get<int>();
  if (records.size() != static_cast<std::size_t>(trials) + 1) {
    throw std::invalid_argument(fmt::format("flatness: {} trial records for 1 + {} trials", records.size(), trials));
  }
  if (records[0].value("status", "") != "ok") {
    throw std::invalid_argument("flatness: Fig. 1's closed forms were not recorded: " +
                                campaign::TrialFailure(records[0]));
  }
  const nlohmann::json& fig1 = records[0].at("metrics");
  std::vector<double> w, settle, detect, ts, ts_nominal, act, act_nominal, tilt, tilt_free;
  int success = 0, replanned = 0;
  std::map<std::string, int> decisions, bindings;
  campaign::FailureList failures(10);
  const double truth = fig1.at("fault_w").get<double>();
  const auto add = [](const nlohmann::json& m, const char* key, std::vector<double>* to) {
    if (m.contains(key) && m.at(key).is_number()) to->push_back(m.at(key).get<double>());
  };
  for (std::size_t i = 1; i < records.size(); ++i) {
    const nlohmann::json& r = records[i];
    const std::string failure = campaign::TrialFailure(r);
    const bool flew = r.value("status", "") == "ok";
    const nlohmann::json& m = r.at("metrics");
    if (flew && m.at("success").get<bool>()) {
      ++success;
    } else {
      failures.Add({{"seed", std::stoull(r.at("params").at("seed").get<std::string>())}, {"reason", failure}});
    }
    if (!flew) continue;
    add(m, "max_tilt_deg", &tilt);
    add(m, "fault_free_tilt_deg", &tilt_free);
    add(m, "w_estimate", &w);
    add(m, "settle_s", &settle);
    add(m, "detect_s", &detect);
    if (!m.at("replanned").get<bool>()) continue;
    ++replanned;
    ++decisions[m.at("replan_decision").get<std::string>()];
    ++bindings[m.at("replan_binding").get<std::string>()];
    add(m, "replan_ts_s", &ts);
    add(m, "replan_nominal_ts_s", &ts_nominal);
    add(m, "replan_actuator_s", &act);
    add(m, "replan_nominal_actuator_s", &act_nominal);
  }
  const auto identified = std::count_if(w.begin(), w.end(), [&](double e) { return std::abs(e - truth) <= 0.05; });
  const auto median = [](const std::vector<double>& v) {
    return v.empty() ? nlohmann::json(nullptr) : nlohmann::json(Percentile(v, 0.5));
  };
  const auto range = [](const std::vector<double>& v) {
    if (v.empty()) return nlohmann::json(nullptr);
    return nlohmann::json({{"median", Percentile(v, 0.5)}, {"min", *std::min_element(v.begin(), v.end())},
                           {"max", *std::max_element(v.begin(), v.end())}});
  };
  return {{"benchmark", "flatness"},
          {"ts_envelope_s", fig1.at("ts_envelope_s")},
          {"ts_actuator_s", fig1.at("ts_actuator_s")},
          {"ts_plan_s", fig1.at("ts_plan_s")},
          {"ts_plan_binding", fig1.at("ts_plan_binding")},
          {"flights", trials},
          {"success_rate", static_cast<double>(success) / trials},
          {"fault", {{"rotor", fig1.at("fault_rotor")}, {"w", truth}, {"onset_s", fig1.at("fault_onset_s")}}},
          {"ukf_w_estimate", median(w)},
          {"ukf_w_estimate_range", range(w)},
          {"ukf_identified_rate", static_cast<double>(identified) / trials},
          {"ukf_detect_s", median(detect)},
          {"ukf_settle_s", median(settle)},
          {"ukf_settle_s_range", range(settle)},
          {"replanned_rate", static_cast<double>(replanned) / trials},
          {"replan_decisions", decisions},
          {"replan_bindings", bindings},
          {"replan_ts_s", median(ts)},
          {"replan_ts_s_range", range(ts)},
          {"replan_ts_nominal_s", median(ts_nominal)},
          {"replan_actuator_s", median(act)},
          {"replan_actuator_nominal_s", median(act_nominal)},
          {"theta_max_deg", fig1.at("theta_max_deg")},
          {"max_pitch_deg", median(tilt_free)},
          {"max_pitch_deg_range", range(tilt_free)},
          {"max_tilt_deg_with_fault", median(tilt)},
          {"failures", failures.listed()},
          {"failures_not_listed", failures.not_listed()},
          {"options", options},
          {"truth", options.at("truth")},
          {"host", buildinfo::HostInfo()}};
}

nlohmann::json RunFlatnessBenchmark(const FlatnessBenchOptions& o) {
  const campaign::Campaign c = FlatnessCampaign(o);
  return FlatnessResult(c.bench["options"], campaign::RunWholeCampaign(c, o.jobs, o.progress));
}

std::string FlatnessMarkdown(const nlohmann::json& r) {
  const auto num = [&](const char* key, const char* fmt_spec = "{:.3f}") {
    return r[key].is_null() ? std::string("–") : fmt::format(fmt::runtime(fmt_spec), r[key].get<double>());
  };
  std::string md = "| figure | value | paper |\n|---|---|---|\n";
  md += fmt::format("| ts_envelope_s (R = -1.5 m, theta_max = {:.0f} deg) | {} | 5.46 |\n", r["theta_max_deg"].get<double>(),
                    num("ts_envelope_s"));
  md += fmt::format("| ts_actuator_s (actuator limits only) | {} | 4.46 (their u_max = 0.028) |\n", num("ts_actuator_s"));
  md += fmt::format("| flights of Fig. 2 (seeds) | {} | 1 |\n", r["flights"].get<int>());
  md += fmt::format("| success_rate | {} | |\n", num("success_rate"));
  md += fmt::format("| ukf_w_estimate (median; truth {:.2f}) | {} | 0.4 |\n", r["fault"]["w"].get<double>(),
                    num("ukf_w_estimate"));
  md += fmt::format("| ukf_identified_rate (within 0.05) | {} | |\n", num("ukf_identified_rate"));
  md += fmt::format("| ukf_detect_s after onset (median) | {} | about 0.5 |\n", num("ukf_detect_s"));
  md += fmt::format("| ukf_settle_s after onset (median) | {} | |\n", num("ukf_settle_s"));
  md += fmt::format("| replan_ts_s (median) | {} | 7 |\n", num("replan_ts_s"));
  md += fmt::format("| replan_ts_nominal_s (fault-free re-plan, same distance) | {} | |\n", num("replan_ts_nominal_s"));
  md += fmt::format("| replan_actuator_s / fault-free (eq. 23 candidate) | {} / {} | |\n", num("replan_actuator_s"),
                    num("replan_actuator_nominal_s"));
  md += fmt::format("| max_pitch_deg, fault-free flight (theta_max {:.0f}) | {} | below 10 |\n",
                    r["theta_max_deg"].get<double>(), num("max_pitch_deg", "{:.2f}"));
  md += fmt::format("| max tilt with the fault [deg] | {} | |\n", num("max_tilt_deg_with_fault", "{:.2f}"));
  md += "\nre-plan decisions: " + r["replan_decisions"].dump() + ", binding limits: " + r["replan_bindings"].dump() + "\n";
  for (const auto& f : r["failures"]) {
    md += fmt::format("failed: seed {}: {}\n", f["seed"].get<std::uint64_t>(), f["reason"].get<std::string>());
  }
  if (const std::string more = campaign::FailureList::NotListedLine(r, ""); !more.empty()) md += more + "\n";
  return md;
}

}  // namespace rotorguard::benchmarks
