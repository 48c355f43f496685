#include "rotorguard/harness/scene_recorder.h"

#include <algorithm>
#include <iterator>

namespace rotorguard::harness {

namespace {

nlohmann::json Vec(const Vector3& v) { return {v.x(), v.y(), v.z()}; }

// Voxel indices packed in one integer (21 bits each, offset to be non-negative) so that a
// snapshot is a sorted vector and its change is a set difference.
constexpr std::int64_t kKeyOffset = 1 << 20;
std::int64_t PackVoxel(const Eigen::Vector3i& i) {
  return ((static_cast<std::int64_t>(i.x()) + kKeyOffset) << 42) | ((static_cast<std::int64_t>(i.y()) + kKeyOffset) << 21) |
         (static_cast<std::int64_t>(i.z()) + kKeyOffset);
}
void AppendUnpacked(std::int64_t key, nlohmann::json* out) {
  constexpr std::int64_t mask = (1 << 21) - 1;
  out->push_back(((key >> 42) & mask) - kKeyOffset);
  out->push_back(((key >> 21) & mask) - kKeyOffset);
  out->push_back((key & mask) - kKeyOffset);
}

}  // namespace

SceneRecorder::SceneRecorder(const vehicle::VehicleParams& vehicle, const sim::World& world,
                             const SceneRecorderOptions& options, const modular::Assembly* assembly)
    : options_(options), world_(&world) {
  scene_["format"] = "rotorguard-scene/1";
  nlohmann::json rotors = nlohmann::json::array();
  for (int k = 0; k < vehicle.num_rotors(); ++k) {
    const vehicle::Rotor& r = vehicle.rotors[static_cast<std::size_t>(k)];
    rotors.push_back({{"position_m", Vec(r.p_B)},
                      {"spin", r.direction == vehicle::SpinDirection::kClockwise ? "cw" : "ccw"}});
    if (assembly) rotors.back()["unit"] = assembly->UnitOfRotor(k);
  }
  scene_["vehicle"] = {{"name", vehicle.name},
                       {"collision_radius_m", vehicle.collision_radius_m},
                       {"thrust_coefficient_n_s2", vehicle.thrust_coefficient_n_s2},  // commanded rpm from thrust
                       {"rotors", rotors}};
  if (assembly) {
    nlohmann::json units = nlohmann::json::array();
    for (const Vector3& c : assembly->unit_position_B) units.push_back({{"center_m", Vec(c)}});
    scene_["vehicle"]["units"] = units;
  }
  nlohmann::json boxes = nlohmann::json::array(), cylinders = nlohmann::json::array(), moving = nlohmann::json::array();
  for (const sim::Box& b : world.boxes) {
    boxes.push_back({{"center_m", Vec(b.center_m)}, {"size_m", Vec(b.size_m)}, {"yaw_rad", b.yaw_rad}});
  }
  for (const sim::Cylinder& c : world.cylinders) {
    cylinders.push_back({{"center_m", {c.center_m.x(), c.center_m.y()}}, {"radius_m", c.radius_m}, {"height_m", c.height_m}});
  }
  for (const sim::MovingBox& m : world.moving_boxes) {
    moving.push_back({{"size_m", Vec(m.size_m)}, {"t_s", nlohmann::json::array()}, {"center_m", nlohmann::json::array()}});
  }
  scene_["world"] = {{"boxes", boxes}, {"cylinders", cylinders}, {"moving_boxes", moving}};
  scene_["plans"] = nlohmann::json::array();
  scene_["map"] = nullptr;  // set by the first snapshot of a stack with a LiDAR
}

void SceneRecorder::OnTime(double t) {
  if (world_->moving_boxes.empty() || t < next_moving_s_) return;
  next_moving_s_ += 1.0 / options_.moving_box_rate_hz;
  nlohmann::json& moving = scene_["world"]["moving_boxes"];
  for (std::size_t i = 0; i < world_->moving_boxes.size(); ++i) {
    const sim::Box b = world_->moving_boxes[i].At(t);
    moving[i]["t_s"].push_back(t);
    moving[i]["center_m"].push_back(Vec(b.center_m));
  }
}

void SceneRecorder::OnControlCycle(double t, const stack::FlightStack& st) {
  if (const planning::Replanner* nav = st.navigator()) {
    // A successful plan is adopted by the replanner: draw the trajectory it now follows.
    for (; plans_seen_ < nav->events().size(); ++plans_seen_) {
      const planning::Replanner::Event& e = nav->events()[plans_seen_];
      if (e.status != planning::PlanSummary::Status::kSuccess) continue;
      const planning::MinimumJerkTrajectory& traj = nav->trajectory();
      nlohmann::json points = nlohmann::json::array();
      const double duration = traj.total_duration();
      // Every plan_sample_s from its start, then its end.
      for (int k = 0; k * options_.plan_sample_s < duration; ++k) {
        points.push_back(Vec(traj.Evaluate(traj.start_time() + k * options_.plan_sample_s).p_W));
      }
      points.push_back(Vec(traj.Evaluate(traj.start_time() + duration).p_W));
      scene_["plans"].push_back({{"t_s", e.t}, {"reason", e.reason}, {"start_s", traj.start_time()},
                                 {"duration_s", duration}, {"sample_s", options_.plan_sample_s}, {"points_m", points}});
    }
  }
  if (const perception::VoxelMap* map = st.map(); map != nullptr && t >= next_map_s_) OnMap(t, *map);
}

void SceneRecorder::OnMap(double t, const perception::VoxelMap& map) {
  next_map_s_ = t + 1.0 / options_.map_rate_hz;
  map_resolution_ = map.resolution();
  std::vector<std::int64_t> keys;
  for (const Vector3& c : map.OccupiedVoxels()) {
    keys.push_back(PackVoxel((c / map_resolution_).array().floor().cast<int>()));
  }
  std::sort(keys.begin(), keys.end());
  std::vector<std::int64_t> added, removed;
  std::set_difference(keys.begin(), keys.end(), map_keys_.begin(), map_keys_.end(), std::back_inserter(added));
  std::set_difference(map_keys_.begin(), map_keys_.end(), keys.begin(), keys.end(), std::back_inserter(removed));
  map_keys_ = std::move(keys);
  if (scene_["map"].is_null()) scene_["map"] = {{"resolution_m", map_resolution_}, {"snapshots", nlohmann::json::array()}};
  if (added.empty() && removed.empty()) return;
  nlohmann::json a = nlohmann::json::array(), r = nlohmann::json::array();
  for (const std::int64_t k : added) AppendUnpacked(k, &a);
  for (const std::int64_t k : removed) AppendUnpacked(k, &r);
  scene_["map"]["snapshots"].push_back({{"t_s", t}, {"added", a}, {"removed", r}});
}

nlohmann::json SceneRecorder::ToJson() const { return scene_; }

}  // namespace rotorguard::harness
