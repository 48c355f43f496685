#include "rotorguard/campaign_kinds/planner_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/world_raster.h"
#include "rotorguard/planning/planner.h"

namespace rotorguard::benchmarks {

namespace {

constexpr double kVehicleRadius = 0.2;  // the reference vehicle's collision radius [m]

/// One kind of world: its generator, the box starts and goals are drawn in, their least distance.
struct Kind {
  std::string name;
  sim::World (*make)(std::uint64_t);
  Vector3 lo, hi;
  double min_distance_m;
  Vector3 window_m;
};

/// One group's accumulated figures.
struct Group {
  std::vector<double> plan_ms;
  double search_ms = 0.0, optimize_ms = 0.0, iterations = 0.0, rounds = 0.0, pieces = 0.0;
  double expansions = 0.0, segment_checks = 0.0;  // the front end's work
  int attempted = 0, no_path = 0, succeeded = 0;
  /// Successful plans that needed the planner's fallbacks (PlanSummary::fine_search, rest_to_rest).
  int fine_search = 0, rest_to_rest = 0;
  double duration_sum = 0.0, max_violation = 0.0;
  std::map<std::string, int> failures;
};

/// Largest relative excess of |v|, |a|, |j| over the limits along the trajectory (2000 samples per
/// piece), 0 when within them; and the smallest distance of the trajectory to a true surface
/// (100 samples per piece, a few cm apart; the ground left out, as the planner keeps a band).
void Check(const planning::MinimumJerkTrajectory& traj, const planning::DynamicLimits& limits, const sim::World& world,
           double* violation, double* clearance) {
  const double limit[3] = {limits.v_max, limits.a_max, limits.j_max};
  *violation = 0.0;
  for (int d = 1; d <= 3; ++d) *violation = std::max(*violation, traj.MaxNorm(d, 2000) / limit[d - 1] - 1.0);
  *clearance = std::numeric_limits<double>::infinity();
  for (int i = 0; i < traj.pieces(); ++i) {
    for (int j = 0; j <= 100; ++j) {
      *clearance = std::min(*clearance, world.DistanceToObstacles(traj.PieceDerivative(i, traj.durations()(i) * j / 100.0, 0), 0.0));
    }
  }
}

nlohmann::json GroupJson(const Group& g) {
  const std::vector<double>& ms = g.plan_ms;
  double mean = 0.0;
  for (double v : ms) mean += v;
  mean = ms.empty() ? 0.0 : mean / static_cast<double>(ms.size());
  const int with_path = g.attempted - g.no_path;
  nlohmann::json failures = nlohmann::json::object();
  for (const auto& [k, v] : g.failures) failures[k] = v;
  return {{"pairs", g.attempted},
          {"pairs_without_path", g.no_path},
          {"success_rate", with_path > 0 ? static_cast<double>(g.succeeded) / with_path : 0.0},
          {"plan_ms_mean", mean},
          {"plan_ms_median", Percentile(ms, 0.5)},
          {"plan_ms_p99", Percentile(ms, 0.99)},
          {"plan_ms_samples", ms},  // the distribution, for the HTML page's histogram
          {"mean_traj_duration_s", g.succeeded > 0 ? g.duration_sum / g.succeeded : 0.0},
          {"search_ms_mean", g.attempted > 0 ? g.search_ms / g.attempted : 0.0},
          {"search_expansions_mean", g.attempted > 0 ? g.expansions / g.attempted : 0.0},
          {"search_segment_checks_mean", g.attempted > 0 ? g.segment_checks / g.attempted : 0.0},
          {"optimize_ms_mean", g.attempted > 0 ? g.optimize_ms / g.attempted : 0.0},
          {"lbfgs_iterations_mean", g.attempted > 0 ? g.iterations / g.attempted : 0.0},
          {"clearance_rounds_mean", g.attempted > 0 ? g.rounds / g.attempted : 0.0},
          {"pieces_mean", g.attempted > 0 ? g.pieces / g.attempted : 0.0},
          {"max_limit_violation", g.max_violation},
          {"plans_fine_search", g.fine_search},
          {"plans_rest_to_rest", g.rest_to_rest},
          {"failures", failures}};
}

}  // namespace

void PlannerBenchOptions::Validate() const {
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowInvalidArgument("RunPlannerBenchmark", std::string("PlannerBenchOptions::") + field, v, rule);
  };
  require(pairs >= 1 && pairs <= 100000, "pairs", pairs, "in [1, 100000]");
  require(worlds >= 1 && worlds <= pairs, "worlds", worlds, "in [1, pairs]");
}

