#pragma once
/// A scenario's mission (key `mission`): what the vehicle is asked to fly, as a value the loader
/// returns (ParseMission) and the scenario then holds.
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/core/types.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::harness {

/// The mission's type (key mission.type).
enum class MissionKind {
  kHover,         ///< hold a point
  kTakeoff,       ///< a minimum-jerk climb from the start
  kLand,          ///< the start held, then a minimum-jerk descent to the ground
  kLemniscate,    ///< the figure eight of paper 000's tracking tests
  kCircle,        ///< a horizontal circle, or a helix (paper 002's spiral)
  kWaypoints,     ///< straight legs through waypoints, stopping at each
  kNavigate,      ///< waypoints planned on the stack's LiDAR map (docs/planning.md)
  kAssemblyPlan,  ///< an assembly's plan to a goal on a known map (paper 002; assembly_mission.h)
};
inline constexpr EnumName<MissionKind> kMissionKindNames[] = {{MissionKind::kHover, "hover"},
                                                              {MissionKind::kTakeoff, "takeoff"},
                                                              {MissionKind::kLand, "land"},
                                                              {MissionKind::kLemniscate, "lemniscate"},
                                                              {MissionKind::kCircle, "circle"},
                                                              {MissionKind::kWaypoints, "waypoints"},
                                                              {MissionKind::kNavigate, "navigate"},
                                                              {MissionKind::kAssemblyPlan, "assembly_plan"}};
constexpr std::span<const EnumName<MissionKind>> NamesOf(const MissionKind*) { return kMissionKindNames; }

/// How an assembly plans (key mission.method).
enum class AssemblyPlanMethod {
  kOurs,      ///< eqs. 9 and 11-12 with the assembly's dynamics
  kBaseline,  ///< Table II's SVSDF-style row: kinematic limits only, no attitude terms
};
inline constexpr EnumName<AssemblyPlanMethod> kAssemblyPlanMethodNames[] = {
    {AssemblyPlanMethod::kOurs, "ours"}, {AssemblyPlanMethod::kBaseline, "baseline"}};
constexpr std::span<const EnumName<AssemblyPlanMethod>> NamesOf(const AssemblyPlanMethod*) {
  return kAssemblyPlanMethodNames;
}

/// Mission `assembly_plan` (paper 002, Sec. III): the assembly plans from its initial pose to
/// `goal_m` on the world's geometry (a known map, the paper's setting) with the dynamically
/// feasible A* and the shape-aware trajectory optimisation (modular/assembly_trajectory.h), for the
/// rotors the stack knows of (stack.known_faults), and flies the result.
struct AssemblyPlanSpec {
  Vector3 goal_m = Vector3::Zero();
  AssemblyPlanMethod method = AssemblyPlanMethod::kOurs;
  double max_speed_m_s = 1.0;
  double max_accel_m_s2 = 2.0;
  double max_jerk_m_s3 = 6.0;
  double max_yaw_rate_rad_s = 1.0;  ///< both methods: the yaw's rate limit [rad/s]
  double safety_factor = 0.7;       ///< ours: the share of the assembly's capacity planned for, in (0, 1]
  double attitude_weight = 0.3;     ///< ours: L_Phi of the A* (eq. 9b) [m/rad]
  /// λ_t of eq. (11) for both methods: the larger, the more agile (closer to the limits) the plan.
  double time_weight = 10.0;
  double map_resolution_m = 0.1;
  /// The finest known map: its window (KnownMapOptions) then holds 27.6 million voxels, under the
  /// voxel map's 64 million (`validate` of mars_plan_3x2.yaml at 0.05 m peaks at 172 MB). Finer,
  /// the map would not be built (found by the flight fuzzer at 0.02 m, which `validate` accepted).
  static constexpr double kMinMapResolutionM = 0.05;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("goal_m", &goal_m,
             {.meaning = "where the assembly plans to, from its initial pose [m]",
              .min = -kMaxCoordinateM,
              .max = kMaxCoordinateM,
              .required = true});
    a->Visit("method", &method, {.meaning = "ours, or baseline: Table II's SVSDF-style row"});
    a->Visit("max_speed_m_s", &max_speed_m_s, {.meaning = "speed limit [m/s]", .min = kMinSpeedMS, .max = kMaxSpeedMS});
    a->Visit("max_accel_m_s2", &max_accel_m_s2,
             {.meaning = "acceleration limit [m/s²]", .min = kMinAccelerationMS2, .max = kMaxAccelerationMS2});
    a->Visit("max_jerk_m_s3", &max_jerk_m_s3, {.meaning = "jerk limit [m/s³]", .min = kMinJerkMS3, .max = kMaxJerkMS3});
    a->Visit("max_yaw_rate_rad_s", &max_yaw_rate_rad_s,
             {.meaning = "both methods: the yaw's rate limit [rad/s]", .max = kMaxBodyRateRadS, .positive = true});
    a->Visit("safety_factor", &safety_factor,
             {.meaning = "ours: the share of the assembly's capacity planned for", .min = 0.01, .max = 1.0});
    a->Visit("attitude_weight", &attitude_weight,
             {.meaning = "ours: L_Φ of the A* (eq. 9b) [m/rad]", .min = 0.0, .max = 100.0});
    a->Visit("time_weight", &time_weight,
             {.meaning = "λ_t of eq. (11): the larger, the more agile the plan", .min = 0.0, .max = 1e6});
    a->Visit("map_resolution_m", &map_resolution_m,
             {.meaning = "voxel edge of the known map, a 24 x 24 x 6 m window between start and goal [m]",
              .min = kMinMapResolutionM,
              .max = 1.0});
  }
};

/// The navigate mission's own keys: the waypoints the stack plans to on its LiDAR map.
struct NavigateSpec {
  std::vector<Vector3> waypoints_m;
  int rounds = 1;  ///< the list is flown this many times
  double yaw_rad = 0.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("waypoints_m", &waypoints_m,
             {.meaning = "the waypoints, flown to in turn [m]",
              .min = -kMaxCoordinateM,
              .max = kMaxCoordinateM,
              .required = true});
    a->Visit("rounds", &rounds, {.meaning = "times over the list", .min = 1, .max = 1000});
    a->Visit("yaw_rad", &yaw_rad,
             {.meaning = "the heading held [rad]", .min = -kTwoPi, .max = kTwoPi, .default_text = "the initial yaw"});
  }
};

/// What the vehicle flies.
struct Mission {
  MissionKind kind = MissionKind::kHover;
  /// The reference the stack follows: the trajectory of hover, takeoff, lemniscate, circle and
  /// waypoints; for navigate, the start held until the first plan; for assembly_plan, null until
  /// PlanMission (assembly_mission.h) has made the plan.
  std::shared_ptr<const ReferenceTrajectory> reference;
  std::optional<NavigateSpec> navigate;           ///< kind navigate
  std::optional<AssemblyPlanSpec> assembly_plan;  ///< kind assembly_plan
};

/// Reads a mission block: its type, then that type's keys (the options of planning/references.h,
/// NavigateSpec, AssemblyPlanSpec). Positions and headings default to the start's. Throws
/// io::ConfigError naming the key (a reference that rejects its options is reported at the block).
Mission ParseMission(const io::ConfigNode& node, const Vector3& start_m, double start_yaw_rad);

}  // namespace rotorguard::harness
