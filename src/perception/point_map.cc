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
// 21 bits per axis (±2^20 voxels: ±52 km at 5 cm), offset to be non-negative (KeyOfCell).
constexpr std::int64_t kOffset = std::int64_t{1} << 20, kMask = (std::int64_t{1} << 21) - 1;

// The slot a key probes first: splitmix64's finaliser, which spreads neighbouring cells' keys.
std::size_t Home(std::uint64_t key, std::size_t mask) {
  key ^= key >> 30;
  key *= 0xbf58476d1ce4e5b9ULL;
  key ^= key >> 27;
  key *= 0x94d049bb133111ebULL;
  key ^= key >> 31;
  return static_cast<std::size_t>(key) & mask;
}
}  // namespace

CellKey KeyOfCell(const Eigen::Vector3i& c) {
  return (static_cast<CellKey>((c.x() + kOffset) & kMask) << 42) |
         (static_cast<CellKey>((c.y() + kOffset) & kMask) << 21) | static_cast<CellKey>((c.z() + kOffset) & kMask);
}

Eigen::Vector3i PointMap::CellOf(Key key) {
  return Eigen::Vector3i(static_cast<int>(static_cast<std::int64_t>(key >> 42) - kOffset),
                         static_cast<int>(static_cast<std::int64_t>((key >> 21) & kMask) - kOffset),
                         static_cast<int>(static_cast<std::int64_t>(key & kMask) - kOffset));
}

void CellIndex::Clear(std::size_t expected) {
  std::size_t capacity = 1024;
  while (capacity < 2 * expected) capacity *= 2;
  slots_.assign(capacity, Slot{});
  size_ = 0;
}

std::size_t CellIndex::Probe(CellKey key) const {
  const std::size_t mask = slots_.size() - 1;
  std::size_t i = Home(key, mask);
  while (slots_[i].key != key && slots_[i].key != kEmpty) i = (i + 1) & mask;
  return i;
}

std::int64_t CellIndex::Find(CellKey key) const {
  if (slots_.empty()) return -1;
  const Slot& slot = slots_[Probe(key)];
  return slot.key == key ? static_cast<std::int64_t>(slot.index) : -1;
}

std::uint32_t CellIndex::FindOrAdd(CellKey key, std::uint32_t next, bool* added) {
  if (2 * (size_ + 1) > slots_.size()) Grow();
  Slot& slot = slots_[Probe(key)];
  *added = slot.key == kEmpty;
  if (*added) {
    slot = {key, next};
    ++size_;
  }
  return slot.index;
}

void CellIndex::Grow() {
  // Twice the slots, the keys re-probed into them.
  std::vector<Slot> old(2 * std::max<std::size_t>(slots_.size(), 512));
  old.swap(slots_);
  for (const Slot& s : old) {
    if (s.key != kEmpty) slots_[Probe(s.key)] = s;
  }
}

std::uint32_t PointMap::FindOrAdd(Key key) {
  bool added = false;
  const std::uint32_t v = index_.FindOrAdd(key, static_cast<std::uint32_t>(voxels_.size()), &added);
  if (added) {
    voxels_.emplace_back();
    voxels_.back().key = key;
  }
  return v;
}

int PointMap::Insert(const std::vector<Vector3>& points_W) {
  int stored = 0;
  const float spacing2 = static_cast<float>(options_.min_point_spacing_m * options_.min_point_spacing_m);
  // Coordinates beyond the key's range would alias; the window keeps a flight far inside it.
  const double limit = 0.99 * std::ldexp(options_.voxel_m, 20);
  for (const Vector3& p : points_W) {
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > limit) continue;
    const Key key = KeyOfCell(Cell(p));
    Voxel& v = voxels_[FindOrAdd(key)];
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
  std::size_t kept = 0;
  for (std::size_t i = 0; i < voxels_.size(); ++i) {
    const Vector3 centre = (CellOf(voxels_[i].key).cast<double>().array() + 0.5).matrix() * options_.voxel_m;
    if ((centre - center_W).squaredNorm() > r2) {
      removed += voxels_[i].count;
      continue;
    }
    if (kept != i) voxels_[kept] = voxels_[i];
    ++kept;
  }
  if (kept == voxels_.size()) return 0;
  voxels_.resize(kept);
  // The index again, for the voxels that stay.
  index_.Clear(kept);
  bool added = false;
  for (std::size_t v = 0; v < kept; ++v) index_.FindOrAdd(voxels_[v].key, static_cast<std::uint32_t>(v), &added);
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
  // A neighbour voxel is visited only when it comes within r of the query: per axis the distance
  // to the lower and the upper face of the query's voxel. With r at most half the edge, 8 of the
  // 27 on average (2 per axis).
  const Vector3 low = query - c.cast<double>() * options_.voxel_m;  // in [0, voxel_m)
  const Vector3 high = Vector3::Constant(options_.voxel_m) - low;
  for (int dx = -1; dx <= 1; ++dx) {
    const double ex = dx < 0 ? low.x() : dx > 0 ? high.x() : 0.0;
    if (ex > r) continue;
    for (int dy = -1; dy <= 1; ++dy) {
      const double ey = dy < 0 ? low.y() : dy > 0 ? high.y() : 0.0;
      if (ex * ex + ey * ey > r * r) continue;
      for (int dz = -1; dz <= 1; ++dz) {
        const double ez = dz < 0 ? low.z() : dz > 0 ? high.z() : 0.0;
        if (ex * ex + ey * ey + ez * ez > r * r) continue;
        const std::int64_t found = index_.Find(KeyOfCell(c + Eigen::Vector3i(dx, dy, dz)));
        if (found < 0) continue;
        const Voxel& v = voxels_[static_cast<std::size_t>(found)];
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
