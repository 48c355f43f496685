#include "rotorguard/harness/mission.h"

#include <stdexcept>

#include "rotorguard/io/config_archive.h"
#include "rotorguard/planning/references.h"

namespace rotorguard::harness {

namespace {

/// Reads the block's keys into `options` (defaults already set), then builds its reference; a
/// reference that rejects its options is reported at the block.
template <typename Reference, typename Options>
std::shared_ptr<const ReferenceTrajectory> Build(const io::ConfigNode& node, Options options) {
  io::ReadKeys(node, &options);
  try {
    return std::make_shared<Reference>(options);
  } catch (const std::invalid_argument& e) {
    node.Fail(e.what());
  }
}

std::shared_ptr<const ReferenceTrajectory> Hold(const Vector3& p, double yaw) {
  planning::HoverOptions o;
  o.position_m = p;
  o.yaw_rad = yaw;
  return std::make_shared<planning::HoverReference>(o);
}

}  // namespace

Mission ParseMission(const io::ConfigNode& node, const Vector3& start_m, double start_yaw_rad) {
  Mission m;
  m.kind = *FromName<MissionKind>(node.Required("type").AsEnum(NameList<MissionKind>()));
  switch (m.kind) {
    case MissionKind::kHover:
      m.reference = Build<planning::HoverReference>(
          node, planning::HoverOptions{.position_m = start_m, .yaw_rad = start_yaw_rad});
      break;
    case MissionKind::kTakeoff:
      m.reference = Build<planning::TakeoffReference>(
          node, planning::TakeoffOptions{.start_m = start_m, .yaw_rad = start_yaw_rad});
      break;
    case MissionKind::kLand:
      m.reference = Build<planning::LandingReference>(
          node, planning::LandingOptions{.start_m = start_m, .yaw_rad = start_yaw_rad});
      break;
    case MissionKind::kLemniscate:
      m.reference = Build<planning::LemniscateReference>(
          node, planning::LemniscateOptions{.center_m = start_m, .yaw_rad = start_yaw_rad});
      break;
    case MissionKind::kCircle:
      m.reference = Build<planning::CircleReference>(node, planning::CircleOptions{.yaw_rad = start_yaw_rad});
      break;
    case MissionKind::kWaypoints: {
      planning::WaypointOptions o;
      o.yaw_rad = start_yaw_rad;
      io::ReadKeys(node, &o);
      o.waypoints_m.insert(o.waypoints_m.begin(), start_m);  // the legs start where the vehicle does
      try {
        m.reference = std::make_shared<planning::WaypointReference>(o);
      } catch (const std::invalid_argument& e) {
        node.Fail(e.what());
      }
      break;
    }
    case MissionKind::kNavigate: {
      // Planned on the LiDAR map (docs/planning.md): the stack holds the start until its first
      // plan, then flies the waypoints in turn, `rounds` times.
      NavigateSpec n;
      n.yaw_rad = start_yaw_rad;
      io::ReadKeys(node, &n);
      m.reference = Hold(start_m, n.yaw_rad);
      m.navigate = n;
      break;
    }
    case MissionKind::kAssemblyPlan: {
      // Planned after loading, on the world's geometry, for the rotors the stack knows of
      // (PlanMission, assembly_mission.h).
      AssemblyPlanSpec p;
      io::ReadKeys(node, &p);
      m.assembly_plan = p;
      break;
    }
  }
  return m;
}

}  // namespace rotorguard::harness
