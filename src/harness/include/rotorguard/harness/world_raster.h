#pragma once
/// Voxel maps and the world's truth: the world's geometry written into a map, for planning on the
/// truth (paper 002's setting, and the planner benchmark's), where the flight stack would otherwise
/// build its map from LiDAR returns; and a map the stack built scored against the world.
#include <vector>

#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/sim/world.h"

namespace rotorguard::harness {

/// Marks occupied every voxel of `map`'s window whose centre lies within half a voxel diagonal of
/// a box or cylinder of `world` (the ground is left out: the planner keeps an altitude band).
void RasterizeWorld(const sim::World& world, perception::VoxelMap* map);

/// Share of the map's occupied voxels within one voxel of a true surface: the voxel's centre at
/// most half a diagonal plus one edge from it. 0 for an empty map.
double MapPrecision(const perception::VoxelMap& map, const sim::World& world);
/// The same score for any map's occupied cells, given as their centres and edge: what scores a
/// reference map (bench perception's OctoMap) exactly as the project's own is scored.
double MapPrecision(const std::vector<Vector3>& occupied_centers_W, double resolution_m, const sim::World& world);

}  // namespace rotorguard::harness
