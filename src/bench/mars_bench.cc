#include "rotorguard/bench/mars_bench.h"

#include <algorithm>
#include <numbers>

#include <fmt/format.h>

#include "rotorguard/bench/assembly_mission.h"
#include "rotorguard/bench/metrics.h"
#include "rotorguard/bench/parallel.h"
#include "rotorguard/bench/reconfiguration.h"
#include "rotorguard/bench/runner.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/modular/allocation.h"

namespace rotorguard::bench {

namespace {

/// A row of Table I (or Fig. 3): what each faulty rotor keeps of its thrust, rotor by rotor.
struct FaultCase {
  std::string name;
  std::vector<std::pair<int, double>> rotors;  ///< (rotor, loss); loss 1 is a stopped motor
};

std::vector<FaultCase> TableOneCases() {
  // Unit No. k is index k - 1, its rotor j is index 4 (k - 1) + j - 1 (modular::Assembly).
  const auto unit = [](int k) {
    std::vector<std::pair<int, double>> r;
    for (int j = 0; j < 4; ++j) r.emplace_back(4 * (k - 1) + j, 1.0);
    return r;
  };
  std::vector<std::pair<int, double>> two_units = unit(1);
  for (const auto& r : unit(6)) two_units.push_back(r);
  std::vector<std::pair<int, double>> same_row = unit(1);
  for (const auto& r : unit(3)) same_row.push_back(r);
  return {{"no failure", {}},
          {"eta_2,2 = 0.5", {{5, 0.5}}},
          {"eta_2,1 = eta_2,2 = 0.5", {{4, 0.5}, {5, 0.5}}},
          {"unit No. 1 dead", unit(1)},
          {"units No. 1 and 6 dead (diagonal)", two_units},
          {"units No. 1 and 3 dead (one row)", same_row}};
}

const std::vector<modular::Reallocation> kMethods = {modular::Reallocation::kNone, modular::Reallocation::kPartial,
                                                     modular::Reallocation::kFull};

struct Flight {
  bool success = false;
  double rmse = 0.0, max_error = 0.0;
  std::string failure;
};

/// Flies `s` once; an exception is the flight's failure.
Flight FlyOnce(const Scenario& s) {
  Flight f;
  try {
    const RunSummary r = RunScenario(s, RunOptions{});
    f.success = r.success;
    f.rmse = r.tracking_rmse_m;
    f.max_error = r.max_position_error_m;
    f.failure = r.failure_reason;
  } catch (const std::exception& e) {
    f.failure = std::string("error: ") + e.what();
  }
  return f;
}

Scenario WithFaults(const Scenario& base, const FaultCase& c, modular::Reallocation method, std::uint64_t seed) {
  Scenario s = base;
  s.seed = seed;
  s.allocation.method = method;
  s.faults.clear();
  s.stack.known_faults.clear();
  for (const auto& [rotor, loss] : c.rotors) {
    sim::FaultSpec f;
    f.rotor = rotor;
    f.kind = loss >= 1.0 ? vehicle::FaultKind::kMotorStop : vehicle::FaultKind::kLossOfEffectiveness;
    f.eta = loss >= 1.0 ? 0.0 : loss;
    f.onset.value = 0.0;
    s.faults.push_back(f);
    s.stack.known_faults.push_back({rotor, 0.0, loss});
  }
  return s;
}

/// Mean and 99th percentile [us] of the full reallocation on `a` with a dead unit and random
/// partial losses, for random wrenches around hover.
std::pair<double, double> TimeAllocation(const modular::Assembly& a, int samples, std::uint64_t seed) {
  modular::AssemblyAllocator alloc(a, {});
  Rng rng(seed);
  const int n = a.vehicle.num_rotors();
  RotorVector eta = RotorVector::Ones(n);
  eta.segment(0, a.rotors_per_unit).setZero();  // unit No. 1 dead
  for (int k = a.rotors_per_unit; k < n; ++k) eta[k] = rng.Uniform() < 0.15 ? rng.Uniform(0.3, 0.9) : 1.0;
  alloc.SetEffectiveness(eta);
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(samples));
  RotorVector u;
  const double w = a.vehicle.weight_n();
  for (int i = 0; i < samples; ++i) {
    const Eigen::Vector4d wrench(w * rng.Uniform(0.7, 1.4), rng.Uniform(-0.5, 0.5), rng.Uniform(-0.5, 0.5),
                                 rng.Uniform(-0.1, 0.1));
    us.push_back(1e6 * alloc.Allocate(wrench, &u).solve_time_s);  // the allocator times itself
  }
  double mean = 0.0;
  for (const double v : us) mean += v / samples;
  return {mean, Percentile(us, 99.0)};
}

/// The rotors of unit No. k (index k - 1), all stopped.
std::vector<std::pair<int, double>> DeadUnit(int k) {
  std::vector<std::pair<int, double>> r;
  for (int j = 0; j < 4; ++j) r.emplace_back(4 * (k - 1) + j, 1.0);
  return r;
}

/// What a plan asks of the assembly, sampled every millisecond (finer than the planner's checks):
/// the largest acceleration, thrust per kilogram |a + g e_z| and yaw acceleration.
struct PlanDemands {
  double accel = 0.0, thrust_accel = 0.0, yaw_accel = 0.0;
};
PlanDemands DemandsOf(const modular::AssemblyTrajectory& t) {
  PlanDemands d;
  for (double time = 0.0; time <= t.duration(); time += 1e-3) {
    Vector3 a = t.Evaluate(time).a_W;
    d.accel = std::max(d.accel, a.norm());
    a.z() += kGravity;
    d.thrust_accel = std::max(d.thrust_accel, a.norm());
    d.yaw_accel = std::max(d.yaw_accel, std::abs(t.yaw().Evaluate(time).a_W.x()));
  }
  return d;
}

/// Table II: each scene and fault planned by ours and by the baseline (once: planning is
/// deterministic) and flown over the trials' seeds with the full reallocation.
nlohmann::json RunTableTwo(const MarsBenchOptions& o) {
  struct Row {
    const Scenario* scene;
    std::string fault;
    int dead_unit;  ///< paper's No.; 0: none
  };
  const std::vector<Row> rows = {{&o.plan_4x1, "normal", 0}, {&o.plan_4x1, "No. 3", 3}, {&o.plan_4x1, "No. 4", 4},
                                 {&o.plan_3x2, "normal", 0}, {&o.plan_3x2, "No. 2", 2}};
  const char* methods[2] = {"baseline", "ours"};
  std::vector<Scenario> planned;  // row-major: row, method
  std::vector<AssemblyPlanResult> plans;
  for (const Row& row : rows) {
    for (const char* m : methods) {
      const FaultCase c{row.fault, row.dead_unit > 0 ? DeadUnit(row.dead_unit) : std::vector<std::pair<int, double>>{}};
      Scenario s = WithFaults(*row.scene, c, modular::Reallocation::kFull, o.seed);
      s.assembly_plan->method = m;
      plans.push_back(PlanAssemblyMission(s));  // never throws: a failure is the row's
      if (plans.back().ok) s.reference = plans.back().trajectory;
      planned.push_back(std::move(s));
    }
  }
  const int total = static_cast<int>(planned.size()) * o.trials;
  std::vector<Flight> flights(static_cast<std::size_t>(total));
  ParallelFor(total, o.jobs, [&](int task) {
    const std::size_t k = static_cast<std::size_t>(task / o.trials);
    if (!plans[k].ok) return;
    Scenario s = planned[k];
    s.seed = o.seed + static_cast<std::uint64_t>(task % o.trials);
    flights[static_cast<std::size_t>(task)] = FlyOnce(s);
  }, nullptr);
  nlohmann::json table = nlohmann::json::array();
  double sum[2] = {0.0, 0.0}, improvement_sum = 0.0;
  int compared = 0;
  bool all_better = true;
  for (std::size_t row = 0; row < rows.size(); ++row) {
    nlohmann::json r = {{"shape", rows[row].scene->assembly->name}, {"fault", rows[row].fault}};
    double error[2] = {0.0, 0.0};
    bool both_planned = true;
    for (int m = 0; m < 2; ++m) {
      const std::size_t k = 2 * row + static_cast<std::size_t>(m);
      const AssemblyPlanResult& plan = plans[k];
      const std::string name = methods[m];
      r[name + "_planned"] = plan.ok;
      if (!plan.ok) {
        r[name + "_plan_failure"] = plan.message;
        both_planned = false;
        continue;
      }
      int success = 0;
      double max_error = 0.0;
      std::string failure;
      for (int t = 0; t < o.trials; ++t) {
        const Flight& f = flights[k * static_cast<std::size_t>(o.trials) + static_cast<std::size_t>(t)];
        error[m] += f.rmse / o.trials;
        max_error = std::max(max_error, f.max_error);
        success += f.success;
        if (!f.success && failure.empty()) failure = f.failure;
      }
      r[name + "_error_m"] = error[m];
      r[name + "_max_error_m"] = max_error;
      r[name + "_success_rate"] = static_cast<double>(success) / o.trials;
      r[name + "_first_failure"] = failure;
      r[name + "_duration_s"] = plan.trajectory_summary.duration_s;
      r[name + "_attitude_deviation_deg"] = plan.trajectory_summary.attitude_deviation_rad * 180.0 / std::numbers::pi;
      r[name + "_plan_ms"] = plan.astar_ms + plan.trajectory_summary.solve_ms;
      // What the plan asks of the assembly, beside what it can give (the mechanism of the rows).
      const PlanDemands demands = DemandsOf(*plan.trajectory);
      r[name + "_max_accel_m_s2"] = demands.accel;
      r[name + "_max_thrust_accel_m_s2"] = demands.thrust_accel;
      r[name + "_max_yaw_accel_rad_s2"] = demands.yaw_accel;
      r["capacity_accel_m_s2"] = plan.capacity.max_acceleration_m_s2;
      r["capacity_thrust_accel_m_s2"] = plan.capacity.max_thrust_n / rows[row].scene->vehicle.mass_kg;
      r["capacity_yaw_accel_rad_s2"] = plan.capacity.max_yaw_acceleration_rad_s2;
    }
    // A row that either method could not plan has no comparison: null, left out of the averages.
    all_better = all_better && both_planned && error[1] < error[0];
    if (both_planned && error[0] > 0.0) {
      r["improvement"] = 1.0 - error[1] / error[0];
      improvement_sum += r["improvement"].get<double>();
      ++compared;
      sum[0] += error[0];
      sum[1] += error[1];
    } else {
      r["improvement"] = nullptr;
    }
    table.push_back(r);
  }
  return {{"table2", table},
          {"table2_rows_compared", compared},
          {"table2_improvement_average", sum[0] > 0.0 ? nlohmann::json(1.0 - sum[1] / sum[0]) : nlohmann::json()},
          {"table2_improvement_row_mean", compared > 0 ? nlohmann::json(improvement_sum / compared) : nlohmann::json()},
          {"table2_ours_better_in_every_row", all_better}};
}

}  // namespace

