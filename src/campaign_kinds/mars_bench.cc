#include "rotorguard/campaign_kinds/mars_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <mutex>
#include <numbers>

#include "rotorguard/campaign_kinds/reconfiguration.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/harness/assembly_mission.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/modular/allocation.h"
#include "rotorguard/sim/truth.h"

namespace rotorguard::benchmarks {

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

harness::Scenario WithFaults(const harness::Scenario& base, const FaultCase& c, modular::Reallocation method, std::uint64_t seed) {
  harness::Scenario s = base;
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
  return {mean, Percentile(us, 0.99)};
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
  /// The tilt's angular acceleration about the body's x and y axes: near hover the horizontal
  /// snap in the yaw's frame over g (y's snap needs roll, x's pitch).
  double roll_accel = 0.0, pitch_accel = 0.0;
};
PlanDemands DemandsOf(const modular::AssemblyTrajectory& t) {
  PlanDemands d;
  const planning::MinimumJerkTrajectory& p = t.position();
  for (int i = 0; i < p.pieces(); ++i) {
    for (double time = 0.0; time <= p.durations()(i); time += 1e-3) {
      Vector3 a = p.PieceDerivative(i, time, 2);
      d.accel = std::max(d.accel, a.norm());
      a.z() += kGravity;
      d.thrust_accel = std::max(d.thrust_accel, a.norm());
      d.yaw_accel = std::max(d.yaw_accel, std::abs(t.yaw().PieceDerivative(i, time, 2).x()));
      const Vector3 snap = QuaternionFromYaw(t.yaw().PieceDerivative(i, time, 0).x()).inverse() *
                           p.PieceDerivative(i, time, 4);
      d.roll_accel = std::max(d.roll_accel, std::abs(snap.y()) / kGravity);
      d.pitch_accel = std::max(d.pitch_accel, std::abs(snap.x()) / kGravity);
    }
  }
  return d;
}

/// A row of Table II: a scene and the unit that is dead in it.
struct PlanRow {
  const harness::Scenario* scene;
  std::string fault;
  int dead_unit;  ///< paper's No.; 0: none
};
constexpr int kTableTwoRows = 5;
std::array<PlanRow, kTableTwoRows> TableTwoRows(const MarsBenchOptions& o) {
  return {{{&o.plan_4x1, "normal", 0}, {&o.plan_4x1, "No. 3", 3}, {&o.plan_4x1, "No. 4", 4},
           {&o.plan_3x2, "normal", 0}, {&o.plan_3x2, "No. 2", 2}}};
}
constexpr harness::AssemblyPlanMethod kPlanners[2] = {harness::AssemblyPlanMethod::kBaseline,
                                                      harness::AssemblyPlanMethod::kOurs};
constexpr int kPlanSlots = 2 * kTableTwoRows;  ///< a plan per row and planner
constexpr const char* kSwitches[2] = {"prepared", "naive"};

/// How far a Table II trial moves its start and goal, each horizontal axis uniformly in ± this [m]:
/// each row is many plans, not one deterministic plan whose outcome could hang on a rounding.
/// Trial 0 flies the scenario as written.
constexpr double kPlanPerturbationM = 0.1;

/// Row `row`'s scenario for trial `seed`, planned by `planner`: the start and goal moved by the
/// trial's draw (the same for both planners), the plan made (a failure is the trial's), and what it
/// asks of the assembly.
struct PlannedTrial {
  harness::Scenario scene;
  harness::AssemblyPlanResult plan;
  PlanDemands demands;
};
PlannedTrial PlanTrial(const PlanRow& row, harness::AssemblyPlanMethod planner, int trial, std::uint64_t seed) {
  const FaultCase fault{row.fault, row.dead_unit > 0 ? DeadUnit(row.dead_unit) : std::vector<std::pair<int, double>>{}};
  PlannedTrial t;
  t.scene = WithFaults(*row.scene, fault, modular::Reallocation::kFull, seed);
  Rng rng(DeriveSeed(seed, 0x706c616eULL));  // "plan"
  const auto shift = [&rng] {
    const double x = rng.Uniform(-kPlanPerturbationM, kPlanPerturbationM);
    return Vector3(x, rng.Uniform(-kPlanPerturbationM, kPlanPerturbationM), 0.0);
  };
  if (trial > 0) {
    t.scene.initial_position_m += shift();
    t.scene.assembly_plan->goal_m += shift();
  }
  t.scene.assembly_plan->method = planner;
  t.plan = harness::PlanAssemblyMission(t.scene);  // never throws: a failure is the trial's
  if (t.plan.ok) {
    t.scene.reference = t.plan.trajectory;
    t.demands = DemandsOf(*t.plan.trajectory);
  }
  return t;
}

/// The records of `part`, in trial order.
std::vector<const nlohmann::json*> PartOf(const std::vector<nlohmann::json>& records, const std::string& part) {
  std::vector<const nlohmann::json*> r;
  for (const nlohmann::json& x : records) {
    if (x["params"]["part"] == part) r.push_back(&x);
  }
  return r;
}

/// A record's metric, or `fallback` when the trial did not record it (an error).
double MetricOr(const nlohmann::json& record, const char* key, double fallback) {
  const nlohmann::json& m = record["metrics"];
  return m.is_object() && m.contains(key) && m[key].is_number() ? m[key].get<double>() : fallback;
}
bool Succeeded(const nlohmann::json& record) {
  return record["status"] == "ok" && record["metrics"].value("success", false);
}

/// A table cell from its flights: the mean error over the window (a wreck held) and up to the
/// crash, the largest error, the success rate, the first failure.
struct Cell {
  double error_m = 0.0, error_to_crash_m = 0.0, max_error_m = 0.0, success_rate = 0.0;
  std::string first_failure;
};
Cell CellOf(const std::vector<const nlohmann::json*>& flights) {
  Cell c;
  int success = 0;
  const double n = static_cast<double>(flights.size());
  for (const nlohmann::json* f : flights) {
    c.error_m += MetricOr(*f, "rmse_m", 0.0) / n;
    c.error_to_crash_m += MetricOr(*f, "rmse_flown_m", 0.0) / n;
    c.max_error_m = std::max(c.max_error_m, MetricOr(*f, "max_error_m", 0.0));
    success += Succeeded(*f);
    if (!Succeeded(*f) && c.first_failure.empty()) c.first_failure = campaign::TrialFailure(*f);
  }
  c.success_rate = flights.empty() ? 0.0 : success / n;
  return c;
}
/// records[first, first + count).
std::vector<const nlohmann::json*> Slice(const std::vector<const nlohmann::json*>& records, std::size_t first,
                                         int count) {
  const auto begin = records.begin() + static_cast<std::ptrdiff_t>(first);
  return {begin, begin + count};
}
/// The cell's figures as row[name + "_error_m"], ..._error_to_crash_m, ..._max_error_m, ..._success_rate.
void WriteCell(const Cell& c, const std::string& name, nlohmann::json* row) {
  (*row)[name + "_error_m"] = c.error_m;
  (*row)[name + "_error_to_crash_m"] = c.error_to_crash_m;
  (*row)[name + "_max_error_m"] = c.max_error_m;
  (*row)[name + "_success_rate"] = c.success_rate;
}

}  // namespace

