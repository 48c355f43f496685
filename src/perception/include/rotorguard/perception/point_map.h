#pragma once
/// The LiDAR-inertial odometry's map: the registered points themselves, in a hash of voxels (the
/// incremental voxel map of Bai et al., "Faster-LIO", RA-L 2022, in place of FAST-LIO2's ikd-tree).
/// A point goes into the voxel that contains it; a voxel keeps at most max_points_per_voxel points,
/// and a new point closer than min_point_spacing_m to one it already holds is not stored (the
/// down-sampling happens on the map, as in FAST-LIO2, so a surface seen again and again does not
/// grow it). Voxels farther than window_radius_m from the vehicle are deleted (Prune), so the map
/// follows the vehicle like the occupancy map does. Nearest neighbours within a voxel edge of the
/// query are exact: the query's voxel and its 26 neighbours hold all of them, and a search
/// radius of half the edge visits 8 of them on average (those that come within the radius).
#include <array>
#include <cstdint>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"

namespace rotorguard::perception {

struct PointMapOptions {
  double voxel_m = 1.0;  ///< hash voxel edge [m], in [0.05, 10]; the neighbour search's exact radius
  /// Points a voxel holds at most, in [1, kMaxPointsPerVoxel].
  int max_points_per_voxel = 20;
  static constexpr int kMaxPointsPerVoxel = 32;
  /// A point this close [m] to one its voxel holds is not stored, in [0, voxel_m).
  double min_point_spacing_m = 0.1;
  /// Voxels whose centre is farther than this from the vehicle are deleted by Prune [m], in
  /// [2 voxel_m, 1e4].
  double window_radius_m = 60.0;
  /// Throws ValidationError naming the field.
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("voxel_m", &voxel_m, {.meaning = "the point map's hash voxel edge [m]", .min = 0.05, .max = 10});
    a->Visit("max_points_per_voxel", &max_points_per_voxel,
             {.meaning = "points a voxel keeps at most", .min = 1, .max = kMaxPointsPerVoxel});
    a->Visit("min_point_spacing_m", &min_point_spacing_m,
             {.meaning = "a point this close to one its voxel holds is not stored [m], below voxel_m", .min = 0});
    a->Visit("window_radius_m", &window_radius_m,
             {.meaning = "voxels farther than this from the vehicle are deleted [m], at least 2 voxel_m", .max = 1e4});
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
  /// Deletes the voxels whose centre is farther than window_radius_m from `center_W`. Returns
  /// how many points went.
  int Prune(const Vector3& center_W);

  /// The up to `k` (at most 16) stored points nearest to `query` within `radius_m` (at most voxel_m), nearest
  /// first, into `out`; their squared distances into `squared_distances` if not null. Returns how
  /// many were found.
  int Nearest(const Vector3& query, int k, double radius_m, std::vector<Vector3>* out,
              std::vector<double>* squared_distances = nullptr) const;

  long size() const { return points_; }
  long voxels() const { return static_cast<long>(voxels_.size()); }

 private:
  using Key = CellKey;
  struct Voxel {
    Key key = 0;
    int count = 0;
    std::array<Eigen::Vector3f, PointMapOptions::kMaxPointsPerVoxel> points;
  };
  /// The voxel index of a coordinate on each axis, and the cell a key packs.
  Eigen::Vector3i Cell(const Vector3& p) const;
  static Eigen::Vector3i CellOf(Key key);

  /// The voxel of `key`, created empty when new.
  std::uint32_t FindOrAdd(Key key);

  PointMapOptions options_;
  double inverse_voxel_ = 0.0;
  CellIndex index_;  ///< key -> position in voxels_
  std::vector<Voxel> voxels_;
  long points_ = 0;
};

}  // namespace rotorguard::perception
