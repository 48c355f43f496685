#pragma once
/// OctoMap (Hornung et al., Autonomous Robots 2013; Debian's liboctomap) as the reference that
/// `rotorguard bench perception` measures the stack's occupancy map (perception::VoxelMap) against:
/// an independent, widely used implementation of the same log-odds model, fed the same frames. The
/// octree stays behind this class so that only the benchmarks link OctoMap, never the flight stack.
#include <cstddef>
#include <memory>
#include <vector>

#include "rotorguard/core/types.h"
#include "rotorguard/perception/voxel_map.h"

namespace octomap {
class OcTree;
}  // namespace octomap

namespace rotorguard::benchmarks {

class OctomapReference {
 public:
  /// An empty octree at the map's resolution with the map's sensor model: the same hit and miss
  /// log-odds, clamps and occupancy threshold (OctoMap takes them as probabilities), so that the
  /// two maps differ only in how they implement the model. OctoMap's cells are aligned as the
  /// map's voxels are (cell k spans [k r, (k + 1) r) along each axis), so a voxel centre names the
  /// same cell in both.
  explicit OctomapReference(const perception::VoxelMapOptions& map);
  ~OctomapReference();
  OctomapReference(const OctomapReference&) = delete;
  OctomapReference& operator=(const OctomapReference&) = delete;

  /// One frame of returns (world frame) measured from `origin_W`, by OctoMap's insertPointCloud:
  /// every cell a ray crosses before its return is missed, the return's cell hit, each cell
  /// updated at most once per frame (hits win); a return beyond `max_range_m` only clears up to
  /// that range and is not hit. Inner nodes are updated and pruned as it goes (lazy evaluation
  /// off, the library's default), so the tree is complete and queryable after every frame, as the
  /// stack's map is. Non-finite points are dropped, as the map drops them.
  void Insert(const Vector3& origin_W, const std::vector<Eigen::Vector3f>& points_W, double max_range_m);

  /// The cell of `p_W` is known and its log-odds above the threshold (OctoMap's isNodeOccupied).
  /// Unknown cells are not occupied, as in the stack's map.
  bool IsOccupied(const Vector3& p_W) const;
  /// The cell of `p_W` has been observed (hit or missed).
  bool IsKnown(const Vector3& p_W) const;
  /// Centres of the occupied cells (at the map's resolution: a pruned leaf is listed cell by cell)
  /// whose centres lie in the box [min_W, max_W).
  std::vector<Vector3> OccupiedCells(const Vector3& min_W, const Vector3& max_W) const;
  /// The octree's own estimate of its memory (OcTree::memoryUsage).
  std::size_t memory_bytes() const;

 private:
  std::unique_ptr<octomap::OcTree> tree_;
  double res_;
};

}  // namespace rotorguard::benchmarks
