#include "rotorguard/benchmarks/flatness_bench.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/campaign/failure_list.h"
#include "rotorguard/campaign/parallel.h"
#include "rotorguard/core/error.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/planning/flatness.h"

namespace rotorguard::benchmarks {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Fig2Flight {
  bool success = false, replanned = false;
  double w_estimate = 0.0, settle_s = -1.0, detect_s = -1.0, replan_ts_s = 0.0, replan_nominal_ts_s = 0.0;
  double replan_actuator_s = 0.0, replan_nominal_actuator_s = 0.0, max_tilt_deg = 0.0, fault_free_tilt_deg = 0.0;
  std::string decision, binding, failure;
};

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

void FlatnessBenchOptions::Validate() const {
  if (seeds < 1 || seeds > 10000) ThrowInvalidArgument("FlatnessBenchOptions", "seeds", seeds, "a count in [1, 10000]");
  if (jobs < 1 || jobs > 256) ThrowInvalidArgument("FlatnessBenchOptions", "jobs", jobs, "a count in [1, 256]");
  if (fig2.stack.navigation.method != stack::NavigationMethod::kFlatness || fig2.faults.empty() || fig2.stack.navigation.waypoints.empty()) {
    ThrowInvalidArgument("FlatnessBenchOptions", "fig2", fig2.name, "a flatness navigate scenario with a fault");
  }
}

nlohmann::json RunFlatnessBenchmark(const FlatnessBenchOptions& o) {
  o.Validate();
  const vehicle::PwmQuadModel model = vehicle::PwmQuadModel::FromVehicle(o.fig2.vehicle);
  const planning::FlatnessLimits& limits = o.fig2.stack.navigation.flatness.limits;
  const Vector3 move = o.fig2.stack.navigation.waypoints.front() - o.fig2.initial_position_m;
  // Fig. 1: the envelope-bound plan (eq. 16) and the actuator-bound plan (eq. 23) of the move.
  planning::FlatnessLimits actuator_only = limits;
  actuator_only.theta_max_rad = actuator_only.phi_max_rad = std::numeric_limits<double>::infinity();
  const planning::SettlingTime fig1 = planning::PlanSettlingTime(model, limits, move.head<2>());
  const planning::SettlingTime fig1b = planning::PlanSettlingTime(model, actuator_only, move.head<2>());
  const int faulty = o.fig2.faults.front().rotor;
  const double onset = o.fig2.faults.front().onset.value;

  std::vector<Fig2Flight> flights(static_cast<std::size_t>(o.seeds));
  campaign::ParallelFor(2 * o.seeds, o.jobs, [&](int task) {
    Fig2Flight& f = flights[static_cast<std::size_t>(task / 2)];
    harness::Scenario s = o.fig2;
    s.seed = o.seed + static_cast<std::uint64_t>(task / 2);
    s.truth.preset = o.truth;
    try {
      if (task % 2 == 1) {  // the same flight without the fault: the pitch the plan asks for
        s.faults.clear();
        f.fault_free_tilt_deg = harness::RunScenario(s, harness::RunOptions{}).max_tilt_rad / kDeg;
        return;
      }
      const harness::RunSummary r = harness::RunScenario(s, harness::RunOptions{});
      f.success = r.success;
      f.failure = r.failure_reason.value_or("");
      f.max_tilt_deg = r.max_tilt_rad / kDeg;
      if (const std::optional<stack::UkfSummary>& ukf = r.stack.ukf) {
        if (faulty < static_cast<int>(ukf->w_hat.size())) f.w_estimate = ukf->w_hat[static_cast<std::size_t>(faulty)];
        if (ukf->settled_s) f.settle_s = *ukf->settled_s - onset;
      }
      if (r.fdd) f.detect_s = r.fdd->diagnosis ? r.fdd->diagnosis->detection_s - onset : -1.0;
      for (const planning::FlatnessDecision& d : r.stack.flatness_decisions) {
        if (d.kind != "continue" && d.kind != "return" && d.kind != "land") continue;
        f.replanned = true;
        f.decision = d.kind;
        f.replan_ts_s = d.t_s;
        f.binding = d.binding;
        f.replan_actuator_s = d.actuator_s;
        const Eigen::Vector2d delta(d.delta_m.x(), d.delta_m.y());
        const planning::SettlingTime nominal = planning::PlanSettlingTime(model, limits, delta);
        f.replan_nominal_ts_s = std::max(nominal.t_s, o.fig2.stack.navigation.flatness.min_t_s);
        f.replan_nominal_actuator_s = nominal.actuator_s;
      }
    } catch (const std::exception& e) {
      f.failure = std::string("error: ") + e.what();
    }
  }, o.progress);

  std::vector<double> w, settle, detect, ts, ts_nominal, act, act_nominal, tilt, tilt_free;
  int success = 0, replanned = 0;
  std::map<std::string, int> decisions, bindings;
  campaign::FailureList failures(10);
  for (std::size_t i = 0; i < flights.size(); ++i) {
    const Fig2Flight& f = flights[i];
    success += f.success;
    tilt.push_back(f.max_tilt_deg);
    tilt_free.push_back(f.fault_free_tilt_deg);
    w.push_back(f.w_estimate);
    if (f.settle_s >= 0.0) settle.push_back(f.settle_s);
    if (f.detect_s >= 0.0) detect.push_back(f.detect_s);
    if (!f.success) failures.Add({{"seed", o.seed + i}, {"reason", f.failure}});
    if (!f.replanned) continue;
    ++replanned;
    ++decisions[f.decision];
    ++bindings[f.binding];
    ts.push_back(f.replan_ts_s);
    ts_nominal.push_back(f.replan_nominal_ts_s);
    act.push_back(f.replan_actuator_s);
    act_nominal.push_back(f.replan_nominal_actuator_s);
  }
  const auto range = [](const std::vector<double>& v) {
    if (v.empty()) return nlohmann::json(nullptr);
    return nlohmann::json({{"median", Median(v)}, {"min", *std::min_element(v.begin(), v.end())},
                           {"max", *std::max_element(v.begin(), v.end())}});
  };
  const double truth = o.fig2.faults.front().eta;
  int identified = 0;
  for (const double e : w) identified += std::abs(e - truth) <= 0.05;
  return {
      {"benchmark", "flatness"},
      {"ts_envelope_s", fig1.envelope_s},
      {"ts_actuator_s", fig1b.actuator_s},
      {"ts_plan_s", fig1.t_s},
      {"ts_plan_binding", planning::ToString(fig1.binding)},
      {"flights", o.seeds},
      {"success_rate", static_cast<double>(success) / o.seeds},
      {"fault", {{"rotor", faulty}, {"w", truth}, {"onset_s", onset}}},
      {"ukf_w_estimate", Median(w)},
      {"ukf_w_estimate_range", range(w)},
      {"ukf_identified_rate", static_cast<double>(identified) / o.seeds},
      {"ukf_detect_s", detect.empty() ? nlohmann::json(nullptr) : nlohmann::json(Median(detect))},
      {"ukf_settle_s", settle.empty() ? nlohmann::json(nullptr) : nlohmann::json(Median(settle))},
      {"ukf_settle_s_range", range(settle)},
      {"replanned_rate", static_cast<double>(replanned) / o.seeds},
      {"replan_decisions", decisions},
      {"replan_bindings", bindings},
      {"replan_ts_s", ts.empty() ? nlohmann::json(nullptr) : nlohmann::json(Median(ts))},
      {"replan_ts_s_range", range(ts)},
      {"replan_ts_nominal_s", ts_nominal.empty() ? nlohmann::json(nullptr) : nlohmann::json(Median(ts_nominal))},
      {"replan_actuator_s", act.empty() ? nlohmann::json(nullptr) : nlohmann::json(Median(act))},
      {"replan_actuator_nominal_s",
       act_nominal.empty() ? nlohmann::json(nullptr) : nlohmann::json(Median(act_nominal))},
      {"theta_max_deg", limits.theta_max_rad / kDeg},
      {"max_pitch_deg", Median(tilt_free)},
      {"max_pitch_deg_range", range(tilt_free)},
      {"max_tilt_deg_with_fault", Median(tilt)},
      {"failures", failures.listed()},
      {"failures_not_listed", failures.not_listed()},
      {"options",
       {{"seeds", o.seeds}, {"seed", o.seed}, {"jobs", o.jobs}, {"scenario", o.fig2.name}, {"truth", ToName(o.truth)}}},
      {"truth", ToName(o.truth)},
      {"host", buildinfo::HostInfo()}};
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
