#pragma once
/// The LiDAR-inertial odometry's map: the registered points themselves, in a hash of voxels (the
/// incremental voxel map of Bai et al., "Faster-LIO", RA-L 2022, in place of FAST-LIO2's ikd-tree).
/// A point goes into the voxel that contains it; a voxel keeps at most max_points_per_voxel points,
/// and a new point closer than min_point_spacing_m to one it already holds is not stored (the
/// down-sampling happens on the map, as in FAST-LIO2, so a surface seen again and again does not
/// grow it). Voxels are grouped in blocks of 4 x 4 x 4; blocks farther than window_radius_m from
/// the vehicle are deleted (Prune), so the map follows the vehicle like the occupancy map does.
/// Nearest neighbours within a voxel edge of the query are exact: the query's voxel and its 26
/// neighbours hold all of them, and only those that come within the radius are read.
#include <array>
#include <cstdint>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"

namespace rotorguard::perception {

struct PointMapOptions {
  double voxel_m = 0.5;  ///< hash voxel edge [m], in [0.05, 10]; the neighbour search's exact radius
  /// Points a voxel holds at most, in [1, kMaxPointsPerVoxel].
  int max_points_per_voxel = 20;
  static constexpr int kMaxPointsPerVoxel = 32;
  /// A point this close [m] to one its voxel holds is not stored, in [0, voxel_m).
  double min_point_spacing_m = 0.1;
  /// Blocks of 4 x 4 x 4 voxels whose centre is farther than this from the vehicle are deleted by
  /// Prune [m], in [6 voxel_m, 1e4] (the vehicle's block and its surroundings always stay).
  double window_radius_m = 60.0;
  /// Throws ValidationError naming the field.
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("voxel_m", &voxel_m, {.meaning = "the point map's hash voxel edge [m]", .min = 0.05, .max = 10});
    a->Visit("max_points_per_voxel", &max_points_per_voxel,
             {.meaning = "points a voxel keeps at most", .min = 1, .max = kMaxPointsPerVoxel});
    a->Visit(
        "min_point_spacing_m", &min_point_spacing_m,
        {.meaning = "a point this close to one its voxel holds is not stored [m], below voxel_m", .min = 0, .max = 10});
    // At least 6 voxel edges of the smallest voxel.
    a->Visit("window_radius_m", &window_radius_m,
             {.meaning = "blocks of 4^3 voxels farther than this from the vehicle are deleted [m], at least 6 voxel_m",
              .min = 0.3,
              .max = 1e4});
  }
};

/// A 64-bit key for the integer cell `c` of any grid: 21 bits per axis (±2^20 cells), offset to
/// be non-negative; the top bit stays clear.
using CellKey = std::uint64_t;
CellKey KeyOfCell(const Eigen::Vector3i& c);

/// Cell key -> index, open addressing with linear probing, at most half full. A lookup touches
/// one slot (16 bytes) where a node-based hash chases two pointers and allocates per key: the
/// point map looks up 8 voxels for each of a frame's thousands of points, and the frame's
/// down-sampling one cell for each of its tens of thousands.
class CellIndex {
 public:
  /// Empty, with room for `expected` keys before it grows (its storage kept).
  void Clear(std::size_t expected);
  /// The index stored for `key`, or -1.
  std::int64_t Find(CellKey key) const;
  /// The index stored for `key`; when absent, `next` is stored for it and *added set.
  std::uint32_t FindOrAdd(CellKey key, std::uint32_t next, bool* added);
  std::size_t size() const { return size_; }

 private:
  struct Slot {
    CellKey key = kEmpty;
    std::uint32_t index = 0;
  };
  static constexpr CellKey kEmpty = ~CellKey{0};  ///< KeyOfCell uses 63 bits: never a key
  /// The slot holding `key`, or the empty one where it would go.
  std::size_t Probe(CellKey key) const;
  void Grow();
  std::vector<Slot> slots_;
  std::size_t size_ = 0;
};

class PointMap {
 public:
  explicit PointMap(const PointMapOptions& options);
  const PointMapOptions& options() const { return options_; }

  /// Stores each point unless its voxel is full or holds one within min_point_spacing_m.
  /// Returns how many were stored. Non-finite points are skipped.
  int Insert(const std::vector<Vector3>& points_W);
  /// Deletes the blocks whose centre is farther than window_radius_m from `center_W`. Returns
  /// how many points went.
  int Prune(const Vector3& center_W);

  /// The up to `k` (at most 16) stored points nearest to `query` within `radius_m` (at most voxel_m), nearest
  /// first, into `out`; their squared distances into `squared_distances` if not null. Returns how
  /// many were found.
  int Nearest(const Vector3& query, int k, double radius_m, std::vector<Vector3>* out,
              std::vector<double>* squared_distances = nullptr) const;

  long size() const { return points_; }
  long voxels() const { return static_cast<long>(points_W_.size() / capacity_ - free_voxels_.size()); }

 private:
  /// Voxels are found through blocks of 4 x 4 x 4 cells: one hash lookup finds a block, whose
  /// dense table gives each of its cells' voxel and point count. A query's neighbour cells share
  /// one to a few blocks, and an empty cell (most of them around a thin trunk) costs a read of a
  /// table already in cache, not a probe of a hash larger than the cache; a voxel's points are
  /// read only when it holds some, and then they are all the bytes read.
  static constexpr int kBlockShift = 2, kBlockEdge = 1 << kBlockShift;
  /// A table entry: (voxel << kCountBits) | count; count 0: no voxel (a voxel is made for a point).
  using Entry = std::uint32_t;
  static constexpr int kCountBits = 6;  // counts up to kMaxPointsPerVoxel = 32
  static constexpr Entry kCountMask = (Entry{1} << kCountBits) - 1;
  static_assert(PointMapOptions::kMaxPointsPerVoxel <= kCountMask);
  struct Block {
    CellKey key = 0;
    std::array<Entry, kBlockEdge * kBlockEdge * kBlockEdge> entry{};
  };
  /// The voxel index of a coordinate on each axis.
  Eigen::Vector3i Cell(const Vector3& p) const;
  /// The largest |coordinate| [m] a key holds (2^20 voxels, with a margin): beyond, none is stored.
  double KeyRange() const;
  /// The block holding a cell, and the cell's entry in the block's table.
  static Eigen::Vector3i BlockOf(const Eigen::Vector3i& cell);
  static int EntryIndex(const Eigen::Vector3i& cell);
  /// The cell a key packs (KeyOfCell's inverse): a block's, here.
  static Eigen::Vector3i BlockOfKey(CellKey key);
  /// `cell`'s entry in its block's table (the block created, empty, when new).
  Entry& EntryOf(const Eigen::Vector3i& cell);
  /// The first of a voxel's max_points_per_voxel points in points_W_.
  std::size_t First(Entry e) const { return static_cast<std::size_t>(e >> kCountBits) * capacity_; }

  PointMapOptions options_;
  double inverse_voxel_ = 0.0;
  std::size_t capacity_ = 0;  ///< max_points_per_voxel
  CellIndex block_index_;     ///< block key -> position in blocks_
  std::vector<Block> blocks_;
  /// Each voxel's points, `capacity_` slots apiece; the slots of pruned voxels are reused.
  std::vector<Eigen::Vector3f> points_W_;
  std::vector<std::uint32_t> free_voxels_;
  long points_ = 0;
};

}  // namespace rotorguard::perception