double TruthThrustAcceleration(const harness::Scenario& s) {
  modular::Assembly truth = *s.assembly;
  const sim::TruthDraw draw = sim::DrawTruth(s.truth, s.vehicle, s.seed);
  truth.vehicle = sim::TruthVehicle(s.vehicle, draw);
  const RotorVector ratio = sim::ThrustRatios(draw);
  RotorVector eta = RotorVector::Ones(truth.vehicle.num_rotors());
  for (int i = 0; i < truth.vehicle.num_rotors(); ++i) {
    truth.vehicle.rotors[static_cast<std::size_t>(i)].max_thrust_n *= ratio[i];
  }
  for (const sim::FaultSpec& f : s.faults) {
    if (f.kind == vehicle::FaultKind::kMotorStop) eta[f.rotor] = 0.0;  // Table II's dead units
  }
  const modular::AssemblyCapacity c = modular::CapacityOf(truth, eta);
  return c.hover_attainable ? c.max_thrust_n / truth.vehicle.mass_kg : 0.0;
}

void MarsBenchOptions::Validate() const {
  if (trials < 1 || trials > 10000) ThrowInvalidArgument("MarsBenchOptions", "trials", trials, "a count in [1, 10000]");
  if (jobs < 1 || jobs > 256) ThrowInvalidArgument("MarsBenchOptions", "jobs", jobs, "a count in [1, 256]");
  if (alloc_samples < 100 || alloc_samples > 10'000'000) {
    ThrowInvalidArgument("MarsBenchOptions", "alloc_samples", alloc_samples, "a count in [100, 10^7]");
  }
  if (!spiral.assembly || spiral.stack.controller != stack::ControllerKind::kAssembly) {
    ThrowInvalidArgument("MarsBenchOptions", "spiral", spiral.name, "an assembly scenario flown by controller assembly");
  }
  if (spiral.assembly->num_units != 6) {
    ThrowInvalidArgument("MarsBenchOptions", "spiral", spiral.name, "the 3x2 assembly of Table I (six units)");
  }
}

