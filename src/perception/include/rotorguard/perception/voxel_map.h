#pragma once
/// Local occupancy map for planning among obstacles the vehicle discovers (paper 000 Sec. V-C
/// plans on a LiDAR map built while spinning). Voxels (0.1 m by default) in a window that follows
/// the vehicle, stored as a ring buffer so that moving the window clears only the slabs it leaves.
/// Each frame updates log-odds (Thrun, Burgard, Fox, Probabilistic Robotics, Sec. 9.2): the voxel
/// of every return is hit, the voxels its ray crossed are missed (of every ray, or of one in
/// clearing_stride), each voxel updated at most once per frame (hits win), so that an obstacle
/// that moved away is cleared by the rays that now pass through it. The planner's queries see
/// occupied voxels inflated by the vehicle radius, read from a bit per voxel at query time: a
/// layer of inflation counts kept up to date instead cost a scattered cache line per stencil
/// column (29 at the flight stack's 0.3 m) for each voxel that changed state, a fifth of the
/// map's update.
#include <algorithm>
#include <cstdint>
#include <numbers>
#include <optional>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/huge_pages.h"
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
  double occupied_threshold = 0.7;  ///< occupied above this log-odds (one hit from unknown: 0.85), in (0, max)
  double inflation_radius_m = 0.2;  ///< the vehicle's radius [m], >= 0
  /// Rays longer than this only clear up to it (and still mark their return) [m], > 0.
  double max_clearing_range_m = 20.0;
  /// A frame walks one in this many of its rays, in [1, kMaxClearingStride]: the n-th frame given
  /// to Insert (n from 0, a frame dropped for a non-finite origin included) those of index
  /// i = n (mod stride) in the frame's list of rays (one per hit voxel and one per return outside
  /// the window, in the returns' order). Every return is still hit. The walks are most of a
  /// frame's cost, and most of their steps cross space already settled free by earlier frames;
  /// 1 walks every ray.
  int clearing_stride = 1;
  /// At 10 Hz each residue's rays are then walked at least every 1.6 s.
  static constexpr int kMaxClearingStride = 16;
  /// The window follows its centre along an axis only once the centre is more than this from the
  /// window's centre there [m], in [0, a quarter of the smallest extent]. Without it a centre on a
  /// voxel boundary (a level flight at z = 1.5 m) moves the window back and forth with the
  /// estimate's noise, and each move of a whole face costs more than a frame's rays.
  double recenter_hysteresis_m = 0.5;
  /// How a frame's rays are walked. Both kernels list exactly the same voxels (a test flies one
  /// map per kernel and compares them); they differ in speed only. kAuto walks four rays in one
  /// vector register when the build targets AVX2 (x86-64-v3), else two interleaved rays;
  /// kPortable forces the latter.
  enum class WalkKernel { kAuto, kPortable };
  WalkKernel walk_kernel = WalkKernel::kAuto;
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    // The window also holds at most 4096 voxels an axis and 64 million in all (Validate): a fine
    // resolution needs a small window.
    a->Visit("resolution_m", &resolution_m, {.meaning = "voxel edge [m]", .min = 0.01, .max = 5.0});
    a->Visit("window_size_m", &window_size_m,
             {.meaning = "the map's window around the vehicle [m], rounded up to a power of two voxels per axis; "
                         "at most 4096 voxels an axis and 64 million in all",
              .max = 2000.0,
              .positive = true});
    // The fixed-point store holds |log-odds| <= 30.
    a->Visit("log_odds_hit", &log_odds_hit, {.meaning = "log-odds added by a return", .max = 30.0, .positive = true});
    a->Visit("log_odds_miss", &log_odds_miss,
             {.meaning = "log-odds added by a ray passing through", .min = -30.0, .max = 0.0, .open_max = true});
    a->Visit("log_odds_min", &log_odds_min,
             {.meaning = "lower clamp of a voxel's log-odds", .min = -30.0, .max = 0.0, .open_max = true});
    a->Visit("log_odds_max", &log_odds_max,
             {.meaning = "upper clamp of a voxel's log-odds", .max = 30.0, .positive = true});
    a->Visit("occupied_threshold", &occupied_threshold,
             {.meaning = "log-odds above which a voxel is occupied",
              .max = 30.0,
              .positive = true,
              .rule_text = "in (0, log_odds_max)"});
    a->Visit("max_clearing_range_m", &max_clearing_range_m,
             {.meaning = "rays clear free space up to this range [m]", .max = 1e4, .positive = true});
    a->Visit("clearing_stride", &clearing_stride,
             {.meaning = "a frame walks one in this many of its rays (every return is still hit)",
              .min = 1,
              .max = kMaxClearingStride});
    a->Visit("recenter_hysteresis_m", &recenter_hysteresis_m,
             {.meaning = "the window follows an axis once the vehicle is this far from its centre along it [m]",
              .min = 0.0,
              .max = 500.0,
              .rule_text = "in [0, a quarter of the smallest window_size_m]"});
  }
};

