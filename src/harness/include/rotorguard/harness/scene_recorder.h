#pragma once
/// Builds a flight's scene.json (record/flight_log.h) while it flies: the vehicle's geometry, the
/// world's obstacles (moving boxes sampled over time), every plan the navigator adopted and the
/// LiDAR map's changes. It reads the stack's outputs and the world the simulator flies in: a
/// logger outside the loop, which is why it lives with the runner and not with the file formats.
#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/modular/assembly.h"
#include "rotorguard/sim/world.h"
#include "rotorguard/stack/flight_stack.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::harness {

struct SceneRecorderOptions {
  double moving_box_rate_hz = 10.0;  ///< samples of moving boxes per second, > 0
  double map_rate_hz = 2.0;          ///< map snapshots per second, > 0
  double plan_sample_s = 0.1;        ///< spacing of a plan's points in time [s], > 0
};

/// Call OnControlCycle after each control cycle and OnTime at every physics step; ToJson at the end.
class SceneRecorder {
 public:
  /// `assembly`, when the vehicle is one, adds its units (vehicle.units, each rotor's unit) so
  /// that the replay draws the docked units.
  SceneRecorder(const vehicle::VehicleParams& vehicle, const sim::World& world,
                const SceneRecorderOptions& options = {}, const modular::Assembly* assembly = nullptr);
  /// After each control cycle at time t [s]: the plans adopted since, and the map when a snapshot
  /// is due.
  void OnControlCycle(double t, const stack::FlightStack& stack);
  /// A snapshot of the map at time t [s] (the changes since the last one).
  void OnMap(double t, const perception::VoxelMap& map);
  /// Samples the moving boxes when due (call at every physics step or so).
  void OnTime(double t);
  nlohmann::json ToJson() const;

 private:
  SceneRecorderOptions options_;
  const sim::World* world_;
  nlohmann::json scene_;
  std::size_t plans_seen_ = 0;
  double next_map_s_ = 0.0, next_moving_s_ = 0.0;
  std::vector<std::int64_t> map_keys_;  // sorted packed voxel indices of the last snapshot
  double map_resolution_ = 0.0;
};

}  // namespace rotorguard::harness
