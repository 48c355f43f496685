#include "rotorguard/benchmarks/octomap_reference.h"

#include <octomap/OcTree.h>
#include <octomap/octomap_utils.h>

#include <cmath>

namespace rotorguard::benchmarks {

OctomapReference::OctomapReference(const perception::VoxelMapOptions& map)
    : tree_(std::make_unique<octomap::OcTree>(map.resolution_m)), res_(map.resolution_m) {
  // OctoMap's defaults (0.7, 0.4, 0.12, 0.97) are the map's own hit, miss and clamps to a few
  // thousandths; its threshold (0.5, log-odds 0) is not: the map needs one hit more than misses to
  // call a voxel occupied. Set from the map's options, so a changed option changes both.
  tree_->setProbHit(octomap::probability(map.log_odds_hit));
  tree_->setProbMiss(octomap::probability(map.log_odds_miss));
  tree_->setClampingThresMin(octomap::probability(map.log_odds_min));
  tree_->setClampingThresMax(octomap::probability(map.log_odds_max));
  tree_->setOccupancyThres(octomap::probability(map.occupied_threshold));
}

OctomapReference::~OctomapReference() = default;

void OctomapReference::Insert(const Vector3& origin_W, const std::vector<Eigen::Vector3f>& points_W,
                              double max_range_m) {
  // The conversion to OctoMap's cloud is part of its cost to a user of these frames, so it is
  // inside what the benchmark times (tens of microseconds a frame).
  octomap::Pointcloud cloud;
  cloud.reserve(points_W.size());
  for (const Eigen::Vector3f& p : points_W) {
    if (p.allFinite()) cloud.push_back(p.x(), p.y(), p.z());  // the map drops non-finite returns too
  }
  const octomap::point3d origin(static_cast<float>(origin_W.x()), static_cast<float>(origin_W.y()),
                                static_cast<float>(origin_W.z()));
  tree_->insertPointCloud(cloud, origin, max_range_m, /*lazy_eval=*/false, /*discretize=*/false);
}

bool OctomapReference::IsOccupied(const Vector3& p_W) const {
  const octomap::OcTreeNode* node = tree_->search(p_W.x(), p_W.y(), p_W.z());
  return node != nullptr && tree_->isNodeOccupied(node);
}

bool OctomapReference::IsKnown(const Vector3& p_W) const { return tree_->search(p_W.x(), p_W.y(), p_W.z()) != nullptr; }

std::vector<Vector3> OctomapReference::OccupiedCells(const Vector3& min_W, const Vector3& max_W) const {
  std::vector<Vector3> out;
  const auto inside = [&](const Vector3& c) {
    return (c.array() >= min_W.array()).all() && (c.array() < max_W.array()).all();
  };
  // The cells whose centres lie in the box, by key (the iterator's bounds are inclusive).
  const octomap::OcTreeKey lo = tree_->coordToKey(octomap::point3d(static_cast<float>(min_W.x() + 0.5 * res_),
                                                                   static_cast<float>(min_W.y() + 0.5 * res_),
                                                                   static_cast<float>(min_W.z() + 0.5 * res_)));
  const octomap::OcTreeKey hi = tree_->coordToKey(octomap::point3d(static_cast<float>(max_W.x() - 0.5 * res_),
                                                                   static_cast<float>(max_W.y() - 0.5 * res_),
                                                                   static_cast<float>(max_W.z() - 0.5 * res_)));
  for (auto it = tree_->begin_leafs_bbx(lo, hi), end = tree_->end_leafs_bbx(); it != end; ++it) {
    if (!tree_->isNodeOccupied(*it)) continue;
    // A leaf larger than a cell is a pruned block of equal cells: listed one by one, so that the
    // score counts cells as the stack's map counts voxels. Indices from the leaf's corner (floats
    // in OctoMap) rounded to the grid, centres computed in double as the map computes its own.
    const double size = it.getSize();
    const int n = static_cast<int>(std::lround(size / res_));
    const Eigen::Vector3d corner =
        Vector3(it.getX(), it.getY(), it.getZ()) - Vector3::Constant(0.5 * size) + Vector3::Constant(0.5 * res_);
    const Eigen::Vector3d first = (corner / res_).array().floor();
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) {
          const Vector3 c = (first + Vector3(i, j, k) + Vector3::Constant(0.5)) * res_;
          if (inside(c)) out.push_back(c);
        }
      }
    }
  }
  return out;
}

std::size_t OctomapReference::memory_bytes() const { return tree_->memoryUsage(); }

}  // namespace rotorguard::benchmarks