void MarsBenchOptions::Validate() const {
  if (trials < 1 || trials > 10000) ThrowInvalidArgument("MarsBenchOptions", "trials", trials, "a count in [1, 10000]");
  if (jobs < 1 || jobs > 256) ThrowInvalidArgument("MarsBenchOptions", "jobs", jobs, "a count in [1, 256]");
  if (alloc_samples < 100 || alloc_samples > 10'000'000) {
    ThrowInvalidArgument("MarsBenchOptions", "alloc_samples", alloc_samples, "a count in [100, 10^7]");
  }
  if (!spiral.assembly || spiral.stack.controller != "assembly") {
    ThrowInvalidArgument("MarsBenchOptions", "spiral", spiral.name, "an assembly scenario flown by controller assembly");
  }
  if (spiral.assembly->num_units != 6) {
    ThrowInvalidArgument("MarsBenchOptions", "spiral", spiral.name, "the 3x2 assembly of Table I (six units)");
  }
}

nlohmann::json RunMarsBenchmark(const MarsBenchOptions& o) {
  o.Validate();
  const std::vector<FaultCase> cases = TableOneCases();
  const int methods = static_cast<int>(kMethods.size());
  const int total = static_cast<int>(cases.size()) * methods * o.trials;
  std::vector<Flight> flights(static_cast<std::size_t>(total));
  ParallelFor(total, o.jobs, [&](int task) {
    const int trial = task % o.trials, method = (task / o.trials) % methods, row = task / (o.trials * methods);
    // Every method and row flies the same seeds: the rows differ by their faults only.
    flights[static_cast<std::size_t>(task)] = FlyOnce(WithFaults(o.spiral, cases[row], kMethods[method], o.seed + trial));
  }, o.progress);

  nlohmann::json table1 = nlohmann::json::array();
  double fault_free = 0.0;
  bool within = true;
  for (std::size_t row = 0; row < cases.size(); ++row) {
    // Whether the rotors that still deliver can hold the assembly's weight at all (the allocator's
    // exact QP): a case that cannot hover is reported, not held against the target.
    modular::AssemblyAllocator check(*o.spiral.assembly, {});
    RotorVector eta = RotorVector::Ones(o.spiral.vehicle.num_rotors());
    for (const auto& [rotor, loss] : cases[row].rotors) eta[rotor] = 1.0 - loss;
    check.SetEffectiveness(eta);
    RotorVector hover;
    const bool can_hover = check.Allocate(Eigen::Vector4d(o.spiral.vehicle.weight_n(), 0, 0, 0), &hover).attainable;
    nlohmann::json r = {{"case", cases[row].name}, {"hover_attainable", can_hover}};
    nlohmann::json faults = nlohmann::json::array();
    for (const auto& [rotor, loss] : cases[row].rotors) faults.push_back({{"rotor", rotor}, {"loss", loss}});
    r["faults"] = faults;
    for (int m = 0; m < methods; ++m) {
      double rmse = 0.0, max_error = 0.0;
      int success = 0;
      for (int t = 0; t < o.trials; ++t) {
        const Flight& f = flights[static_cast<std::size_t>((static_cast<int>(row) * methods + m) * o.trials + t)];
        rmse += f.rmse / o.trials;
        max_error = std::max(max_error, f.max_error);
        success += f.success;
      }
      const std::string name(modular::ToString(kMethods[m]));
      r[name + "_error_m"] = rmse;
      r[name + "_max_error_m"] = max_error;
      r[name + "_success_rate"] = static_cast<double>(success) / o.trials;
    }
    if (row == 0) fault_free = r["full_error_m"].get<double>();
    r["full_over_fault_free"] = fault_free > 0.0 ? r["full_error_m"].get<double>() / fault_free : 0.0;
    if (can_hover) {
      within = within && r["full_over_fault_free"].get<double>() <= 1.5 && r["full_success_rate"].get<double>() == 1.0;
    }
    table1.push_back(r);
  }
  const auto [alloc_mean, alloc_p99] = TimeAllocation(o.nine_units, o.alloc_samples, o.seed);
  nlohmann::json reconfig = nullptr;
  if (o.reconfigure.assembly) {
    // Self-reconfiguration, prepared (the split allocation blended in) and naive, on the same seeds.
    std::vector<ReconfigurationResult> runs(static_cast<std::size_t>(2 * o.trials));
    ParallelFor(2 * o.trials, o.jobs, [&](int task) {
      ReconfigurationOptions r;
      r.base = o.reconfigure;
      r.base.seed = o.seed + static_cast<std::uint64_t>(task / 2);
      r.naive = task % 2 == 1;
      try {
        runs[static_cast<std::size_t>(task)] = RunReconfiguration(r);
      } catch (const std::exception& e) {
        runs[static_cast<std::size_t>(task)].failure = std::string("error: ") + e.what();
      }
    }, nullptr);
    nlohmann::json variants;
    for (int v = 0; v < 2; ++v) {
      double sep = 0.0, dock = 0.0, sep_acc = 0.0, dock_acc = 0.0, unit_tilt = 0.0, steady = 0.0;
      int success = 0;
      std::string failure;
      for (int t = 0; t < o.trials; ++t) {
        const ReconfigurationResult& r = runs[static_cast<std::size_t>(2 * t + v)];
        success += r.success;
        if (!r.success && failure.empty()) failure = r.failure;
        sep = std::max(sep, r.separation_max_attitude_deg);
        dock = std::max(dock, r.docking_max_attitude_deg);
        sep_acc = std::max(sep_acc, r.separation_max_accel_m_s2);
        dock_acc = std::max(dock_acc, r.docking_max_accel_m_s2);
        unit_tilt = std::max(unit_tilt, r.unit_max_tilt_deg);
        steady = std::max(steady, r.steady_max_attitude_deg);
      }
      variants[v == 0 ? "prepared" : "naive"] = {{"success_rate", static_cast<double>(success) / o.trials},
                                                 {"separation_max_attitude_deg", sep},
                                                 {"docking_max_attitude_deg", dock},
                                                 {"separation_max_accel_m_s2", sep_acc},
                                                 {"docking_max_accel_m_s2", dock_acc},
                                                 {"unit_max_tilt_deg", unit_tilt},
                                                 {"steady_max_attitude_deg", steady},
                                                 {"first_failure", failure}};
    }
    reconfig = variants;
  }
  const nlohmann::json table2 = o.plan_4x1.assembly_plan && o.plan_3x2.assembly_plan ? RunTableTwo(o) : nlohmann::json();
  nlohmann::json failures = nlohmann::json::array();
  for (int task = 0; task < total && failures.size() < 10; ++task) {
    const Flight& f = flights[static_cast<std::size_t>(task)];
    if (f.success || kMethods[(task / o.trials) % methods] == modular::Reallocation::kNone) continue;
    failures.push_back({{"case", cases[task / (o.trials * methods)].name},
                        {"method", modular::ToString(kMethods[(task / o.trials) % methods])},
                        {"seed", o.seed + task % o.trials},
                        {"reason", f.failure}});
  }
  nlohmann::json result = {{"benchmark", "mars"},
          {"assembly", o.spiral.assembly->name},
          {"trials", o.trials},
          {"table1", table1},
          {"table1_full_within_1_5x_fault_free", within},
          {"alloc_units", o.nine_units.num_units},
          {"alloc_us_mean", alloc_mean},
          {"alloc_us_p99", alloc_p99},
          {"reconfig", reconfig},
          {"reconfig_max_attitude_deg",
           reconfig.is_null() ? nlohmann::json(nullptr)
                              : nlohmann::json(std::max(reconfig["prepared"]["separation_max_attitude_deg"].get<double>(),
                                                        reconfig["prepared"]["docking_max_attitude_deg"].get<double>()))},
          {"reconfig_max_attitude_deg_naive",
           reconfig.is_null() ? nlohmann::json(nullptr)
                              : nlohmann::json(std::max(reconfig["naive"]["separation_max_attitude_deg"].get<double>(),
                                                        reconfig["naive"]["docking_max_attitude_deg"].get<double>()))},
          {"failures", failures}};
  for (const char* key : {"table2", "table2_rows_compared", "table2_improvement_average",
                          "table2_improvement_row_mean", "table2_ours_better_in_every_row"}) {
    result[key] = table2.is_null() ? nlohmann::json(nullptr) : table2[key];
  }
  return result;
}