namespace {

/// Where a trial index falls: bench mars's trials are, in order, the allocation's timing (one
/// trial), Table I (case, method, trial), the self-reconfiguration (trial, switch) and Table II
/// (row, planner, trial), the trial varying fastest in each. One decoder for the trial's parameters
/// and its run.
struct MarsTrial {
  enum class Part { kAlloc, kTableOne, kReconfig, kTableTwo } part = Part::kAlloc;
  int row = 0;     ///< Table I's case or Table II's row
  int method = 0;  ///< kMethods (Table I), kPlanners (Table II), kSwitches (reconfiguration)
  int trial = 0;   ///< the repetition; every row and method flies the same seeds
};

MarsTrial DecodeMarsTrial(int index, int trials, int table_one_trials, int reconfig_trials) {
  MarsTrial d;
  if (index == 0) return d;
  int k = index - 1;
  if (k < table_one_trials) {
    const int methods = static_cast<int>(kMethods.size());
    return {MarsTrial::Part::kTableOne, k / (trials * methods), (k / trials) % methods, k % trials};
  }
  k -= table_one_trials;
  if (k < reconfig_trials) return {MarsTrial::Part::kReconfig, 0, k % 2, k / 2};
  k -= reconfig_trials;
  const int slot = k / trials;  // row * 2 + planner
  return {MarsTrial::Part::kTableTwo, slot / 2, slot % 2, k % trials};
}

}  // namespace

