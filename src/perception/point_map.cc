#include "rotorguard/perception/point_map.h"

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::perception {

void PointMapOptions::Validate() const {
  CheckDeclaredRanges("PointMapOptions", *this);
  // The rules between keys.
  const auto require = [](bool ok, const char* key, double value, const char* rule) {
    if (!ok) ThrowValidation("PointMapOptions", key, value, rule);
  };
  require(min_point_spacing_m < voxel_m, "min_point_spacing_m", min_point_spacing_m, "a distance in [0, voxel_m) m");
  // Pruning goes by blocks of 4 voxels a side, whose centre lies up to 2 sqrt(3) voxel_m from
  // their points: from 6 voxel_m on, the vehicle's own block and every voxel within one edge of
  // it stay (2 sqrt(3) + 1 < 6).
  require(window_radius_m >= 6.0 * voxel_m, "window_radius_m", window_radius_m, "a radius in [6 voxel_m, 1e4] m");
}

PointMap::PointMap(const PointMapOptions& options) : options_(options) {
  options_.Validate();
  inverse_voxel_ = 1.0 / options_.voxel_m;
  capacity_ = static_cast<std::size_t>(options_.max_points_per_voxel);
}

Eigen::Vector3i PointMap::Cell(const Vector3& p) const { return (p * inverse_voxel_).array().floor().cast<int>(); }

double PointMap::KeyRange() const { return 0.99 * std::ldexp(options_.voxel_m, 20); }

Eigen::Vector3i PointMap::BlockOf(const Eigen::Vector3i& cell) {
  // An arithmetic shift: floor division, negative cells included.
  return Eigen::Vector3i(cell.x() >> kBlockShift, cell.y() >> kBlockShift, cell.z() >> kBlockShift);
}

int PointMap::EntryIndex(const Eigen::Vector3i& cell) {
  constexpr int m = kBlockEdge - 1;
  return ((cell.x() & m) * kBlockEdge + (cell.y() & m)) * kBlockEdge + (cell.z() & m);
}

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

Eigen::Vector3i PointMap::BlockOfKey(CellKey key) {
  return Eigen::Vector3i(static_cast<int>(static_cast<std::int64_t>(key >> 42) - kOffset),
                         static_cast<int>(static_cast<std::int64_t>((key >> 21) & kMask) - kOffset),
                         static_cast<int>(static_cast<std::int64_t>(key & kMask) - kOffset));
}

CellKey KeyOfCell(const Eigen::Vector3i& c) {
  return (static_cast<CellKey>((c.x() + kOffset) & kMask) << 42) |
         (static_cast<CellKey>((c.y() + kOffset) & kMask) << 21) | static_cast<CellKey>((c.z() + kOffset) & kMask);
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

PointMap::Entry& PointMap::EntryOf(const Eigen::Vector3i& cell) {
  const CellKey key = KeyOfCell(BlockOf(cell));
  bool added = false;
  const std::uint32_t i = block_index_.FindOrAdd(key, static_cast<std::uint32_t>(blocks_.size()), &added);
  if (added) {
    blocks_.emplace_back();
    blocks_.back().key = key;
  }
  return blocks_[i].entry[static_cast<std::size_t>(EntryIndex(cell))];
}

int PointMap::Insert(const std::vector<Vector3>& points_W) {
  int stored = 0;
  const float spacing2 = static_cast<float>(options_.min_point_spacing_m * options_.min_point_spacing_m);
  // Coordinates beyond the key's range would alias; the window keeps a flight far inside it.
  const double limit = KeyRange();
  for (const Vector3& p : points_W) {
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > limit) continue;
    Entry& e = EntryOf(Cell(p));
    const Entry count = e & kCountMask;
    if (count >= capacity_) continue;
    const Eigen::Vector3f pf = p.cast<float>();
    if (count == 0) {
      // A new voxel: a freed one's slots, or new ones.
      std::uint32_t v;
      if (!free_voxels_.empty()) {
        v = free_voxels_.back();
        free_voxels_.pop_back();
      } else {
        v = static_cast<std::uint32_t>(points_W_.size() / capacity_);
        if (v >= (Entry{1} << (32 - kCountBits))) continue;  // 2^26 voxels: the window keeps far below
        points_W_.resize(points_W_.size() + capacity_);
      }
      e = v << kCountBits;
    } else {
      const Eigen::Vector3f* held = &points_W_[First(e)];
      bool near = false;
      for (Entry i = 0; i < count && !near; ++i) near = (held[i] - pf).squaredNorm() < spacing2;
      if (near) continue;
    }
    points_W_[First(e) + count] = pf;
    ++e;
    ++stored;
  }
  points_ += stored;
  return stored;
}

int PointMap::Prune(const Vector3& center_W) {
  const double r2 = options_.window_radius_m * options_.window_radius_m;
  const double block_m = kBlockEdge * options_.voxel_m;
  int removed = 0;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    Block& block = blocks_[i];
    const Eigen::Vector3i b = BlockOfKey(block.key);
    const Vector3 centre = (b.cast<double>().array() + 0.5).matrix() * block_m;
    if ((centre - center_W).squaredNorm() > r2) {
      for (const Entry e : block.entry) {
        if ((e & kCountMask) == 0) continue;
        removed += static_cast<int>(e & kCountMask);
        free_voxels_.push_back(e >> kCountBits);
      }
      continue;
    }
    if (kept != i) blocks_[kept] = block;
    ++kept;
  }
  if (kept == blocks_.size()) return 0;
  blocks_.resize(kept);
  // The index again, for the blocks that stay.
  block_index_.Clear(kept);
  bool added = false;
  for (std::size_t i = 0; i < kept; ++i) block_index_.FindOrAdd(blocks_[i].key, static_cast<std::uint32_t>(i), &added);
  points_ -= removed;
  return removed;
}