sim::World PlannerForest(std::uint64_t seed) {
  Rng rng(DeriveSeed(seed, 7));
  sim::World w;
  while (w.cylinders.size() < 150) {  // 0.25 per m² over 600 m²
    w.cylinders.push_back({Eigen::Vector2d(rng.Uniform(-15, 15), rng.Uniform(-10, 10)), rng.Uniform(0.1, 0.3),
                           rng.Uniform(4, 10)});
  }
  return w;
}

sim::World PlannerRoom(std::uint64_t seed) {
  Rng rng(DeriveSeed(seed, 8));
  sim::World w;
  w.boxes = {{Vector3(5.25, 0, 1.5), Vector3(0.5, 8.5, 3), 0.0}, {Vector3(-5.25, 0, 1.5), Vector3(0.5, 8.5, 3), 0.0},
             {Vector3(0, 4.25, 1.5), Vector3(10.5, 0.5, 3), 0.0}, {Vector3(0, -4.25, 1.5), Vector3(10.5, 0.5, 3), 0.0}};
  for (int k = 0; k < 8; ++k) {  // furniture: tables, shelves, cabinets
    const Vector3 size(rng.Uniform(0.4, 1.6), rng.Uniform(0.4, 1.6), rng.Uniform(0.5, 2.2));
    w.boxes.push_back({Vector3(rng.Uniform(-4, 4), rng.Uniform(-3, 3), 0.5 * size.z()), size, rng.Uniform(0, 3.14)});
  }
  for (int k = 0; k < 2; ++k) w.cylinders.push_back({Eigen::Vector2d(rng.Uniform(-4, 4), rng.Uniform(-3, 3)), 0.2, 3.0});
  return w;
}

