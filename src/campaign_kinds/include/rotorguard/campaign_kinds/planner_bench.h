#pragma once
/// `rotorguard bench planner` (issue: rotor-failure-aware trajectory planner): random forests
/// (30 x 20 m, trunks 0.1-0.3 m in radius, dense enough that passages narrower than 1 m are common)
/// and furnished rooms (10 x 8 x 3 m), random start/goal pairs in each, planned on the map of the
/// world's truth (rasterised into the planner's own voxel map) with nominal limits and with the
/// post-failure acceleration limit of eq. (33). A plan succeeds when the planner reports success,
/// the trajectory keeps the vehicle's radius from every true surface and stays within its limits
/// on a dense check; pairs with no path in the map are counted apart.
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/planning/lbfgs.h"
#include "rotorguard/sim/world.h"

namespace rotorguard::benchmarks {

struct PlannerBenchOptions {
  int pairs = 100;           ///< start/goal pairs per world kind, in [1, 100000]
  std::uint64_t seed = 1;    ///< worlds and pairs
  int worlds = 10;           ///< distinct worlds per kind (pairs spread over them), in [1, pairs]
  planning::LbfgsMethod lbfgs = planning::LbfgsMethod::kLewisOverton;  ///< the optimiser's L-BFGS
  /// Called after each plan with (done, total).
  std::function<void(int, int)> progress;
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// A random forest: trees of radius 0.1-0.3 m, 0.25 per m² over 30 x 20 m around the origin.
sim::World PlannerForest(std::uint64_t seed);
/// A random furnished room: 10 x 8 m walls (3 m high) with 8 boxes of furniture and 2 pillars.
sim::World PlannerRoom(std::uint64_t seed);

nlohmann::json RunPlannerBenchmark(const PlannerBenchOptions& options);
/// The result as a Markdown table.
std::string PlannerMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks
