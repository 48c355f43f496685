
#include "rotorguard/harness/assembly_mission.h"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "rotorguard/core/error.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/harness/world_raster.h"

namespace rotorguard::harness {

perception::VoxelMapOptions KnownMapOptions(const AssemblyPlanSpec& spec, const modular::Assembly& assembly) {
  perception::VoxelMapOptions o;
  o.resolution_m = spec.map_resolution_m;
  o.inflation_radius_m = assembly.unit_radius_m + 0.05;
  return o;
}

AssemblyPlanResult PlanAssemblyMission(const Scenario& s) {
  AssemblyPlanResult r;
  if (!s.assembly || !s.assembly_plan) {
    r.message = "mission assembly_plan needs an assembly and its spec";
    return r;
  }
  const AssemblyPlanSpec& spec = *s.assembly_plan;
  const modular::Assembly& a = *s.assembly;
  const bool ours = spec.method == AssemblyPlanMethod::kOurs;
  // What the stack knows of its rotors (the paper plans for the known faults, as FTC flies them).
  RotorVector eta = RotorVector::Ones(a.vehicle.num_rotors());
  // Faults the stack learns later in the flight are not known when it plans, at the start.
  for (const stack::KnownFault& f : s.stack.known_faults) {
    if (f.at_time_s <= 0.0) eta[f.rotor] = std::min(eta[f.rotor], 1.0 - f.loss);
  }

  // The world's geometry as a known map.
  perception::VoxelMap map(KnownMapOptions(spec, a));
  map.Recenter(0.5 * (s.initial_position_m + spec.goal_m));
  RasterizeWorld(s.world, &map);

  r.capacity = modular::CapacityOf(a, eta);
  if (!r.capacity.hover_attainable) {
    r.message = "the rotors the stack knows of cannot hold the assembly's weight";
    return r;
  }
  if (ours && !modular::HasMargin(r.capacity)) {
    r.message = "the rotors the stack knows of leave no thrust or yaw torque to spare beyond hover";
    return r;
  }
  const planning::DynamicLimits kinematic{spec.max_speed_m_s, spec.max_accel_m_s2, spec.max_jerk_m_s3};
  modular::AssemblyAStarOptions ao;
  ao.resolution_m = spec.map_resolution_m;
  ao.z_min_m = std::min(s.initial_position_m.z(), spec.goal_m.z()) - 0.05;
  ao.z_max_m = std::max(s.initial_position_m.z(), spec.goal_m.z()) + 0.05;
  modular::AssemblyTrajectoryOptions to;
  to.weight_time = spec.time_weight;
  if (ours) {
    r.limits = modular::DynamicsAwareLimits(kinematic, r.capacity, a.vehicle.mass_kg, spec.max_yaw_rate_rad_s,
                                            spec.safety_factor);
    ao.attitude_weight = spec.attitude_weight;
  } else {  // SVSDF: the footprint and kinematic limits only, the yaw rate's among them
    r.limits.kinematic = kinematic;
    r.limits.yaw_rate_max = spec.max_yaw_rate_rad_s;
    ao.attitude_weight = 0.0;
    to.weight_attitude = 0.0;
  }

  const Stopwatch clock;
  const modular::AssemblyPath path =
      modular::FindAssemblyPath(map, a, eta, {s.initial_position_m, s.initial_yaw_rad}, spec.goal_m, ao);
  r.astar_ms = clock.milliseconds();
  r.path_status = path.status;
  r.astar_attitude_deviation_rad = path.attitude_deviation_rad;
  if (path.status != modular::AssemblyPathStatus::kFound) {
    r.message = fmt::format("A*: {}", modular::ToString(path.status));
    return r;
  }
  auto traj = std::make_shared<modular::AssemblyTrajectory>();
  try {
    r.trajectory_summary = modular::AssemblyTrajectoryOptimizer(a, eta, to).Optimize(map, path, r.limits, traj.get());
  } catch (const std::invalid_argument& e) {
    r.message = std::string("trajectory optimisation: ") + e.what();
    return r;
  }
  if (!r.trajectory_summary.ok()) {
    r.message = fmt::format("trajectory optimisation: {}: {}", modular::ToString(r.trajectory_summary.status),
                            r.trajectory_summary.message);
    return r;
  }
  r.trajectory = std::move(traj);
  r.ok = true;
  return r;
}

void PlanMission(Scenario* s) {
  if (!s->assembly_plan || s->reference) return;
  AssemblyPlanResult plan;
  try {
    plan = PlanAssemblyMission(*s);
  } catch (const ValidationError& e) {  // options made from the spec that a part refuses (the map's size)
    plan.message = e.what();
  }
  if (!plan.ok) {
    const std::string message = "cannot plan the assembly's path: " + plan.message;
    if (s->source.mission) s->source.mission->Fail(message);
    throw std::invalid_argument("PlanMission: " + message);
  }
  s->reference = plan.trajectory;
  CheckPlannedMission(*s);
}

}  // namespace rotorguard::harness
