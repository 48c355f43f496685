#include "rotorguard/perception/point_map.h"

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"

namespace rotorguard::perception {

void PointMapOptions::Validate() const {
  const auto require = [](bool ok, const char* key, double value, const char* rule) {
    if (!ok) ThrowValidation("PointMapOptions", key, value, rule);
  };
  require(std::isfinite(voxel_m) && voxel_m >= 0.05 && voxel_m <= 10.0, "voxel_m", voxel_m, "an edge in [0.05, 10] m");
  require(max_points_per_voxel >= 1 && max_points_per_voxel <= kMaxPointsPerVoxel, "max_points_per_voxel",
          max_points_per_voxel, "a count in [1, 32]");
  require(std::isfinite(min_point_spacing_m) && min_point_spacing_m >= 0.0 && min_point_spacing_m < voxel_m,
          "min_point_spacing_m", min_point_spacing_m, "a distance in [0, voxel_m) m");
  require(std::isfinite(window_radius_m) && window_radius_m >= 2.0 * voxel_m && window_radius_m <= 1e4,
          "window_radius_m", window_radius_m, "a radius in [2 voxel_m, 1e4] m");
}

PointMap::PointMap(const PointMapOptions& options) : options_(options) {
  options_.Validate();
  inverse_voxel_ = 1.0 / options_.voxel_m;
}

Eigen::Vector3i PointMap::Cell(const Vector3& p) const { return (p * inverse_voxel_).array().floor().cast<int>(); }

namespace {
// 21 bits per axis (±2^20 voxels: ±52 km at 5 cm), offset to be non-negative.
constexpr std::int64_t kOffset = std::int64_t{1} << 20, kMask = (std::int64_t{1} << 21) - 1;
}  // namespace

PointMap::Key PointMap::KeyOf(const Eigen::Vector3i& c) {
  return (static_cast<Key>((c.x() + kOffset) & kMask) << 42) | (static_cast<Key>((c.y() + kOffset) & kMask) << 21) |
         static_cast<Key>((c.z() + kOffset) & kMask);
}

Eigen::Vector3i PointMap::CellOf(Key key) {
  return Eigen::Vector3i(static_cast<int>(static_cast<std::int64_t>(key >> 42) - kOffset),
                         static_cast<int>(static_cast<std::int64_t>((key >> 21) & kMask) - kOffset),
                         static_cast<int>(static_cast<std::int64_t>(key & kMask) - kOffset));
}

int PointMap::Insert(const std::vector<Vector3>& points_W) {
  int stored = 0;
  const float spacing2 = static_cast<float>(options_.min_point_spacing_m * options_.min_point_spacing_m);
  // Coordinates beyond the key's range would alias; the window keeps a flight far inside it.
  const double limit = 0.99 * std::ldexp(options_.voxel_m, 20);
  for (const Vector3& p : points_W) {
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > limit) continue;
    const Key key = KeyOf(Cell(p));
    auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(voxels_.size()));
    if (inserted) {
      voxels_.emplace_back();
      voxels_.back().key = key;
    }
    Voxel& v = voxels_[it->second];
    if (v.count >= options_.max_points_per_voxel) continue;
    const Eigen::Vector3f pf = p.cast<float>();
    bool near = false;
    for (int i = 0; i < v.count && !near; ++i) near = (v.points[i] - pf).squaredNorm() < spacing2;
    if (near) continue;
    v.points[v.count++] = pf;
    ++stored;
  }
  points_ += stored;
  return stored;
}

int PointMap::Prune(const Vector3& center_W) {
  const double r2 = options_.window_radius_m * options_.window_radius_m;
  int removed = 0;
  for (std::size_t i = 0; i < voxels_.size();) {
    const Key key = voxels_[i].key;
    const Vector3 centre = (CellOf(key).cast<double>().array() + 0.5).matrix() * options_.voxel_m;
    if ((centre - center_W).squaredNorm() <= r2) {
      ++i;
      continue;
    }
    // Swap-remove: the last voxel takes this one's slot and its index entry follows it.
    removed += voxels_[i].count;
    index_.erase(key);
    if (i + 1 != voxels_.size()) {
      voxels_[i] = voxels_.back();
      index_[voxels_[i].key] = static_cast<std::uint32_t>(i);
    }
    voxels_.pop_back();
  }
  points_ -= removed;
  return removed;
}

int PointMap::Nearest(const Vector3& query, int k, double radius_m, std::vector<Vector3>* out,
                      std::vector<double>* squared_distances) const {
  out->clear();
  if (squared_distances) squared_distances->clear();
  if (k <= 0 || !query.allFinite()) return 0;
  const double r = std::min(radius_m, options_.voxel_m);
  const float r2 = static_cast<float>(r * r);
  // The k best so far, sorted by distance (k is small: a plane needs five).
  std::array<std::pair<float, Eigen::Vector3f>, 16> best;
  const int kk = std::min(k, static_cast<int>(best.size()));
  int n = 0;
  const Eigen::Vector3f qf = query.cast<float>();
  const Eigen::Vector3i c = Cell(query);
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        const auto it = index_.find(KeyOf(c + Eigen::Vector3i(dx, dy, dz)));
        if (it == index_.end()) continue;
        const Voxel& v = voxels_[it->second];
        for (int i = 0; i < v.count; ++i) {
          const float d2 = (v.points[i] - qf).squaredNorm();
          if (d2 > r2 || (n == kk && d2 >= best[n - 1].first)) continue;
          int j = n < kk ? n++ : n - 1;  // insertion sort into the k best
          while (j > 0 && best[j - 1].first > d2) {
            best[j] = best[j - 1];
            --j;
          }
          best[j] = {d2, v.points[i]};
        }
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    out->push_back(best[i].second.cast<double>());
    if (squared_distances) squared_distances->push_back(best[i].first);
  }
  return n;
}

}  // namespace rotorguard::perception