std::string MarsMarkdown(const nlohmann::json& r) {
  std::string s = fmt::format("Table I ({} assembly on the spiral, {} flights per cell: mean tracking RMSE, "
                              "success rate)\n\n",
                              r["assembly"].get<std::string>(), r["trials"].get<int>());
  s += "| case | without FTC | partial (eqs. 3-5) | full (eq. 6) | full / fault-free |\n|---|---|---|---|---|\n";
  for (const auto& row : r["table1"]) {
    const auto cell = [&](const char* m) {
      return fmt::format("{:.3f} m ({:.0f} %)", row[std::string(m) + "_error_m"].get<double>(),
                         100.0 * row[std::string(m) + "_success_rate"].get<double>());
    };
    s += fmt::format("| {}{} | {} | {} | {} | {:.2f} |\n", row["case"].get<std::string>(),
                     row["hover_attainable"].get<bool>() ? "" : " (cannot hover: beyond the rotors' reach)",
                     cell("none"), cell("partial"), cell("full"), row["full_over_fault_free"].get<double>());
  }
  s += fmt::format("\nallocation ({} units, full reallocation with a dead unit): {:.1f} us mean, {:.1f} us p99\n",
                   r["alloc_units"].get<int>(), r["alloc_us_mean"].get<double>(), r["alloc_us_p99"].get<double>());
  if (!r["reconfig"].is_null()) {
    s += "\nSelf-reconfiguration (largest over the trials)\n\n| switch | success | steady hover | separation | docking | "
         "unit's tilt |\n|---|---|---|---|---|---|\n";
    for (const char* v : {"prepared", "naive"}) {
      const nlohmann::json& x = r["reconfig"][v];
      s += fmt::format("| {} | {:.0f} % | {:.2f} deg | {:.2f} deg, {:.2f} m/s^2 | {:.2f} deg, {:.2f} m/s^2 | {:.1f} deg |\n", v,
                       100.0 * x["success_rate"].get<double>(), x["steady_max_attitude_deg"].get<double>(),
                       x["separation_max_attitude_deg"].get<double>(),
                       x["separation_max_accel_m_s2"].get<double>(), x["docking_max_attitude_deg"].get<double>(),
                       x["docking_max_accel_m_s2"].get<double>(), x["unit_max_tilt_deg"].get<double>());
    }
  }
  if (!r["table2"].is_null()) {
    s += "\nTable II (planned by each method, flown with the full reallocation: mean tracking RMSE, success rate, "
         "the trajectory's duration)\n\n| shape | fault | baseline (SVSDF) | ours | improvement |\n|---|---|---|---|---|\n";
    for (const auto& row : r["table2"]) {
      const auto cell = [&](const std::string& m) {
        if (!row[m + "_planned"].get<bool>()) return "no plan: " + row[m + "_plan_failure"].get<std::string>();
        return fmt::format("{:.3f} m ({:.0f} %, {:.1f} s)", row[m + "_error_m"].get<double>(),
                           100.0 * row[m + "_success_rate"].get<double>(), row[m + "_duration_s"].get<double>());
      };
      s += fmt::format("| {} | {} | {} | {} | {} |\n", row["shape"].get<std::string>(),
                       row["fault"].get<std::string>(), cell("baseline"), cell("ours"),
                       row["improvement"].is_null() ? std::string("-")
                                                    : fmt::format("{:.1f} %", 100.0 * row["improvement"].get<double>()));
    }
    const auto percent = [](const nlohmann::json& v) {
      return v.is_null() ? std::string("-") : fmt::format("{:.1f} %", 100.0 * v.get<double>());
    };
    s += fmt::format("\naverage improvement {} (1 - mean ours / mean baseline, the paper's Average row; {} as the "
                     "mean of the rows'); ours better in every row: {}\n",
                     percent(r["table2_improvement_average"]), percent(r["table2_improvement_row_mean"]),
                     r["table2_ours_better_in_every_row"].get<bool>() ? "yes" : "no");
  }
  return s;
}

}  // namespace rotorguard::bench
