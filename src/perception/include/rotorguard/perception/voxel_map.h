#pragma once
/// Local occupancy map for planning among obstacles the vehicle discovers (paper 000 Sec. V-C
/// plans on a LiDAR map built while spinning). Voxels (0.1 m by default) in a window that follows
/// the vehicle, stored as a ring buffer so that moving the window clears only the slabs it leaves.
/// Each frame updates log-odds (Thrun, Burgard, Fox, Probabilistic Robotics, Sec. 9.2): the voxel
/// of every return is hit, the voxels its ray crossed are missed, each voxel updated at most once
/// per frame (hits win), so that an obstacle that moved away is cleared by the rays that now pass
/// through it. Occupied voxels are inflated by the vehicle radius in a second layer kept up to
/// date incrementally, which the planner's queries read.
#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "rotorguard/core/types.h"

namespace rotorguard::perception {

namespace internal {
/// a mod n for n a power of two, also for negative a (two's complement).
inline int PositiveMod(int a, int n) { return a & (n - 1); }
}  // namespace internal

struct VoxelMapOptions {
  double resolution_m = 0.1;                      ///< voxel edge [m], > 0
  /// Extent of the local window [m], > resolution; rounded up to a power of two voxels per axis
  /// (24 x 24 x 6 m at 0.1 m gives 25.6 x 25.6 x 6.4 m).
  Vector3 window_size_m = Vector3(24.0, 24.0, 6.0);
  // Log-odds are stored in fixed point (steps of 0.001, |value| <= 30) so that a voxel's state
  // fits the 4 bytes one ray step touches.
  double log_odds_hit = 0.85;   ///< added on a return (p = 0.7), in (0, 30]
  double log_odds_miss = -0.4;  ///< added when a ray passes (p = 0.4), in [-30, 0)
  double log_odds_min = -2.0;   ///< clamp, in [-30, 0)
  double log_odds_max = 3.5;    ///< clamp, in (0, 30]
  double occupied_threshold = 0.7;  ///< occupied above this log-odds (two hits from unknown), in (0, max)
  double inflation_radius_m = 0.2;  ///< the vehicle's radius [m], >= 0
  /// Rays longer than this only clear up to it (and still mark their return) [m], > 0.
  double max_clearing_range_m = 20.0;
  /// The window follows its centre along an axis only once the centre is more than this from the
  /// window's centre there [m], in [0, a quarter of the smallest extent]. Without it a centre on a
  /// voxel boundary (a level flight at z = 1.5 m) moves the window back and forth with the
  /// estimate's noise, and each move of a whole face costs more than a frame's rays.
  double recenter_hysteresis_m = 0.5;
  void Validate() const;
};

struct MapUpdateSummary {
  int points_used = 0;
  int points_dropped = 0;  ///< non-finite, or their voxel outside the window
  int voxels_updated = 0;
  long voxels_traversed = 0;  ///< steps of the rays' walks (the update's cost)
};

/// The nearest occupied voxel to a query point.
struct NearestObstacle {
  Vector3 point_W;   ///< the voxel's centre
  double distance_m = 0.0;
  Vector3 normal_W;  ///< unit vector from the obstacle towards the query (the obstacle's outward normal there)
};

class VoxelMap {
 public:
  explicit VoxelMap(const VoxelMapOptions& options);
  const VoxelMapOptions& options() const { return options_; }

  /// Moves the window so that it is centred on `center_W` (to the voxel) along each axis where the
  /// centre is beyond the hysteresis; voxels that leave are forgotten. Cheap when the centre moved
  /// little.
  void Recenter(const Vector3& center_W);
  /// Integrates one frame of returns (world frame) measured from `origin_W`.
  MapUpdateSummary Insert(const Vector3& origin_W, const std::vector<Eigen::Vector3f>& points_W);

  /// Sets the voxel of `p_W` occupied with the largest log-odds (known), as if hit many times:
  /// for maps built from a known world (planner benchmarks, tests). Outside the window: nothing.
  void MarkOccupied(const Vector3& p_W);

  bool InWindow(const Vector3& p_W) const;
  /// The window's corners [m]: it covers [window_min_W, window_max_W).
  Vector3 window_min_W() const { return origin_.cast<double>() * res_; }
  Vector3 window_max_W() const { return (origin_ + size_).cast<double>() * res_; }
  /// The window's extent in voxels per axis (powers of two).
  Eigen::Vector3i size_voxels() const { return size_; }
  /// Occupied (log-odds above the threshold). Outside the window: false.
  bool IsOccupied(const Vector3& p_W) const;
  /// Observed at least once (hit or missed). Outside the window: false.
  bool IsKnown(const Vector3& p_W) const;
  /// Within the inflation radius of an occupied voxel. Outside the window: false.
  bool IsInflated(const Vector3& p_W) const;
  /// The nearest occupied voxel within `radius_m` of p, if any.
  std::optional<NearestObstacle> Nearest(const Vector3& p_W, double radius_m) const;
  /// Whether the segment a-b passes through an inflated voxel (unknown and outside-window space
  /// count as free: the planner is optimistic about what it has not seen).
  bool SegmentCollides(const Vector3& a_W, const Vector3& b_W) const;

  /// Centres of all occupied voxels (for scoring and display).
  std::vector<Vector3> OccupiedVoxels() const;
  int occupied_count() const { return occupied_count_; }
  double resolution() const { return res_; }