nlohmann::json RunPlannerBenchmark(const PlannerBenchOptions& options) {
  options.Validate();
  const std::vector<Kind> kinds = {
      {"forest", &PlannerForest, Vector3(-14, -9, 1.0), Vector3(14, 9, 2.0), 10.0, Vector3(32, 24, 6)},
      {"room", &PlannerRoom, Vector3(-4.5, -3.5, 1.0), Vector3(4.5, 3.5, 2.0), 4.0, Vector3(12, 12, 6)}};
  // Nominal limits, and after a failure eq. (33) with the reference vehicle (1.15 kg, two rotors
  // of 11.5 N, drag 0.65 kg/s at 1 m/s) and a safety factor of 0.05: 0.84 m/s².
  planning::DynamicLimits nominal{1.0, 2.0, 6.0}, failed = nominal;
  failed.a_max = planning::PostFailureAccelerationLimit(1.15, 11.5, 0.65, nominal.v_max, 0.05);
  planning::PlannerOptions planner_options;
  planner_options.optimizer.lbfgs.method = options.lbfgs;
  const planning::Planner planner(planner_options);
  std::map<std::string, Group> groups;
  Group all;
  const int total = 2 * static_cast<int>(kinds.size()) * options.pairs;
  int done = 0;
  for (std::size_t kind = 0; kind < kinds.size(); ++kind) {
    const Kind& k = kinds[kind];
    Rng rng(DeriveSeed(options.seed, 100 + kind));
    for (int w = 0; w < options.worlds; ++w) {
      const sim::World world = k.make(DeriveSeed(options.seed, 1000 * kind + static_cast<std::uint64_t>(w)));
      perception::VoxelMapOptions map_options;
      map_options.window_size_m = k.window_m;
      map_options.inflation_radius_m = kVehicleRadius;
      perception::VoxelMap map(map_options);
      harness::RasterizeWorld(world, &map);
      const int pairs = options.pairs / options.worlds + (w < options.pairs % options.worlds ? 1 : 0);
      for (int pair = 0; pair < pairs; ++pair) {
        // A start and a goal in free space, far enough apart.
        Vector3 a, b;
        const auto draw = [&] {
          return Vector3(rng.Uniform(k.lo.x(), k.hi.x()), rng.Uniform(k.lo.y(), k.hi.y()), rng.Uniform(k.lo.z(), k.hi.z()));
        };
        const auto free = [&](const Vector3& p) { return world.DistanceToSurface(p, 0.0) > 0.5 && !map.IsInflated(p); };
        do {
          a = draw();
          b = draw();
        } while (!free(a) || !free(b) || (a - b).norm() < k.min_distance_m);
        planning::PvaState start = planning::PvaState::Zero();
        start.col(0) = a;
        for (const bool after_failure : {false, true}) {
          const planning::DynamicLimits& limits = after_failure ? failed : nominal;
          Group& g = groups[k.name + (after_failure ? "_post_failure" : "_nominal")];
          planning::MinimumJerkTrajectory traj;
          const planning::PlanSummary s = planner.Plan(start, b, limits, map, &traj);
          for (Group* x : {&g, &all}) {
            ++x->attempted;
            x->plan_ms.push_back(s.total_ms);
            x->search_ms += s.search_ms;
            x->expansions += s.path.expansions;
            x->segment_checks += s.path.segment_checks;
            x->optimize_ms += s.optimize_ms;
            x->iterations += s.optimizer.iterations;
            x->rounds += s.clearance_rounds;
            x->pieces += s.pieces;
          }
          if (s.status == planning::PlanSummary::Status::kNoPath) {
            ++g.no_path;
            ++all.no_path;
          } else if (!s.ok()) {
            ++g.failures[planning::ToString(s.status)];
            ++all.failures[planning::ToString(s.status)];
          } else {
            double violation, clearance;
            Check(traj, limits, world, &violation, &clearance);
            for (Group* x : {&g, &all}) x->max_violation = std::max(x->max_violation, violation);
            const bool good = violation <= 1e-3 && clearance >= kVehicleRadius;
            for (Group* x : {&g, &all}) {
              if (good) {
                ++x->succeeded;
                x->fine_search += s.fine_search;
                x->rest_to_rest += s.rest_to_rest;
                x->duration_sum += traj.total_duration();
              } else {
                ++x->failures[clearance < kVehicleRadius ? "true_collision" : "limit_exceeded"];
              }
            }
          }
          if (options.progress) options.progress(++done, total);
        }
      }
    }
  }
  nlohmann::json result = GroupJson(all);
  nlohmann::json group_json = nlohmann::json::object();
  for (const auto& [name, g] : groups) group_json[name] = GroupJson(g);
  result["benchmark"] = "planner";
  result["seed"] = options.seed;
  result["pairs_per_kind"] = options.pairs;
  result["worlds_per_kind"] = options.worlds;
  result["lbfgs"] = ToName(options.lbfgs);
  result["limits_nominal"] = {{"v_max", nominal.v_max}, {"a_max", nominal.a_max}, {"j_max", nominal.j_max}};
  result["limits_post_failure"] = {{"v_max", failed.v_max}, {"a_max", failed.a_max}, {"j_max", failed.j_max}};
  result["groups"] = group_json;
  result["meets_targets"] = result["plan_ms_mean"].get<double>() <= 5.0 && result["success_rate"].get<double>() >= 0.98 &&
                            result["max_limit_violation"].get<double>() <= 1e-3;
  result["host"] = buildinfo::HostInfo();
  return result;
}

std::string PlannerMarkdown(const nlohmann::json& r) {
  std::string md = fmt::format("{} start/goal pairs per world kind over {} worlds each, seed {}.\n\n",
                               r["pairs_per_kind"].get<int>(), r["worlds_per_kind"].get<int>(), r["seed"].get<std::uint64_t>());
  md += "| group | pairs | without path | success | plan ms (mean / median / p99) | duration s | max limit violation |\n";
  md += "|---|---|---|---|---|---|---|\n";
  const auto row = [&](const std::string& name, const nlohmann::json& g) {
    md += fmt::format("| {} | {} | {} | {:.3f} | {:.2f} / {:.2f} / {:.2f} | {:.1f} | {:.4f} |\n", name, g["pairs"].get<int>(),
                      g["pairs_without_path"].get<int>(), g["success_rate"].get<double>(), g["plan_ms_mean"].get<double>(),
                      g["plan_ms_median"].get<double>(), g["plan_ms_p99"].get<double>(),
                      g["mean_traj_duration_s"].get<double>(), g["max_limit_violation"].get<double>());
  };
  for (const auto& [name, g] : r["groups"].items()) row(name, g);
  row("all", r);
  md += fmt::format("\nOf the successful plans, {} needed the search at the map's resolution and {} were flown from "
                    "rest to rest (the planner's fallbacks).\n",
                    r["plans_fine_search"].get<int>(), r["plans_rest_to_rest"].get<int>());
  md += fmt::format("\nTargets (plan_ms_mean <= 5, success_rate >= 0.98, within limits): {}.\n",
                    r["meets_targets"].get<bool>() ? "met" : "NOT met");
  return md;
}

}  // namespace rotorguard::benchmarks
