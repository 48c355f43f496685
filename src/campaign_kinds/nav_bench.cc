#include "rotorguard/campaign_kinds/nav_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "rotorguard/campaign_kinds/planner_bench.h"
#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/failure_list.h"
#include "rotorguard/campaign/statistics.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/planning/references.h"

namespace rotorguard::benchmarks {

namespace {

constexpr const char* kVariants[] = {"rotorguard", "failure_unaware"};

/// A point with `clearance` to every obstacle: `guess` moved along y (forest) or redrawn in the
/// room's interior until free; the last draw when none is.
Vector3 FreePoint(const sim::World& w, Rng* rng, Vector3 p, double y_lo, double y_hi, double x_lo, double x_hi,
                  double clearance) {
  for (int k = 0; k < 200 && w.DistanceToObstacles(p, 0.0) < clearance; ++k) {
    p.x() = rng->Uniform(x_lo, x_hi);
    p.y() = rng->Uniform(y_lo, y_hi);
  }
  return p;
}

struct NavTrial {
  bool success = false, collision = false, crashed = false;
  double tracking_rmse_m = 0.0, max_spin_rad_s = 0.0, mission_time_s = -1.0;
  double planner_ms_mean = 0.0, stack_ms_per_cycle_mean = 0.0;
  double realtime_factor = 0.0;                     // the stack's: harness::RunSummary::stack_realtime_factor
  double trial_realtime_factor = 0.0;               // the whole trial's, the simulator included
  std::map<std::string, double> cost_ms_per_sim_s;  // harness::RunCost's parts by name
  std::string failure;
};

/// A trial record's metric for a part of RunCost.
std::string CostMetric(const std::string& part) { return "cost_" + part + "_ms_per_sim_s"; }

nlohmann::json Aggregate(const std::vector<const NavTrial*>& trials, const std::vector<std::uint64_t>& seeds,
                         const std::vector<std::string>& kinds) {
  const double n = static_cast<double>(trials.size());
  double success = 0, collision = 0, crash = 0, rmse = 0, spin = 0, planner = 0, stack = 0, rtf = 0, trial_rtf = 0,
         time = 0;
  int completed = 0;
  std::map<std::string, double> cost;
  campaign::FailureList failures(10);  // each with its seed for --replay
  for (std::size_t i = 0; i < trials.size(); ++i) {
    const NavTrial& t = *trials[i];
    success += t.success;
    collision += t.collision;
    crash += t.crashed;
    rmse += t.tracking_rmse_m / n;
    spin += t.max_spin_rad_s / n;
    planner += t.planner_ms_mean / n;
    stack += t.stack_ms_per_cycle_mean / n;
    rtf += t.realtime_factor / n;
    trial_rtf += t.trial_realtime_factor / n;
    for (const auto& [part, ms] : t.cost_ms_per_sim_s) cost[part] += ms / n;
    if (t.mission_time_s >= 0.0) time += t.mission_time_s, ++completed;
    if (!t.success) failures.Add({{"kind", kinds[i]}, {"seed", seeds[i]}, {"reason", t.failure}});
  }
  const auto [success_lo, success_hi] = campaign::WilsonInterval(static_cast<int>(success), static_cast<int>(n));
  return {{"trials", trials.size()},
          {"success_rate", success / n},
          {"success_wilson95", {success_lo, success_hi}},
          {"collision_rate", collision / n},
          {"crash_rate", crash / n},
          {"tracking_rmse_m", rmse},
          {"max_spin_rad_s", spin},
          {"mission_time_s", completed > 0 ? nlohmann::json(time / completed) : nlohmann::json(nullptr)},
          {"planner_ms_mean", planner},
          {"stack_ms_per_cycle_mean", stack},
          {"realtime_factor", rtf},
          {"trial_realtime_factor", trial_rtf},
          {"cost_ms_per_sim_s", cost},
          {"failures", failures.listed()},
          {"failures_not_listed", failures.not_listed()}};
}

/// The two variants on the same worlds, pair by pair (docs/metrics.md, "Comparing two methods"): how
/// many worlds each alone succeeded in, and the exact McNemar test of that split.
nlohmann::json Paired(const std::vector<const NavTrial*>& aware, const std::vector<const NavTrial*>& unaware) {
  int both = 0, only_aware = 0, only_unaware = 0, neither = 0;
  for (std::size_t i = 0; i < aware.size(); ++i) {
    const bool a = aware[i]->success, u = unaware[i]->success;
    both += a && u;
    only_aware += a && !u;
    only_unaware += !a && u;
    neither += !a && !u;
  }
  return {{"worlds", aware.size()},
          {"both_succeeded", both},
          {"only_rotorguard", only_aware},
          {"only_failure_unaware", only_unaware},
          {"both_failed", neither},
          {"success_difference", aware.empty() ? 0.0 : static_cast<double>(only_aware - only_unaware) / aware.size()},
          {"mcnemar_exact_p", campaign::McNemarExactP(only_aware, only_unaware)}};
}

}  // namespace

void NavBenchOptions::Validate() const {
  if (trials < 1 || trials > 100000) ThrowInvalidArgument("NavBenchOptions", "trials", trials, "a count in [1, 100000]");
  if (jobs < 1 || jobs > 256) ThrowInvalidArgument("NavBenchOptions", "jobs", jobs, "a count in [1, 256]");
  if (kinds.empty()) ThrowInvalidArgument("NavBenchOptions", "kinds", "(none)", "at least one of forest, room");
  for (const std::string& k : kinds) {
    if (k != "forest" && k != "room") ThrowInvalidArgument("NavBenchOptions", "kinds", k, "forest or room");
  }
  if (base.stack.navigation.waypoints.empty()) {
    ThrowInvalidArgument("NavBenchOptions", "base", base.name, "a navigate scenario (its stack flies every trial)");
  }
}

harness::Scenario MakeNavTrial(const harness::Scenario& base, const std::string& kind, std::uint64_t seed, bool failure_aware) {
  harness::Scenario s = base;
  Rng rng(DeriveSeed(seed, 21));
  s.name = fmt::format("nav_{}_{}", kind, seed);
  s.seed = seed;
  std::vector<Vector3> points;  // start, then the waypoints
  if (kind == "forest") {
    s.world = PlannerForest(DeriveSeed(seed, 22));
    // West to east across the forest through a point in its middle, 1.5 m up.
    for (const double x : {-13.5, 0.0, 13.5}) {
      points.push_back(FreePoint(s.world, &rng, Vector3(x, rng.Uniform(-7, 7), 1.5), -7, 7, x - 1.0, x + 1.0, 1.0));
    }
  } else {
    s.world = PlannerRoom(DeriveSeed(seed, 23));
    // A room has a ceiling: without one nothing the LiDAR sees from 1.3 m up fixes the height
    // (its lowest beam meets the floor beyond the walls).
    s.world.boxes.push_back({Vector3(0.0, 0.0, 3.25), Vector3(11.0, 9.0, 0.5), 0.0});
    // Three corners of the room in turn, 1.3 m up.
    for (const Vector3& corner : {Vector3(-3.8, -2.8, 1.3), Vector3(3.8, 2.8, 1.3), Vector3(-3.8, 2.8, 1.3)}) {
      points.push_back(FreePoint(s.world, &rng, corner, -3.2, 3.2, -4.2, 4.2, 0.8));
    }
  }
  s.initial_position_m = points.front();
  s.initial_yaw_rad = 0.0;
  planning::HoverOptions hold;  // the mission's reference: hold the start until the first plan
  hold.position_m = points.front();
  s.reference = std::make_shared<planning::HoverReference>(hold);
  s.stack.navigation.waypoints.assign(points.begin() + 1, points.end());
  s.stack.navigation.rounds = 1;
  s.stack.navigation.failure_aware = failure_aware;
  double length = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  // Time enough to fly the legs at half the speed limit, plus the start and the hold.
  s.duration_s = std::ceil(2.0 * length / s.stack.navigation.replanner.nominal.v_max + 20.0);
  sim::FaultSpec fault;
  fault.rotor = std::min(3, static_cast<int>(rng.Uniform() * 4.0));
  fault.kind = vehicle::FaultKind::kPropellerLoss;
  fault.onset.value = rng.Uniform(4.0, 10.0);  // mid-flight: after the first plan, well before the end
  s.faults = {fault};
  s.sim.wind.mean_m_s = Vector3(rng.Uniform(-0.3, 0.3), rng.Uniform(-0.3, 0.3), 0.0);
  s.sim.wind.gust_std_m_s = rng.Uniform(0.0, 0.4);
  // The scene is rebuilt, the stack's hardware facts stay those of the base vehicle.
  return s;
}

campaign::Campaign NavCampaign(const NavBenchOptions& o) {
  o.Validate();
  campaign::Campaign c;
  c.name = "bench_nav";
  c.seed = o.seed;
  c.trials = static_cast<int>(o.kinds.size()) * o.trials * 2;
  c.group_keys = {"kind", "variant"};
  c.metrics = {"success",        "collision",       "tracking_rmse_m",      "max_spin_rad_s",
               "mission_time_s", "realtime_factor", "trial_realtime_factor"};
  const nlohmann::json options = {{"trials", o.trials},       {"seed", o.seed},
                                  {"kinds", o.kinds},         {"base", o.base.name},
                                  {"truth", ToName(o.truth)}, {"estimator", ToName(o.estimator)}};
  // "records": what a trial records. Version 2 made realtime_factor the stack's and added
  // trial_realtime_factor; the hash then refuses to resume or merge the folders of version 1.
  c.bench = {{"name", "nav"}, {"records", 2}, {"options", options}, {"seed_stream", "bench nav"}};
  c.hash = campaign::Fingerprint(c.bench.dump() + "\n" + harness::ScenarioFingerprint(o.base));
  // Trial index = (kind, trial, variant), the variant fastest: both variants fly the same world,
  // fault and noise (the seed depends on the kind and trial only).
  c.parameters = [o](int index) {
    const int kind = index / (2 * o.trials), trial = (index / 2) % o.trials;
    const std::uint64_t seed = TrialSeed(o.seed, "bench nav", static_cast<std::uint64_t>(kind) * 1'000'003ull + trial);
    return std::map<std::string, std::string>{{"kind", o.kinds[static_cast<std::size_t>(kind)]},
                                              {"variant", kVariants[index % 2]},
                                              {"trial", std::to_string(trial)},
                                              {"seed", std::to_string(seed)}};
  };
  harness::Scenario base = o.base;
  base.truth.preset = o.truth;
  base.stack.estimator.kind = o.estimator;
  c.simulated_s = [base](int, const std::map<std::string, std::string>& params) {
    return MakeNavTrial(base, params.at("kind"), std::stoull(params.at("seed")), params.at("variant") == kVariants[0])
        .duration_s;
  };
  c.reproduce = [o](int, const std::map<std::string, std::string>& params) {
    return fmt::format("rotorguard bench nav --replay {}:{}{} --truth {} --estimator {}", params.at("kind"),
                       params.at("seed"), params.at("variant") == kVariants[0] ? "" : ":unaware", ToName(o.truth),
                       ToName(o.estimator));
  };
  c.run = [base](int, const std::map<std::string, std::string>& params) {
    harness::RunOptions run;
    run.stop_when_mission_complete = true;
    const harness::RunSummary s = harness::RunScenario(MakeNavTrial(base, params.at("kind"), std::stoull(params.at("seed")),
                                                  params.at("variant") == kVariants[0]), run);
    campaign::TrialOutcome out;
    out.metrics = {{"success", s.success},
                   {"crashed", s.crashed},
                   {"collision", s.crashed && s.crash_reason.value_or("").rfind("collision", 0) == 0},
                   {"tracking_rmse_m", s.tracking_rmse_m},
                   {"max_spin_rad_s", s.max_spin_rad_s},
                   {"mission_time_s", s.mission_time_s ? nlohmann::json(*s.mission_time_s) : nlohmann::json()},
                   {"planner_ms_mean", s.stack.navigation ? s.stack.navigation->planner_ms_mean : 0.0},
                   {"stack_ms_per_cycle_mean", s.stack_ms_per_cycle_mean},
                   {"realtime_factor", s.stack_realtime_factor},
                   {"trial_realtime_factor", s.realtime_factor}};
    for (const harness::RunCost::Part& p : harness::RunCost::kParts) out.metrics[CostMetric(p.name)] = s.cost_ms_per_sim_s.*p.field;
    out.message = s.failure_reason.value_or("");
    return out;
  };
  return c;
}

nlohmann::json NavResult(const nlohmann::json& options, const std::vector<nlohmann::json>& records) {
  const std::vector<std::string> kinds = options.at("kinds").get<std::vector<std::string>>();
  const int trials = options.at("trials").get<int>();
  if (records.size() != kinds.size() * static_cast<std::size_t>(trials) * 2) {
    throw std::invalid_argument(fmt::format("nav: {} trial records for {} kinds x {} trials x 2 variants",
                                            records.size(), kinds.size(), trials));
  }
  std::vector<NavTrial> results;
  for (const nlohmann::json& r : records) {
    NavTrial t;
    t.failure = campaign::TrialFailure(r);
    if (r.at("status") == "ok") {
      const nlohmann::json& x = r.at("metrics");
      t.success = x.at("success").get<bool>();
      t.crashed = x.at("crashed").get<bool>();
      t.collision = x.at("collision").get<bool>();
      t.tracking_rmse_m = x.at("tracking_rmse_m").get<double>();
      t.max_spin_rad_s = x.at("max_spin_rad_s").get<double>();
      t.mission_time_s = x.at("mission_time_s").is_null() ? -1.0 : x.at("mission_time_s").get<double>();
      t.planner_ms_mean = x.at("planner_ms_mean").get<double>();
      t.stack_ms_per_cycle_mean = x.at("stack_ms_per_cycle_mean").get<double>();
      t.realtime_factor = x.at("realtime_factor").get<double>();
      t.trial_realtime_factor = x.at("trial_realtime_factor").get<double>();
      for (const harness::RunCost::Part& p : harness::RunCost::kParts) t.cost_ms_per_sim_s[p.name] = x.at(CostMetric(p.name)).get<double>();
    }
    results.push_back(t);
  }
  nlohmann::json result = {{"benchmark", "nav"}};
  nlohmann::json groups = nlohmann::json::object();
  std::vector<const NavTrial*> by_variant[2];
  for (int v = 0; v < 2; ++v) {
    std::vector<const NavTrial*> all;
    std::vector<std::uint64_t> all_seeds;
    std::vector<std::string> all_kinds;
    for (std::size_t k = 0; k < kinds.size(); ++k) {
      std::vector<const NavTrial*> group;
      std::vector<std::uint64_t> group_seeds;
      for (int t = 0; t < trials; ++t) {
        const std::size_t index = (k * static_cast<std::size_t>(trials) + static_cast<std::size_t>(t)) * 2 + v;
        group.push_back(&results[index]);
        group_seeds.push_back(std::stoull(records[index].at("params").at("seed").get<std::string>()));
      }
      const std::vector<std::string> group_kinds(group.size(), kinds[k]);
      groups[kinds[k]][kVariants[v]] = Aggregate(group, group_seeds, group_kinds);
      if (v == 1) {
        const auto first = by_variant[0].begin() + static_cast<std::ptrdiff_t>(k) * trials;
        groups[kinds[k]]["paired"] = Paired({first, first + trials}, group);
      }
      all.insert(all.end(), group.begin(), group.end());
      all_seeds.insert(all_seeds.end(), group_seeds.begin(), group_seeds.end());
      all_kinds.insert(all_kinds.end(), group_kinds.begin(), group_kinds.end());
    }
    result[kVariants[v]] = Aggregate(all, all_seeds, all_kinds);
    by_variant[v] = std::move(all);
  }
  result["paired"] = Paired(by_variant[0], by_variant[1]);
  result["groups"] = groups;
  result["options"] = options;
  result["truth"] = options.value("truth", "ideal");  // records made before the key: the ideal world
  result["estimator"] = options.value("estimator", "odometry");
  result["host"] = buildinfo::HostInfo();
  return result;
}

nlohmann::json RunNavBenchmark(const NavBenchOptions& o) {
  const campaign::Campaign c = NavCampaign(o);
  return NavResult(c.bench["options"], campaign::RunWholeCampaign(c, o.jobs, o.progress));
}

std::string NavMarkdown(const nlohmann::json& r) {
  std::string md =
      "| kind | variant | trials | success | collisions | tracking RMSE [m] | max spin [rad/s] | "
      "mission [s] | planner [ms] | stack [ms/cycle] | real-time factor | trial real-time factor |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  const auto row = [&](const std::string& kind, const std::string& variant, const nlohmann::json& g) {
    md += fmt::format(
        "| {} | {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.2f} | {} | {:.2f} | {:.3f} | {:.1f} | {:.1f} |\n", kind,
        variant, g["trials"].get<int>(), g["success_rate"].get<double>(), g["collision_rate"].get<double>(),
        g["tracking_rmse_m"].get<double>(), g["max_spin_rad_s"].get<double>(),
        g["mission_time_s"].is_null() ? std::string("–") : fmt::format("{:.1f}", g["mission_time_s"].get<double>()),
        g["planner_ms_mean"].get<double>(), g["stack_ms_per_cycle_mean"].get<double>(),
        g["realtime_factor"].get<double>(), g["trial_realtime_factor"].get<double>());
  };
  for (const auto& [kind, variants] : r["groups"].items()) {
    for (const char* v : kVariants) row(kind, v, variants[v]);
  }
  for (const char* v : kVariants) row("all", v, r[v]);
  // The comparison that matters: the same worlds flown by both.
  const auto paired = [&](const std::string& kind, const nlohmann::json& p) {
    md += fmt::format(
        "\nPaired on the same {} {} worlds: both succeeded in {}, rotorguard alone in {}, "
        "failure-unaware alone in {}, neither in {}; difference {:+.3f}, exact McNemar p = {:.3g}.",
        p["worlds"].get<int>(), kind, p["both_succeeded"].get<int>(), p["only_rotorguard"].get<int>(),
        p["only_failure_unaware"].get<int>(), p["both_failed"].get<int>(), p["success_difference"].get<double>(),
        p["mcnemar_exact_p"].get<double>());
  };
  md += "\nSuccess rates' 95 % Wilson intervals:";
  for (const char* v : kVariants) {
    md += fmt::format(" {} [{:.3f}, {:.3f}]", v, r[v]["success_wilson95"][0].get<double>(),
                      r[v]["success_wilson95"][1].get<double>());
  }
  md += ".\n";
  for (const auto& [kind, variants] : r["groups"].items()) {
    if (variants.contains("paired")) paired(kind, variants["paired"]);
  }
  md += "\n";
  // Where the wall-clock time goes (all trials): the parts add up to 1000 / trial real-time factor,
  // the stack's (all but simulator and runner) to 1000 / real-time factor.
  md += "\nWall-clock time per simulated second [ms], all trials:\n\n| variant |";
  for (const harness::RunCost::Part& p : harness::RunCost::kParts) md += fmt::format(" {} |", p.name);
  md += " total |\n|---|";
  for (std::size_t k = 0; k <= harness::RunCost::kParts.size(); ++k) md += "---|";
  md += "\n";
  for (const char* v : kVariants) {
    const nlohmann::json& c = r[v]["cost_ms_per_sim_s"];
    double total = 0.0;
    md += fmt::format("| {} |", v);
    for (const harness::RunCost::Part& p : harness::RunCost::kParts) {
      const double ms = c.value(p.name, 0.0);
      total += ms;
      md += fmt::format(" {:.1f} |", ms);
    }
    md += fmt::format(" {:.1f} |\n", total);
  }
  for (const char* v : kVariants) {
    for (const auto& f : r[v]["failures"]) {
      md += fmt::format("\n{} failed: {} seed {}: {}", v, f["kind"].get<std::string>(), f["seed"].get<std::uint64_t>(),
                        f["reason"].get<std::string>());
    }
    if (const std::string more = campaign::FailureList::NotListedLine(r[v], v); !more.empty()) md += "\n" + more;
  }
  return md + "\n";
}

}  // namespace rotorguard::benchmarks