campaign::Campaign MarsCampaign(const MarsBenchOptions& options_in) {
  options_in.Validate();
  MarsBenchOptions o = options_in;  // every scenario flies the options' world
  for (harness::Scenario* s : {&o.spiral, &o.reconfigure, &o.plan_4x1, &o.plan_3x2}) s->truth.preset = o.truth;
  const std::vector<FaultCase> cases = TableOneCases();
  const bool reconfig = o.reconfigure.assembly != nullptr;
  const bool table2 = o.plan_4x1.assembly_plan && o.plan_3x2.assembly_plan;
  // Parts in trial order: the allocation's timing (one trial), Table I (case, method, trial), the
  // self-reconfiguration (trial, switch) and Table II (row, planner, trial).
  const int n1 = static_cast<int>(cases.size() * kMethods.size()) * o.trials;
  const int n2 = reconfig ? 2 * o.trials : 0;
  const int n3 = table2 ? kPlanSlots * o.trials : 0;
  campaign::Campaign c;
  c.name = "bench_mars";
  c.seed = o.seed;
  c.trials = 1 + n1 + n2 + n3;
  c.group_keys = {"part", "case", "shape", "fault", "method", "variant"};
  c.metrics = {"success", "rmse_m", "max_error_m", "separation_max_attitude_deg", "docking_max_attitude_deg",
               "alloc_us_mean"};
  const nlohmann::json options = {{"trials", o.trials},
                                  {"seed", o.seed},
                                  {"alloc_samples", o.alloc_samples},
                                  {"assembly", o.spiral.assembly->name},
                                  {"alloc_units", o.nine_units.num_units},
                                  {"reconfigure", reconfig},
                                  {"table2", table2},
                                  {"truth", ToName(o.truth)}};
  // Records version 4: each Table II trial plans its own perturbed start and goal, the baseline
  // under the same yaw-rate limit (v3: one plan per row and planner, a crashed flight's wreck held
  // over the plan's window; v1: to the crash; v2: scored over the window of the plan the scene was
  // loaded with).
  c.bench = {{"name", "mars"}, {"records", 4}, {"options", options}, {"seed_stream", "bench mars"}};
  std::string inputs = c.bench.dump() + "\n" + harness::ScenarioFingerprint(o.spiral) + harness::VehicleToYaml(o.nine_units.vehicle);
  if (reconfig) inputs += harness::ScenarioFingerprint(o.reconfigure);
  if (table2) inputs += harness::ScenarioFingerprint(o.plan_4x1) + harness::ScenarioFingerprint(o.plan_3x2);
  c.hash = campaign::Fingerprint(inputs);
  const int trials = o.trials;
  c.parameters = [o, cases, n1, n2, trials](int index) -> std::map<std::string, std::string> {
    const MarsTrial d = DecodeMarsTrial(index, trials, n1, n2);
    // Every row and method flies the same seeds: the rows differ by their faults only.
    const std::string seed = std::to_string(TrialSeed(o.seed, "bench mars", static_cast<std::uint64_t>(d.trial)));
    const auto at = [](int i) { return static_cast<std::size_t>(i); };
    switch (d.part) {
      case MarsTrial::Part::kAlloc:
        return {{"part", "alloc"}, {"seed", std::to_string(o.seed)}};
      case MarsTrial::Part::kTableOne:
        return {{"part", "table1"}, {"case", cases[at(d.row)].name}, {"method", std::string(ToName(kMethods[at(d.method)]))},
                {"trial", std::to_string(d.trial)}, {"seed", seed}};
      case MarsTrial::Part::kReconfig:
        return {{"part", "reconfig"}, {"variant", kSwitches[at(d.method)]}, {"trial", std::to_string(d.trial)}, {"seed", seed}};
      case MarsTrial::Part::kTableTwo: {
        const PlanRow row = TableTwoRows(o)[at(d.row)];
        return {{"part", "table2"}, {"shape", row.scene->assembly->name}, {"fault", row.fault},
                {"method", ToName(kPlanners[at(d.method)])}, {"trial", std::to_string(d.trial)}, {"seed", seed}};
      }
    }
    return {};
  };
  // The flights' simulated time, for the watchdog: Table II's comes from its plan, made inside
  // the trial, and those trials run without a budget.
  c.simulated_s = [o](int, const std::map<std::string, std::string>& params) {
    const std::string part = params.at("part");
    if (part == "table1") return o.spiral.duration_s;
    if (part == "reconfig") return o.reconfigure.duration_s;
    return 0.0;
  };
  c.run = [o, cases, n1, n2, trials](int index, const std::map<std::string, std::string>& params) {
    campaign::TrialOutcome out;
    const std::uint64_t seed = std::stoull(params.at("seed"));
    const std::string part = params.at("part");
    if (part == "alloc") {
      const auto [mean, p99] = TimeAllocation(o.nine_units, o.alloc_samples, seed);
      out.metrics = {{"alloc_us_mean", mean}, {"alloc_us_p99", p99}};
      return out;
    }
    harness::RunSummary r;
    const MarsTrial d = DecodeMarsTrial(index, trials, n1, n2);
    if (part == "table1") {
      const FaultCase& fault = cases[static_cast<std::size_t>(d.row)];
      // Whether the rotors that still deliver can hold the assembly's weight at all (the
      // allocator's exact QP): a case that cannot hover is reported, not held against the target.
      modular::AssemblyAllocator check(*o.spiral.assembly, {});
      RotorVector eta = RotorVector::Ones(o.spiral.vehicle.num_rotors());
      for (const auto& [rotor, loss] : fault.rotors) eta[rotor] = 1.0 - loss;
      check.SetEffectiveness(eta);
      RotorVector hover;
      out.metrics["hover_attainable"] =
          check.Allocate(Eigen::Vector4d(o.spiral.vehicle.weight_n(), 0, 0, 0), &hover).attainable;
      r = harness::RunScenario(WithFaults(o.spiral, fault, kMethods[static_cast<std::size_t>(d.method)], seed), harness::RunOptions{});
    } else if (part == "reconfig") {
      ReconfigurationOptions ro;
      ro.base = o.reconfigure;
      ro.base.seed = seed;
      ro.naive = params.at("variant") == kSwitches[1];
      const ReconfigurationResult x = RunReconfiguration(ro);
      out.metrics = {{"success", x.success},
                     {"separation_max_attitude_deg", x.separation_max_attitude_deg},
                     {"docking_max_attitude_deg", x.docking_max_attitude_deg},
                     {"separation_max_accel_m_s2", x.separation_max_accel_m_s2},
                     {"docking_max_accel_m_s2", x.docking_max_accel_m_s2},
                     {"unit_max_tilt_deg", x.unit_max_tilt_deg},
                     {"steady_max_attitude_deg", x.steady_max_attitude_deg},
                     {"steady_max_accel_m_s2", x.steady_max_accel_m_s2}};
      out.message = x.failure;
      return out;
    } else {
      const PlannedTrial t = PlanTrial(TableTwoRows(o)[static_cast<std::size_t>(d.row)],
                                       kPlanners[static_cast<std::size_t>(d.method)], d.trial, seed);
      const harness::AssemblyPlanResult& plan = t.plan;
      out.metrics["planned"] = plan.ok;
      // Whether the drawn assembly can hover at all (a bound on the row's success, plan or not).
      out.metrics["truth_capacity_thrust_accel_m_s2"] = TruthThrustAcceleration(t.scene);
      if (!plan.ok) {
        out.message = plan.message;
        return out;
      }
      // What the plan asks of the assembly, beside what it can give (the mechanism of the rows).
      const PlanDemands& demands = t.demands;
      out.metrics["duration_s"] = plan.trajectory_summary.duration_s;
      out.metrics["attitude_deviation_deg"] = plan.trajectory_summary.attitude_deviation_rad * 180.0 / std::numbers::pi;
      out.metrics["plan_ms"] = plan.astar_ms + plan.trajectory_summary.solve_ms;
      out.metrics["max_accel_m_s2"] = demands.accel;
      out.metrics["max_thrust_accel_m_s2"] = demands.thrust_accel;
      out.metrics["max_yaw_accel_rad_s2"] = demands.yaw_accel;
      out.metrics["max_roll_accel_rad_s2"] = demands.roll_accel;
      out.metrics["max_pitch_accel_rad_s2"] = demands.pitch_accel;
      out.metrics["capacity_accel_m_s2"] = plan.capacity.max_acceleration_m_s2;
      out.metrics["capacity_thrust_accel_m_s2"] = plan.capacity.max_thrust_n / t.scene.vehicle.mass_kg;
      out.metrics["capacity_yaw_accel_rad_s2"] = plan.capacity.max_yaw_acceleration_rad_s2;
      out.metrics["capacity_roll_accel_rad_s2"] = plan.capacity.max_roll_acceleration_rad_s2;
      out.metrics["capacity_pitch_accel_rad_s2"] = plan.capacity.max_pitch_acceleration_rad_s2;
      const harness::Scenario& s = t.scene;
      r = harness::RunScenario(s, harness::RunOptions{});
    }
    out.metrics["success"] = r.success;
    out.metrics["rmse_m"] = r.tracking_rmse_window_m;  // a crashed flight's wreck counts to the window's end
    out.metrics["rmse_flown_m"] = r.tracking_rmse_m;
    out.metrics["max_error_m"] = r.max_position_error_m;
    out.message = r.failure_reason.value_or("");
    return out;
  };
  return c;
}