int PointMap::Nearest(const Vector3& query, int k, double radius_m, std::vector<Vector3>* out,
                      std::vector<double>* squared_distances) const {
  out->clear();
  if (squared_distances) squared_distances->clear();
  // A query beyond the keys' range (where Insert stores nothing) has no neighbours; its cell
  // would not even fit an int.
  if (k <= 0 || !query.allFinite() || blocks_.empty() || query.cwiseAbs().maxCoeff() > KeyRange()) return 0;
  const double r = std::min(radius_m, options_.voxel_m);
  const float r2 = static_cast<float>(r * r);
  const Eigen::Vector3i c = Cell(query);
  // A neighbour voxel is visited only when it comes within r of the query: per axis the distance
  // to the lower and the upper face of the query's voxel.
  const Vector3 low = query - c.cast<double>() * options_.voxel_m;  // in [0, voxel_m)
  const Vector3 high = Vector3::Constant(options_.voxel_m) - low;
  // The 3 x 3 x 3 cells span at most 2 blocks per axis; each is looked up once, when first needed
  // (its position in blocks_, -1 when there is none).
  const Eigen::Vector3i first_block = BlockOf(c - Eigen::Vector3i::Ones());
  constexpr std::int64_t kNotLookedUp = -2;
  std::array<std::int64_t, 8> block_at;
  block_at.fill(kNotLookedUp);
  // The k best so far, sorted by distance (k is small: a plane needs five).
  std::array<std::pair<float, Eigen::Vector3f>, 16> best;
  const int kk = std::min(k, static_cast<int>(best.size()));
  int n = 0;
  const Eigen::Vector3f qf = query.cast<float>();
  // Visits the voxels whose nearest point lies at a squared distance in (inner2, outer2] of the
  // query: first the entries, their points prefetched, then the points, so that the voxels' loads
  // overlap rather than wait on each other.
  const auto visit_shell = [&](double inner2, double outer2) {
    std::array<Entry, 27> visit;
    int visits = 0;
    for (int dx = -1; dx <= 1; ++dx) {
      const double ex = dx < 0 ? low.x() : dx > 0 ? high.x() : 0.0;
      for (int dy = -1; dy <= 1; ++dy) {
        const double ey = dy < 0 ? low.y() : dy > 0 ? high.y() : 0.0;
        for (int dz = -1; dz <= 1; ++dz) {
          const double ez = dz < 0 ? low.z() : dz > 0 ? high.z() : 0.0;
          const double e2 = ex * ex + ey * ey + ez * ez;
          if (e2 <= inner2 || e2 > outer2) continue;
          const Eigen::Vector3i cell = c + Eigen::Vector3i(dx, dy, dz);
          const Eigen::Vector3i b = BlockOf(cell), o = b - first_block;  // o: 0 or 1 on each axis
          std::int64_t& at = block_at[static_cast<std::size_t>((o.x() * 2 + o.y()) * 2 + o.z())];
          if (at == kNotLookedUp) at = block_index_.Find(KeyOfCell(b));
          if (at < 0) continue;
          const Entry e = blocks_[static_cast<std::size_t>(at)].entry[static_cast<std::size_t>(EntryIndex(cell))];
          if ((e & kCountMask) == 0) continue;
          visit[static_cast<std::size_t>(visits++)] = e;
          __builtin_prefetch(&points_W_[First(e)]);
        }
      }
    }
    for (int m = 0; m < visits; ++m) {
      const Entry e = visit[static_cast<std::size_t>(m)];
      const Eigen::Vector3f* points = &points_W_[First(e)];
      for (Entry i = 0; i < (e & kCountMask); ++i) {
        const float d2 = (points[i] - qf).squaredNorm();
        if (d2 > r2 || (n == kk && d2 >= best[n - 1].first)) continue;
        int j = n < kk ? n++ : n - 1;  // insertion sort into the k best
        while (j > 0 && best[j - 1].first > d2) {
          best[j] = best[j - 1];
          --j;
        }
        best[j] = {d2, points[i]};
      }
    }
  };
  // Within half the radius first (about a third of the cells the whole radius meets): when the
  // k found there lie within it, every point of the cells not visited is farther (each of those
  // cells is), and the answer is exact already. Otherwise the rest of the radius.
  const double inner2 = 0.25 * r * r;  // (r / 2)²
  visit_shell(-1.0, inner2);
  if (n < kk || best[n - 1].first > static_cast<float>(inner2)) visit_shell(inner2, r * r);
  for (int i = 0; i < n; ++i) {
    out->push_back(best[i].second.cast<double>());
    if (squared_distances) squared_distances->push_back(best[i].first);
  }
  return n;
}

}  // namespace rotorguard::perception