 private:
  using Index = Eigen::Vector3i;
  Index ToIndex(const Vector3& p) const;
  Vector3 Center(const Index& i) const;
  /// Whether i lies in the window of this size whose lower corner is `origin`.
  bool InWindowAt(const Index& i, const Index& origin) const {
    return (i.array() >= origin.array()).all() && (i.array() < (origin + size_).array()).all();
  }
  bool InWindow(const Index& i) const { return InWindowAt(i, origin_); }
  /// Where voxel i is stored: its coordinates wrapped into the ring buffer, in bricks of
  /// 8 x 8 x 8 voxels, each contiguous (a ray stays in one brick, a few cache lines, for several
  /// steps in any direction, where a row-major layout jumps a whole plane per step).
  std::size_t Address(const Index& i) const { return AddressOfPacked(Pack(i)); }
  /// Wrapped coordinates packed in one word, a 16-bit field per axis (12 used; the gap keeps a
  /// field's carry from reaching the next before the mask wraps it): what a ray step updates with
  /// one add and one and, the address following only when a voxel is visited.
  static constexpr int kPackShift = 16;
  std::uint64_t Pack(const Index& i) const {
    return static_cast<std::uint64_t>(internal::PositiveMod(i.x(), size_.x())) |
           static_cast<std::uint64_t>(internal::PositiveMod(i.y(), size_.y())) << kPackShift |
           static_cast<std::uint64_t>(internal::PositiveMod(i.z(), size_.z())) << (2 * kPackShift);
  }
  std::uint32_t AddressOfPacked(std::uint64_t p) const { return AddressOfPacked(p, brick_shift_y_, brick_shift_z_); }
  /// The address of packed coordinates, with log2 of the bricks along y and z passed in: the hot
  /// loops keep them in registers (a byte store may alias the members, which the compiler would
  /// otherwise reload after every stamp written).
  static std::uint32_t AddressOfPacked(std::uint64_t p, int shift_y, int shift_z) {
    const auto x = static_cast<std::uint32_t>(p & 0xffff), y = static_cast<std::uint32_t>((p >> kPackShift) & 0xffff),
               z = static_cast<std::uint32_t>(p >> (2 * kPackShift));
    const std::uint32_t brick = ((x >> 3) << (shift_y + shift_z)) | ((y >> 3) << shift_z) | (z >> 3);
    return (brick << 9) | ((x & 7) << 6) | ((y & 7) << 3) | (z & 7);
  }
  /// The window's voxel stored at this address.
  Index IndexOf(std::size_t address) const;
  /// One voxel's state, packed so that a ray step reads and writes a single cache line.
  struct Cell {
    std::int16_t log_odds = 0;  // fixed point, kLogOddsScale per unit
    std::uint8_t stamp = 0;     // 2f: missed in frame f, 2f + 1: hit (f in 1..127)
    std::uint8_t known = 0;     // observed at least once
  };
  static constexpr double kLogOddsScale = 1000.0;
  bool Occupied(const Cell& c) const { return c.log_odds > occupied_q_; }
  void Inflate(const Index& i, int delta);
  /// A hit or a miss: the voxel is known and its log-odds move by the step (fixed point),
  /// clamped; the occupied count and the inflation layer follow a change of state.
  void Observe(std::size_t address, int log_odds_step) {
    Cell& cell = cells_[address];
    cell.known = 1;
    const bool was = Occupied(cell);
    cell.log_odds = static_cast<std::int16_t>(std::clamp(cell.log_odds + log_odds_step, min_q_, max_q_));
    const bool now = Occupied(cell);
    if (was == now) return;
    occupied_count_ += now ? 1 : -1;
    Inflate(IndexOf(address), now ? 1 : -1);
  }
  /// Visits the window's voxels that the segment a-b (voxel units) crosses, in order (Amanatides
  /// and Woo 1987), as visit(packed) until it returns false. The segment is clipped to
  /// the window first and the packed ring-buffer coordinates follow each step, the map's hottest
  /// loop.
  template <typename Visit>
  void TraverseWindow(const Vector3& a, const Vector3& b, Visit&& visit) const;

  VoxelMapOptions options_;
  double res_;
  Index size_;            // voxels per axis
  Index origin_;          // global index of the window's lower corner
  int hit_q_, miss_q_, min_q_, max_q_, occupied_q_;  // the options' log-odds in fixed point
  std::vector<Cell> cells_;
  std::vector<std::uint16_t> inflation_;  // occupied voxels within the radius
  std::uint32_t frame_ = 0;
  std::vector<Index> stencil_;            // offsets within the inflation radius
  /// Offsets within kSortedOffsetRadius voxels, by increasing distance: Nearest visits them in
  /// order and stops early (the planner asks it for every penalty sample).
  static constexpr int kSortedOffsetRadius = 12;
  struct SortedOffset {
    Index offset;
    double distance;  // [voxels]
  };
  std::vector<SortedOffset> sorted_offsets_;
  int stencil_radius_ = 0;                // the stencil's extent along each axis [voxels]
  int hysteresis_voxels_ = 0;             // recenter_hysteresis_m in whole voxels
  std::vector<Index> touched_hit_;
  std::vector<Vector3> ray_ends_;  // the returns whose rays a frame walks
  std::vector<std::uint64_t> walk_;   // the packed voxels a batch of rays crosses, in order
  std::vector<std::uint32_t> addresses_;  // their addresses
  std::uint64_t pack_mask_ = 0;       // each packed field's wrap mask (size - 1)
  int brick_shift_y_ = 0, brick_shift_z_ = 0;  // log2 of the bricks along y and z
  int occupied_count_ = 0;
};

}  // namespace rotorguard::perception