namespace {

/// Table I from its records: (case, method, trial), the trial fastest.
nlohmann::json TableOne(const std::vector<const nlohmann::json*>& records, int trials, bool* within) {
  nlohmann::json table1 = nlohmann::json::array();
  const std::vector<FaultCase> cases = TableOneCases();
  const int methods = static_cast<int>(kMethods.size());
  if (records.size() != cases.size() * static_cast<std::size_t>(methods * trials)) {
    throw std::invalid_argument(fmt::format("mars: {} Table I records for {} cases x {} methods x {} trials",
                                            records.size(), cases.size(), methods, trials));
  }
  double fault_free = 0.0;
  *within = true;
  for (std::size_t row = 0; row < cases.size(); ++row) {
    // Every trial of the row records the allocator's verdict; one that threw records nothing.
    bool can_hover = false;
    for (std::size_t k = 0; k < static_cast<std::size_t>(methods * trials); ++k) {
      const nlohmann::json& m = records[row * static_cast<std::size_t>(methods * trials) + k]->at("metrics");
      if (m.is_object() && m.contains("hover_attainable")) {
        can_hover = m.at("hover_attainable").get<bool>();
        break;
      }
    }
    nlohmann::json r = {{"case", cases[row].name}, {"hover_attainable", can_hover}};
    nlohmann::json faults = nlohmann::json::array();
    for (const auto& [rotor, loss] : cases[row].rotors) faults.push_back({{"rotor", rotor}, {"loss", loss}});
    r["faults"] = faults;
    for (int m = 0; m < methods; ++m) {
      const std::size_t first =
          (row * static_cast<std::size_t>(methods) + static_cast<std::size_t>(m)) * static_cast<std::size_t>(trials);
      WriteCell(CellOf(Slice(records, first, trials)), std::string(ToName(kMethods[static_cast<std::size_t>(m)])), &r);
    }
    if (row == 0) fault_free = r["full_error_m"].get<double>();
    r["full_over_fault_free"] = fault_free > 0.0 ? r["full_error_m"].get<double>() / fault_free : 0.0;
    if (can_hover) {
      *within = *within && r["full_over_fault_free"].get<double>() <= 1.5 && r["full_success_rate"].get<double>() == 1.0;
    }
    table1.push_back(r);
  }
  return table1;
}

/// The self-reconfiguration from its records: (trial, switch), the switch fastest; the largest
/// figures over the trials.
nlohmann::json Reconfiguration(const std::vector<const nlohmann::json*>& records, int trials) {
  if (records.size() != static_cast<std::size_t>(2 * trials)) {
    throw std::invalid_argument(fmt::format("mars: {} reconfiguration records for {} trials x 2", records.size(), trials));
  }
  nlohmann::json variants;
  for (int v = 0; v < 2; ++v) {
    nlohmann::json x = {{"success_rate", 0.0}, {"first_failure", ""}};
    int success = 0;
    for (const char* key : {"separation_max_attitude_deg", "docking_max_attitude_deg", "separation_max_accel_m_s2",
                            "docking_max_accel_m_s2", "unit_max_tilt_deg", "steady_max_attitude_deg",
                            "steady_max_accel_m_s2"}) {
      std::vector<double> values;  // over the flights that got as far as the figure (a failure's is 0)
      for (int t = 0; t < trials; ++t) {
        const nlohmann::json& r = *records[static_cast<std::size_t>(2 * t + v)];
        if (Succeeded(r)) values.push_back(MetricOr(r, key, 0.0));
      }
      x[key] = values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
      x[std::string(key) + "_median"] = values.empty() ? 0.0 : Percentile(values, 0.5);
    }
    for (int t = 0; t < trials; ++t) {
      const nlohmann::json& r = *records[static_cast<std::size_t>(2 * t + v)];
      success += Succeeded(r);
      if (!Succeeded(r) && x["first_failure"] == "") x["first_failure"] = campaign::TrialFailure(r);
    }
    x["success_rate"] = static_cast<double>(success) / trials;
    variants[kSwitches[v]] = x;
  }
  return variants;
}

}  // namespace

