#pragma once
/// A known map: the world's geometry written into a voxel map, for planning on the truth (paper
/// 002's setting, and the planner benchmark's), where the flight stack would otherwise build its
/// map from LiDAR returns.
#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/sim/world.h"

namespace rotorguard::harness {

/// Marks occupied every voxel of `map`'s window whose centre lies within half a voxel diagonal of
/// a box or cylinder of `world` (the ground is left out: the planner keeps an altitude band).
void RasterizeWorld(const sim::World& world, perception::VoxelMap* map);

}  // namespace rotorguard::harness