struct MapUpdateSummary {
  int points_used = 0;
  int points_dropped = 0;  ///< non-finite, or their voxel outside the window
  int rays_walked = 0;     ///< the frame's rays whose free space was walked (clearing_stride)
  int voxels_updated = 0;
  long voxels_traversed = 0;  ///< voxels the rays' walks visited, each ray's last included (the update's cost)
  /// Of those, the visits the update skipped: to settled-free voxels (known and at the lower
  /// clamp, which a miss leaves as they are) and to voxels the frame had already hit or missed.
  long voxels_skipped = 0;
};

/// The nearest occupied voxel to a query point.
struct NearestObstacle {
  Vector3 point_W;   ///< the voxel's centre
  double distance_m = 0.0;
  Vector3 normal_W;  ///< unit vector from the obstacle towards the query (the obstacle's outward normal there)
};

/// Threads: a map may be read from one thread at a time only; its inflation queries fill a memo.
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
  /// Within the inflation radius of an occupied voxel. Outside the window: false. Not safe to
  /// call from two threads at once on one map, nor with SegmentCollides: both fill a memo.
  bool IsInflated(const Vector3& p_W) const;
  /// The voxel holding p (its index: floor of p over the resolution, per axis), and IsInflated of a
  /// voxel by index: IsInflated(p) is IsInflatedVoxel(VoxelOf(p)) for a finite p. A search asking
  /// for many points on a grid computes their voxels once per axis.
  Eigen::Vector3i VoxelOf(const Vector3& p_W) const { return ToIndex(p_W); }
  bool IsInflatedVoxel(const Eigen::Vector3i& voxel) const { return InWindow(voxel) && Inflated(Address(voxel)); }
  /// The nearest occupied voxel within `radius_m` of p, if any; of equally near ones, the one of
  /// lowest index (x, then y, then z). Up to FastNearestRadiusM it reads the columns along z of
  /// the disc around p by increasing distance, a column's height range a word of occupied bits at
  /// a time, and stops once no column left can hold a nearer voxel (about a hundred words for
  /// nothing within 0.5 m at 0.1 m); beyond, it scans a cube, whose cost grows with the radius
  /// cubed.
  std::optional<NearestObstacle> Nearest(const Vector3& p_W, double radius_m) const;
  /// The largest radius of Nearest's fast search at `resolution_m`: 12 voxels, less half a
  /// voxel's diagonal (the query's offset from its voxel's centre).
  static double FastNearestRadiusM(double resolution_m) {
    return (kSortedOffsetRadius - 0.5 * std::numbers::sqrt3) * resolution_m;
  }
  /// Whether the segment a-b passes through an inflated voxel (unknown and outside-window space
  /// count as free: the planner is optimistic about what it has not seen). Fills the same memo
  /// as IsInflated (one thread at a time).
  bool SegmentCollides(const Vector3& a_W, const Vector3& b_W) const;

  /// Centres of all occupied voxels (for scoring and display), in no particular order.
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
  /// Where voxel i is stored: its coordinates wrapped into the ring buffer (modulo the window's
  /// size, a power of two per axis), row-major with z fastest: (x << (ly + lz)) | (y << lz) | z.
  std::size_t Address(const Index& i) const {
    return (static_cast<std::size_t>(i.x() & (size_.x() - 1)) << shift_x_) |
           (static_cast<std::size_t>(i.y() & (size_.y() - 1)) << shift_y_) |
           static_cast<std::size_t>(i.z() & (size_.z() - 1));
  }
  /// A voxel's offset from the window's lower corner in the same bit fields as an address:
  /// what a ray's walk carries (inside the window no field ever wraps, so a step is one add).
  std::uint64_t RelativeIndex(const Index& i) const {
    const Index r = i - origin_;
    return (static_cast<std::uint64_t>(r.x()) << shift_x_) | (static_cast<std::uint64_t>(r.y()) << shift_y_) |
           static_cast<std::uint64_t>(r.z());
  }
  /// The address of a relative index: the origin's residues added field by field modulo each
  /// field's size, without carries between fields (each field's top bit is added apart and
  /// xor-ed in).
  static std::uint32_t AddressOfRelative(std::uint64_t relative, std::uint64_t origin_residues, std::uint64_t top_bits) {
    return static_cast<std::uint32_t>(((relative & ~top_bits) + (origin_residues & ~top_bits)) ^
                                      ((relative ^ origin_residues) & top_bits));
  }
  std::uint32_t AddressOfRelative(std::uint64_t relative) const {
    return AddressOfRelative(relative, origin_residues_, field_top_bits_);
  }
  /// Moves the window's lower corner (and the residues the walks' addresses add).
  void SetOrigin(const Index& origin);
  /// The window's voxel stored at this address.
  Index IndexOf(std::size_t address) const;
  /// One voxel's state in 4 bytes: an update reads and writes one cache line.
  struct Cell {
    std::int16_t log_odds = 0;  // fixed point, kLogOddsScale per unit
    std::uint8_t stamp = 0;     // 2f: missed in frame f, 2f + 1: hit (f in 1..127)
    std::uint8_t known = 0;     // observed at least once
  };
  static constexpr double kLogOddsScale = 1000.0;
  /// Settled free: known and at the lower clamp, where a miss changes nothing. One bit per voxel
  /// at the voxel's address (512 KB for the default window, which a core's L2 cache can hold):
  /// most of a frame's ray steps cross such voxels (89 % in the forest), and testing the bit
  /// spares the first touch of the cell's line in a window larger than the caches.
  bool SettledFree(std::size_t address) const { return SettledFree(settled_free_.data(), address); }
  /// The same bit read through a pointer the hot loop keeps in a register.
  static bool SettledFree(const std::uint64_t* bits, std::size_t address) { return GetBit(bits, address); }
  /// The walk kernels' listing: `address` written at `out`, kept (the end moved past it) unless
  /// its settled bit is set; without a branch, as which voxels are settled is unpredictable.
  static std::uint32_t* ListUnlessSettled(std::uint32_t address, const std::uint64_t* settled, std::uint32_t* out) {
    *out = address;
    return out + static_cast<std::ptrdiff_t>(!SettledFree(settled, address));
  }
  void SetSettledFree(std::size_t address, bool settled) { SetBit(&settled_free_, address, settled); }
  /// Insert's walks skip a voxel whose bit is set, and a voxel the frame has hit or missed is
  /// updated no more in that frame: its bit is set for the rest of the frame, which spares the
  /// walks listing it again (a cache miss on its cell each time: 37 % of the forest demo's
  /// listings). Insert clears the bits it set (handled_) when the frame is done.
  void MarkHandled(std::uint32_t address) {
    if (SettledFree(address)) return;
    SetSettledFree(address, true);
    handled_.push_back(address);
  }
  /// Bit `address` of a set of bits kept in 64-bit words.
  static bool GetBit(const std::uint64_t* bits, std::size_t address) { return (bits[address >> 6] >> (address & 63)) & 1U; }
  static void SetBit(HugePageVector<std::uint64_t>* bits, std::size_t address, bool value) {
    const std::uint64_t bit = std::uint64_t{1} << (address & 63);
    std::uint64_t& word = (*bits)[address >> 6];
    word = value ? word | bit : word & ~bit;
  }
  bool Occupied(const Cell& c) const { return c.log_odds > occupied_q_; }
  /// The same, from the occupied bit at this address (kept equal to Occupied of its cell).
  bool OccupiedBit(std::size_t address) const { return GetBit(occupied_.data(), address); }
  /// Whether an occupied voxel of the window lies within the inflation radius of voxel i: the
  /// stencil's columns read as runs of the occupied bits.
  bool AnyOccupiedWithinRadius(const Index& i) const;
  /// The occupied bits of column (x, y) from height z0 to z1 (clipped to the window) in runs of
  /// consecutive addresses, each up to the end of a word or to where z wraps around the ring (in
  /// the default window, 64 voxels tall, one or two runs of the column's one word):
  /// visit(z, bits) gets a run's bits with bit k for height z + k, skipped when zero, and returns
  /// false to stop. Returns false when a visit stopped, true otherwise.
  template <typename Visit>
  bool ForEachOccupiedRun(int x, int y, int z0, int z1, Visit&& visit) const;
  /// AnyOccupiedWithinRadius of the voxel at this address, remembered until the occupied bits
  /// change: the planner's search asks for the same voxels many times (every segment out of a
  /// cell starts in it), a few dozen words each (29 columns at the stack's 0.3 m).
  bool Inflated(std::size_t address) const;
  /// A hit or a miss: the voxel is known and its log-odds move by the step (fixed point),
  /// clamped; the occupied count and bit follow a change of state.
  void Observe(std::size_t address, int log_odds_step) {
    Cell& cell = cells_[address];
    cell.known = 1;
    const bool was = Occupied(cell);
    cell.log_odds = static_cast<std::int16_t>(std::clamp(cell.log_odds + log_odds_step, min_q_, max_q_));
    SetSettledFree(address, cell.log_odds == min_q_);
    const bool now = Occupied(cell);
    if (was == now) return;
    occupied_count_ += now ? 1 : -1;
    SetBit(&occupied_, address, now);
    inflated_memo_valid_ = false;
  }
  /// One segment's walk through the window's voxels (Amanatides and Woo 1987), in fixed point:
  /// the parameters of the next boundary along each axis and their increments (2^-32 of the
  /// window-clipped segment), the current voxel as a relative index, the index's increment along
  /// each axis (+-1 in that axis' field, two's complement), and the number of steps left (known
  /// before the first, so the loop has no end test).
  struct WindowWalk {
    std::int64_t tx, ty, tz, dx, dy, dz;
    std::uint64_t relative, step_x, step_y, step_z;
    std::int64_t steps;
    /// Into the next voxel: the axis whose boundary comes first, chosen without branches (which
    /// way a ray turns next is what a branch predictor cannot guess): all-ones masks from the
    /// signs of the differences (the parameters stay below 2^35, so no difference overflows),
    /// because with ternaries or && the compiler emits the very branches this avoids. The
    /// differences run in parallel, so the chain from one step's t to the next is a subtraction,
    /// a shift, a few logic operations and an add.
    static void Advance(const WindowWalk& c, std::int64_t& tx, std::int64_t& ty, std::int64_t& tz,
                        std::uint64_t& relative) {
      const std::int64_t on_x = ~(((ty - tx) | (tz - tx)) >> 63);
      const std::int64_t on_y = ~(on_x | ((tz - ty) >> 63));
      const std::int64_t on_z = ~(on_x | on_y);
      relative += (c.step_x & static_cast<std::uint64_t>(on_x)) | (c.step_y & static_cast<std::uint64_t>(on_y)) |
                  (c.step_z & static_cast<std::uint64_t>(on_z));
      tx += c.dx & on_x;
      ty += c.dy & on_y;
      tz += c.dz & on_z;
    }
  };
  /// Starts the walk of the segment a-b (voxel units) clipped to the window, in its first voxel;
  /// false if the segment misses the window.
  bool StartWalk(const Vector3& a, const Vector3& b, WindowWalk* walk) const;
  /// The kernels of Insert's walks: every voxel each of the `count` walks crosses (its first to
  /// its last), as an address (AddressOfRelative with these residues and top bits), written from
  /// `out` on unless its bit in `settled` is set; the end of the list is returned. The order is
  /// the kernel's own. `out` must have room for all the walks' voxels plus 4 (the AVX2 kernel
  /// stores four addresses at a time). The AVX2 kernel is defined only in builds that target AVX2,
  /// where Insert alone selects it.
  static std::uint32_t* ListUnsettledPortable(const WindowWalk* walks, std::size_t count, const std::uint64_t* settled,
                                              std::uint64_t residues, std::uint64_t top_bits, std::uint32_t* out);
  static std::uint32_t* ListUnsettledAvx2(const WindowWalk* walks, std::size_t count, const std::uint64_t* settled,
                                          std::uint64_t residues, std::uint64_t top_bits, std::uint32_t* out);
  /// Visits the window's voxels that the segment a-b (voxel units) crosses, in order, as
  /// visit(address) until it returns false.
  template <typename Visit>
  void TraverseWindow(const Vector3& a, const Vector3& b, Visit&& visit) const;

  VoxelMapOptions options_;
  double res_;
  Index size_;            // voxels per axis
  Index origin_;          // global index of the window's lower corner
  int hit_q_, miss_q_, min_q_, max_q_, occupied_q_;  // the options' log-odds in fixed point
  HugePageVector<Cell> cells_;
  HugePageVector<std::uint64_t> settled_free_;  // SettledFree, a bit per address (and MarkHandled's in Insert)
  std::vector<std::uint32_t> handled_;       // the bits MarkHandled set in this frame
  /// Occupied, a bit per address: the planner's queries (IsInflated, SegmentCollides, Nearest)
  /// and OccupiedVoxels read these 512 KB instead of the 16 MB of cells.
  HugePageVector<std::uint64_t> occupied_;
  /// Inflated's memo, a bit per address: whether it is known, and its value. Cleared on the first
  /// query after a change of the occupied bits or of the window (a 512 KB fill, once a frame when
  /// queries follow a frame's updates): queries fill it (see the class' thread note).
  mutable HugePageVector<std::uint64_t> inflated_known_, inflated_;
  mutable bool inflated_memo_valid_ = false;
  std::uint32_t frame_ = 0;
  std::uint64_t frames_inserted_ = 0;  // Insert's calls, for clearing_stride's choice of rays
  /// The inflation stencil (the offsets whose voxel centres lie within the radius) as columns
  /// along z, the address' fastest axis: a column's voxels are one run of consecutive addresses
  /// (but where z wraps around the ring), so a query computes an (x, y) base and a window test
  /// once per column and reads its occupied bits a word at a time.
  struct StencilColumn {
    int dx, dy, z_lo, z_hi;  // offsets (dx, dy, z) for z in [z_lo, z_hi]
  };
  std::vector<StencilColumn> stencil_columns_;
  /// Columns (dx, dy) within kSortedOffsetRadius voxels, by increasing distance in the plane:
  /// Nearest reads them in order and stops early (the planner asks it for every penalty sample
  /// and every check along a result).
  static constexpr int kSortedOffsetRadius = 12;
  struct SortedColumn {
    int dx, dy;
    double distance;  // [voxels]
  };
  std::vector<SortedColumn> sorted_columns_;
  int hysteresis_voxels_ = 0;             // recenter_hysteresis_m in whole voxels
  /// A frame's returns' addresses, in order; the two codes above any address (a window holds at
  /// most 2^29 voxels: 64 million, each axis rounded up to a power of two) mark a non-finite return and one outside the window.
  std::vector<std::uint32_t> return_addresses_;
  static constexpr std::uint32_t kReturnOutsideWindow = 0xFFFFFFFEU, kNonFiniteReturn = 0xFFFFFFFFU;
  std::vector<Vector3> ray_ends_;  // the returns whose rays a frame walks
  std::vector<WindowWalk> walks_;  // a batch of those rays' walks, started
  std::vector<std::uint32_t> addresses_;  // the voxels a batch of rays leaves to update
  int shift_x_ = 0, shift_y_ = 0;     // the address fields' offsets: log2 of size y * size z, of size z
  std::uint64_t field_top_bits_ = 0;  // each address field's top bit
  std::uint64_t origin_residues_ = 0;  // the address of the window's lower corner
  int occupied_count_ = 0;
};

}  // namespace rotorguard::perception