// Each trial plans its own (perturbed) start and goal with both planners: a method's cell is over
// the flights it could plan (its plan rate beside), the comparison over the trials both planned.
nlohmann::json MarsTableTwo(const std::vector<const nlohmann::json*>& records, int trials) {
  nlohmann::json table = nlohmann::json::array();
  double sum[2] = {0.0, 0.0}, sum_to_crash[2] = {0.0, 0.0}, improvement_sum = 0.0;
  int compared = 0;
  bool all_better = true;
  if (records.size() != static_cast<std::size_t>(kPlanSlots * trials)) {
    throw std::invalid_argument(fmt::format("mars: {} Table II records for {} rows x 2 planners x {} trials",
                                            records.size(), kTableTwoRows, trials));
  }
  const auto planned = [](const nlohmann::json& x) {
    return x.at("status") == "ok" && x.at("metrics").value("planned", false);
  };
  for (std::size_t row = 0; row < static_cast<std::size_t>(kTableTwoRows); ++row) {
    const auto at = [&](int m, int t) -> const nlohmann::json& {
      return *records[(2 * row + static_cast<std::size_t>(m)) * static_cast<std::size_t>(trials) +
                      static_cast<std::size_t>(t)];
    };
    nlohmann::json r = {{"shape", at(0, 0).at("params").at("shape")}, {"fault", at(0, 0).at("params").at("fault")}};
    std::vector<const nlohmann::json*> paired[2];  // the flights of the trials both methods planned
    for (int t = 0; t < trials; ++t) {
      if (!planned(at(0, t)) || !planned(at(1, t))) continue;
      for (int m = 0; m < 2; ++m) paired[m].push_back(&at(m, t));
    }
    // The trials whose drawn assembly can hover at all (both methods fly the same draw): no method
    // can succeed in the others, so the row's success is bounded by their share.
    int hover_capable = 0, hover_capable_success[2] = {0, 0};
    for (int t = 0; t < trials; ++t) {
      const double capacity = std::max(MetricOr(at(0, t), "truth_capacity_thrust_accel_m_s2", 0.0),
                                       MetricOr(at(1, t), "truth_capacity_thrust_accel_m_s2", 0.0));
      if (!(capacity > kGravity)) continue;
      ++hover_capable;
      for (int m = 0; m < 2; ++m) hover_capable_success[m] += Succeeded(at(m, t));
    }
    r["hover_capable_trials"] = hover_capable;
    for (int m = 0; m < 2; ++m) {
      r[std::string(ToName(kPlanners[m])) + "_success_rate_hover_capable"] =
          hover_capable > 0 ? nlohmann::json(static_cast<double>(hover_capable_success[m]) / hover_capable) : nlohmann::json();
    }
    for (int m = 0; m < 2; ++m) {
      const std::string name = ToName(kPlanners[m]);
      std::vector<const nlohmann::json*> flown;
      for (int t = 0; t < trials; ++t) {
        if (planned(at(m, t))) flown.push_back(&at(m, t));
      }
      r[name + "_planned"] = !flown.empty();
      r[name + "_plan_rate"] = static_cast<double>(flown.size()) / trials;
      for (int t = 0; t < trials; ++t) {
        if (planned(at(m, t))) continue;
        r[name + "_plan_failure"] = at(m, t).at("status") == "ok" ? at(m, t).at("message").get<std::string>()
                                                                  : campaign::TrialFailure(at(m, t));
        break;
      }
      if (flown.empty()) continue;
      Cell c = CellOf(flown);
      c.success_rate *= static_cast<double>(flown.size()) / trials;  // a trial without a plan failed
      WriteCell(c, name, &r);
      r[name + "_first_failure"] = c.first_failure;
      // The plans' figures: their means, and the most any of them asks of the assembly.
      double duration = 0.0, deviation = 0.0, plan_ms = 0.0, accel = 0.0, thrust_accel = 0.0, yaw_accel = 0.0,
             roll_accel = 0.0, pitch_accel = 0.0;
      for (const nlohmann::json* f : flown) {
        const nlohmann::json& x = f->at("metrics");
        duration += x.at("duration_s").get<double>() / static_cast<double>(flown.size());
        deviation += x.at("attitude_deviation_deg").get<double>() / static_cast<double>(flown.size());
        plan_ms += x.at("plan_ms").get<double>() / static_cast<double>(flown.size());
        accel = std::max(accel, x.at("max_accel_m_s2").get<double>());
        thrust_accel = std::max(thrust_accel, x.at("max_thrust_accel_m_s2").get<double>());
        yaw_accel = std::max(yaw_accel, x.at("max_yaw_accel_rad_s2").get<double>());
        roll_accel = std::max(roll_accel, x.at("max_roll_accel_rad_s2").get<double>());
        pitch_accel = std::max(pitch_accel, x.at("max_pitch_accel_rad_s2").get<double>());
        // The assembly's capacity depends on the row alone.
        for (const char* key : {"capacity_accel_m_s2", "capacity_thrust_accel_m_s2", "capacity_yaw_accel_rad_s2",
                                "capacity_roll_accel_rad_s2", "capacity_pitch_accel_rad_s2"}) {
          r[key] = x.at(key);
        }
      }
      r[name + "_duration_s"] = duration;
      r[name + "_attitude_deviation_deg"] = deviation;
      r[name + "_plan_ms"] = plan_ms;
      r[name + "_max_accel_m_s2"] = accel;
      r[name + "_max_thrust_accel_m_s2"] = thrust_accel;
      r[name + "_max_yaw_accel_rad_s2"] = yaw_accel;
      r[name + "_max_roll_accel_rad_s2"] = roll_accel;
      r[name + "_max_pitch_accel_rad_s2"] = pitch_accel;
    }
    // The comparison: the same trials, both planned. A row without one has none: null, left out of
    // the averages.
    r["paired_trials"] = paired[0].size();
    const bool comparable = !paired[0].empty();
    const Cell pair[2] = {CellOf(paired[0]), CellOf(paired[1])};
    all_better = all_better && comparable && pair[1].error_m < pair[0].error_m;
    if (comparable && pair[0].error_m > 0.0) {
      r["improvement"] = 1.0 - pair[1].error_m / pair[0].error_m;
      improvement_sum += r["improvement"].get<double>();
      ++compared;
      for (int m = 0; m < 2; ++m) sum[m] += pair[m].error_m, sum_to_crash[m] += pair[m].error_to_crash_m;
    } else {
      r["improvement"] = nullptr;
    }
    table.push_back(r);
  }
  return {{"table2", table},
          {"table2_rows_compared", compared},
          {"table2_improvement_average", sum[0] > 0.0 ? nlohmann::json(1.0 - sum[1] / sum[0]) : nlohmann::json()},
          {"table2_improvement_row_mean", compared > 0 ? nlohmann::json(improvement_sum / compared) : nlohmann::json()},
          // The average as it would be if a crashed flight's error stopped at the crash.
          {"table2_improvement_average_to_crash",
           sum_to_crash[0] > 0.0 ? nlohmann::json(1.0 - sum_to_crash[1] / sum_to_crash[0]) : nlohmann::json()},
          {"table2_ours_better_in_every_row", all_better}};
}

