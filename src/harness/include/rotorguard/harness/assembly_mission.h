#pragma once
/// Mission assembly_plan (scenario.h, AssemblyPlanSpec): paper 002's planning pipeline for an
/// assembly, the dynamically feasible A* (eq. 9) then the shape-aware trajectory optimisation
/// (eqs. 11-12), on a map of the world's geometry, for what the stack knows of its rotors.
#include <memory>
#include <string>

#include "rotorguard/harness/scenario.h"
#include "rotorguard/modular/assembly_trajectory.h"
#include "rotorguard/perception/voxel_map.h"

namespace rotorguard::harness {

struct AssemblyPlanResult {
  bool ok = false;
  std::string message;  ///< why planning failed ("" when ok)
  modular::AssemblyPathStatus path_status = modular::AssemblyPathStatus::kNoPath;
  modular::AssemblyTrajectorySummary trajectory_summary;
  modular::AssemblyCapacity capacity;  ///< of the known rotors
  modular::AssemblyLimits limits;      ///< the limits planned with
  double astar_ms = 0.0;
  double astar_attitude_deviation_rad = 0.0;
  std::shared_ptr<const modular::AssemblyTrajectory> trajectory;  ///< when ok
};

/// The known map an assembly plans on: the voxel map's default window (24 x 24 x 6 m) at the
/// spec's resolution, inflated by a unit's radius and a 5 cm margin for the A*.
perception::VoxelMapOptions KnownMapOptions(const AssemblyPlanSpec& spec, const modular::Assembly& assembly);

/// Plans `scenario`'s assembly_plan mission (which must have an assembly and the spec) for the
/// faults known at the start (stack.known_faults at 0 s). Never throws for an unplannable mission:
/// the result says why. The map holds the world's boxes and cylinders, not its moving boxes.
AssemblyPlanResult PlanAssemblyMission(const Scenario& scenario);

/// Plans `scenario`'s assembly_plan mission when it has one that is not planned yet (its
/// reference is null), makes the plan its reference and runs the checks that need it
/// (CheckPlannedMission). Throws io::ConfigError at the file's mission block (std::invalid_argument
/// for a scenario built in code) when the mission cannot be planned. RunScenario calls it.
void PlanMission(Scenario* scenario);

}  // namespace rotorguard::harness