nlohmann::json MarsResult(const nlohmann::json& options, const std::vector<nlohmann::json>& records) {
  const int trials = options.at("trials").get<int>();
  const std::vector<const nlohmann::json*> alloc = PartOf(records, "alloc"), t1 = PartOf(records, "table1"),
                                           rc = PartOf(records, "reconfig"), t2 = PartOf(records, "table2");
  if (alloc.size() != 1) throw std::invalid_argument(fmt::format("mars: {} allocation timings; expected 1", alloc.size()));
  bool within = true;
  const nlohmann::json table1 = TableOne(t1, trials, &within);
  const nlohmann::json reconfig =
      options.at("reconfigure").get<bool>() ? Reconfiguration(rc, trials) : nlohmann::json();
  const nlohmann::json table2 = options.at("table2").get<bool>() ? MarsTableTwo(t2, trials) : nlohmann::json();
  nlohmann::json failures = nlohmann::json::array();
  for (const nlohmann::json* f : t1) {
    if (failures.size() >= 10) break;
    if (Succeeded(*f) || f->at("params").at("method") == "none") continue;
    failures.push_back({{"case", f->at("params").at("case")},
                        {"method", f->at("params").at("method")},
                        {"seed", std::stoull(f->at("params").at("seed").get<std::string>())},
                        {"reason", campaign::TrialFailure(*f)}});
  }
  const auto worst = [&](const char* variant) {
    return reconfig.is_null()
               ? nlohmann::json(nullptr)
               : nlohmann::json(std::max(reconfig.at(variant).at("separation_max_attitude_deg").get<double>(),
                                         reconfig.at(variant).at("docking_max_attitude_deg").get<double>()));
  };
  nlohmann::json result = {
      {"benchmark", "mars"},
      {"assembly", options.at("assembly")},
      {"trials", trials},
      {"table1", table1},
      {"table1_full_within_1_5x_fault_free", within},
      {"alloc_units", options.at("alloc_units")},
      // Null when the timing trial failed (never a figure that passes the target).
      {"alloc_us_mean",
       alloc[0]->at("status") == "ok" ? alloc[0]->at("metrics").at("alloc_us_mean") : nlohmann::json()},
      {"alloc_us_p99", alloc[0]->at("status") == "ok" ? alloc[0]->at("metrics").at("alloc_us_p99") : nlohmann::json()},
      {"reconfig", reconfig},
      {"reconfig_max_attitude_deg", worst("prepared")},
      {"reconfig_max_attitude_deg_naive", worst("naive")},
      {"failures", failures},
      {"options", options}};
  for (const char* key : {"table2", "table2_rows_compared", "table2_improvement_average", "table2_improvement_row_mean",
                          "table2_improvement_average_to_crash", "table2_ours_better_in_every_row"}) {
    result[key] = table2.is_null() ? nlohmann::json(nullptr) : table2.at(key);
  }
  result["truth"] = options.value("truth", "ideal");  // records made before the key: the ideal world
  return result;
}

nlohmann::json RunMarsBenchmark(const MarsBenchOptions& o) {
  const campaign::Campaign c = MarsCampaign(o);
  return MarsResult(c.bench["options"], campaign::RunWholeCampaign(c, o.jobs, o.progress));
}

}  // namespace rotorguard::benchmarks
