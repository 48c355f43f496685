#include "rotorguard/perception/voxel_map.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::perception {

namespace {

using internal::PositiveMod;

}  // namespace

void VoxelMapOptions::Validate() const {
  CheckDeclaredRanges("VoxelMapOptions", *this);
  // The rules between keys.
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowValidation("VoxelMapOptions", field, v, rule);
  };
  for (int k = 0; k < 3; ++k) {
    require(std::isfinite(window_size_m[k]) && window_size_m[k] > resolution_m &&
                window_size_m[k] / resolution_m <= 4096.0,
            "window_size_m", window_size_m[k], "extents above resolution_m, at most 4096 voxels each");
  }
  require(occupied_threshold > 0.0 && occupied_threshold < log_odds_max, "occupied_threshold", occupied_threshold,
          "a log-odds in (0, log_odds_max)");
  require(std::isfinite(inflation_radius_m) && inflation_radius_m >= 0.0 && inflation_radius_m <= 100.0 * resolution_m,
          "inflation_radius_m", inflation_radius_m, "a radius in [0, 100 voxels]");
  require(recenter_hysteresis_m <= 0.25 * window_size_m.minCoeff(), "recenter_hysteresis_m", recenter_hysteresis_m,
          "a distance in [0, a quarter of the smallest window extent] m");
  const double voxels = (window_size_m / resolution_m).prod();
  require(voxels <= 64e6, "window_size_m", voxels, "at most 64 million voxels");
}

VoxelMap::VoxelMap(const VoxelMapOptions& options) : options_(options) {
  options_.Validate();
  res_ = options_.resolution_m;
  // Voxels per axis: the requested extent rounded up to a power of two (at least 8), so that the
  // ring buffer's index arithmetic is a mask rather than a division (the hottest path).
  for (int k = 0; k < 3; ++k) {
    const auto needed = static_cast<unsigned>(std::ceil(options_.window_size_m[k] / res_));
    size_[k] = static_cast<int>(std::bit_ceil(std::max(needed, 8U)));
  }
  shift_y_ = std::countr_zero(static_cast<unsigned>(size_.z()));  // log2 of a power of two
  shift_x_ = shift_y_ + std::countr_zero(static_cast<unsigned>(size_.y()));
  field_top_bits_ = (static_cast<std::uint64_t>(size_.x() / 2) << shift_x_) |
                    (static_cast<std::uint64_t>(size_.y() / 2) << shift_y_) | static_cast<std::uint64_t>(size_.z() / 2);
  SetOrigin(-size_ / 2);
  hysteresis_voxels_ = static_cast<int>(std::floor(options_.recenter_hysteresis_m / res_ + 1e-9));
  const std::size_t n = static_cast<std::size_t>(size_.x()) * size_.y() * size_.z();
  const auto fixed = [](double v) { return static_cast<int>(std::lround(v * kLogOddsScale)); };
  hit_q_ = fixed(options_.log_odds_hit);
  miss_q_ = fixed(options_.log_odds_miss);
  min_q_ = fixed(options_.log_odds_min);
  max_q_ = fixed(options_.log_odds_max);
  occupied_q_ = fixed(options_.occupied_threshold);
  cells_.assign(n, Cell{});
  settled_free_.assign(n / 64, 0);  // n is a multiple of 512 (at least 8 voxels per axis)
  occupied_.assign(n / 64, 0);
  inflated_known_.assign(n / 64, 0);
  inflated_.assign(n / 64, 0);
  // Offsets whose voxel centres lie within the radius of the centre voxel's.
  const int r = static_cast<int>(std::ceil(options_.inflation_radius_m / res_));
  const double r2 = std::pow(options_.inflation_radius_m / res_ + 1e-9, 2);
  std::vector<Index> stencil;
  for (int x = -r; x <= r; ++x) {
    for (int y = -r; y <= r; ++y) {
      for (int z = -r; z <= r; ++z) {
        if (x * x + y * y + z * z <= r2) stencil.emplace_back(x, y, z);
      }
    }
  }
  // Each (x, y) of the stencil holds a symmetric run of z (the ball's section), in order.
  for (const Index& o : stencil) {
    if (stencil_columns_.empty() || stencil_columns_.back().dx != o.x() || stencil_columns_.back().dy != o.y()) {
      stencil_columns_.push_back({o.x(), o.y(), o.z(), o.z()});
    }
    stencil_columns_.back().z_hi = o.z();
  }
  const int s = kSortedOffsetRadius;
  for (int x = -s; x <= s; ++x) {
    for (int y = -s; y <= s; ++y) {
      const double d = std::sqrt(static_cast<double>(x * x + y * y));
      if (d <= s) sorted_columns_.push_back({x, y, d});
    }
  }
  std::sort(sorted_columns_.begin(), sorted_columns_.end(),
            [](const SortedColumn& a, const SortedColumn& b) { return a.distance < b.distance; });
}

VoxelMap::Index VoxelMap::ToIndex(const Vector3& p) const {
  return Index(static_cast<int>(std::floor(p.x() / res_)), static_cast<int>(std::floor(p.y() / res_)),
               static_cast<int>(std::floor(p.z() / res_)));
}

void VoxelMap::SetOrigin(const Index& origin) {
  origin_ = origin;
  origin_residues_ = Address(origin);
}

Vector3 VoxelMap::Center(const Index& i) const { return (i.cast<double>() + Vector3::Constant(0.5)) * res_; }

bool VoxelMap::InWindow(const Vector3& p) const { return p.allFinite() && InWindow(ToIndex(p)); }

bool VoxelMap::StartWalk(const Vector3& a, const Vector3& b, WindowWalk* walk) const {
  // Clip to the window [origin, origin + size) in voxel units. (Reciprocals once per axis: the
  // setup runs for every ray of a frame, and a division costs as much as a few steps.)
  const Vector3 d = b - a;
  double s_in = 0.0, s_out = 1.0, inv_d[3];
  for (int k = 0; k < 3; ++k) {
    const double lo = origin_[k], hi = origin_[k] + size_[k];
    inv_d[k] = 0.0;
    if (std::abs(d[k]) < 1e-12) {
      if (a[k] < lo || a[k] >= hi) return false;
      continue;
    }
    inv_d[k] = 1.0 / d[k];
    double s0 = (lo - a[k]) * inv_d[k], s1 = (hi - a[k]) * inv_d[k];
    if (s0 > s1) std::swap(s0, s1);
    s_in = std::max(s_in, s0);
    s_out = std::min(s_out, s1);
  }
  if (s_in > s_out) return false;
  // From here on the parameter runs over the clipped segment, so that one voxel is never more
  // than 1/4096 of it (the fixed point below then resolves every step, however long the query).
  const Vector3 start = a + s_in * d, stop = a + s_out * d, c = stop - start;
  const double inv_span = s_out > s_in ? 1.0 / (s_out - s_in) : 0.0;
  int i[3], max_steps = 1;
  double t_max[3], t_delta[3];
  std::uint64_t step[3];
  const int shift[3] = {shift_x_, shift_y_, 0};
  for (int k = 0; k < 3; ++k) {
    const int lo = origin_[k], hi = origin_[k] + size_[k] - 1;
    i[k] = std::clamp(static_cast<int>(std::floor(start[k])), lo, hi);
    max_steps += std::abs(std::clamp(static_cast<int>(std::floor(stop[k])), lo, hi) - i[k]);
    const int st = c[k] > 0.0 ? 1 : (c[k] < 0.0 ? -1 : 0);
    if (st == 0 || inv_d[k] == 0.0) {
      t_max[k] = t_delta[k] = std::numeric_limits<double>::infinity();
    } else {
      // Parameter of the next voxel boundary along k (1 / c[k] = inv_d[k] / span).
      const double inv_c = inv_d[k] * inv_span;
      const double boundary = st > 0 ? i[k] + 1.0 : static_cast<double>(i[k]);
      t_max[k] = (boundary - start[k]) * inv_c;
      t_delta[k] = std::abs(inv_c);
    }
    // -1 in the field as two's complement: no step leaves the window, so no field borrows.
    step[k] = st >= 0 ? std::uint64_t{1} << shift[k] : ~(std::uint64_t{1} << shift[k]) + 1;
  }
  // The boundary parameters in fixed point (2^-32 of the segment): integer compares have a
  // shorter latency than double, and the step's dependency chain runs through them. Beyond the
  // segment's end (> 1) only the order matters, so larger values are capped to stay in range.
  // Each of the n steps adds a truncation error below one unit, so the end is moved in by
  // max_steps + 2 units: a boundary at or beyond the clipped end (the window's face) then always
  // compares beyond it, and no step leaves the window.
  const auto fixed = [](double t) { return static_cast<std::int64_t>(std::min(t, 4.0) * 4294967296.0); };
  WindowWalk& w = *walk;
  w.tx = fixed(t_max[0]), w.ty = fixed(t_max[1]), w.tz = fixed(t_max[2]);
  w.dx = fixed(t_delta[0]), w.dy = fixed(t_delta[1]), w.dz = fixed(t_delta[2]);
  const std::int64_t t_end = fixed(1.0) - (max_steps + 2);
  // The walk takes the boundaries in increasing order (a merge of the three axes' sequences), so
  // it steps exactly once per boundary at or before the end: the count is known before the first
  // step, and the loop needs no end test of its own.
  const auto crossings = [t_end](std::int64_t t0, std::int64_t dt, double per_unit) -> std::int64_t {
    if (t0 > t_end) return 0;
    // per_unit ~ 1 / dt: the estimate is then corrected to the exact integer count.
    std::int64_t n = static_cast<std::int64_t>(static_cast<double>(t_end - t0) * per_unit) + 1;
    while (n > 0 && t0 + (n - 1) * dt > t_end) --n;
    while (t0 + n * dt <= t_end) ++n;
    return n;
  };
  constexpr double kUnit = 1.0 / 4294967296.0;
  w.steps = crossings(w.tx, w.dx, std::abs(c[0]) * kUnit) + crossings(w.ty, w.dy, std::abs(c[1]) * kUnit) +
            crossings(w.tz, w.dz, std::abs(c[2]) * kUnit);
  w.relative = RelativeIndex(Index(i[0], i[1], i[2]));
  w.step_x = step[0], w.step_y = step[1], w.step_z = step[2];
  return true;
}

template <typename Visit>
void VoxelMap::TraverseWindow(const Vector3& a, const Vector3& b, Visit&& visit) const {
  WindowWalk w;
  if (!StartWalk(a, b, &w)) return;
  for (std::int64_t n = 0;; ++n) {
    if (!visit(AddressOfRelative(w.relative)) || n == w.steps) return;
    WindowWalk::Advance(w, w.tx, w.ty, w.tz, w.relative);
  }
}

VoxelMap::Index VoxelMap::IndexOf(std::size_t address) const {
  // Unwrap: the window holds the one index with these residues.
  const auto a = static_cast<int>(address);
  const Index w(a >> shift_x_, (a >> shift_y_) & (size_.y() - 1), a & (size_.z() - 1));
  return origin_ + Index(PositiveMod(w.x() - origin_.x(), size_.x()), PositiveMod(w.y() - origin_.y(), size_.y()),
                         PositiveMod(w.z() - origin_.z(), size_.z()));
}

template <typename Visit>
bool VoxelMap::ForEachOccupiedRun(int x, int y, int z0, int z1, Visit&& visit) const {
  const int z_min = origin_.z(), z_mask = size_.z() - 1;
  const Index bottom(x, y, z_min);  // the column's (x, y) at the window's floor
  if (!InWindow(bottom)) return true;
  const std::size_t base = Address(bottom) & ~static_cast<std::size_t>(z_mask);  // its (x, y) fields
  z1 = std::min(z1, z_min + size_.z() - 1);
  for (int z = std::max(z0, z_min); z <= z1;) {
    const std::size_t address = base | static_cast<std::size_t>(z & z_mask);
    const int run = std::min({z1 - z + 1, 64 - static_cast<int>(address & 63), size_.z() - (z & z_mask)});
    const std::uint64_t mask = run == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << run) - 1;
    const std::uint64_t bits = (occupied_[address >> 6] >> (address & 63)) & mask;
    if (bits != 0 && !visit(z, bits)) return false;
    z += run;
  }
  return true;
}

bool VoxelMap::AnyOccupiedWithinRadius(const Index& i) const {
  for (const StencilColumn& c : stencil_columns_) {
    if (!ForEachOccupiedRun(i.x() + c.dx, i.y() + c.dy, i.z() + c.z_lo, i.z() + c.z_hi,
                            [](int, std::uint64_t) { return false; })) {
      return true;
    }
  }
  return false;
}

bool VoxelMap::Inflated(std::size_t address) const {
  if (!inflated_memo_valid_) {
    std::fill(inflated_known_.begin(), inflated_known_.end(), 0);
    inflated_memo_valid_ = true;
  }
  if (GetBit(inflated_known_.data(), address)) return GetBit(inflated_.data(), address);
  const bool inflated = AnyOccupiedWithinRadius(IndexOf(address));
  SetBit(&inflated_known_, address, true);
  SetBit(&inflated_, address, inflated);
  return inflated;
}

void VoxelMap::Recenter(const Vector3& center_W) {
  if (!center_W.allFinite()) return;
  const Index target = ToIndex(center_W) - size_ / 2;
  Index new_origin = origin_;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(target[k] - origin_[k]) > hysteresis_voxels_) new_origin[k] = target[k];
  }
  if (new_origin == origin_) return;
  inflated_memo_valid_ = false;  // its addresses hold other voxels now
  const Index shift = new_origin - origin_;
  if ((shift.cwiseAbs().array() >= size_.array()).any()) {  // nothing stays
    for (Cell& c : cells_) c = Cell{0, c.stamp, 0};  // the frame stamps stay valid
    std::fill(settled_free_.begin(), settled_free_.end(), 0);
    std::fill(occupied_.begin(), occupied_.end(), 0);
    occupied_count_ = 0;
    SetOrigin(new_origin);
    return;
  }
  // Voxels of the old window outside the new one: a slab along each axis that moved, each voxel
  // visited once (along the axes of earlier slabs only the part that stays is walked).
  const Index stay_lo = origin_.cwiseMax(new_origin), stay_hi = (origin_ + size_).cwiseMin(new_origin + size_);
  const auto for_each_leaving = [&](auto&& f) {
    for (int k = 0; k < 3; ++k) {
      if (shift[k] == 0) continue;
      Index lo = origin_, hi = origin_ + size_;
      for (int j = 0; j < k; ++j) {
        if (shift[j] != 0) lo[j] = stay_lo[j], hi[j] = stay_hi[j];
      }
      lo[k] = shift[k] > 0 ? origin_[k] : stay_hi[k];
      hi[k] = shift[k] > 0 ? stay_lo[k] : origin_[k] + size_[k];
      Index i;
      for (i.x() = lo.x(); i.x() < hi.x(); ++i.x()) {
        for (i.y() = lo.y(); i.y() < hi.y(); ++i.y()) {
          for (i.z() = lo.z(); i.z() < hi.z(); ++i.z()) f(i);
        }
      }
    }
  };
  // Forget them: free their slots.
  for_each_leaving([&](const Index& i) {
    const std::size_t address = Address(i);
    occupied_count_ -= Occupied(cells_[address]) ? 1 : 0;
    cells_[address] = Cell{0, cells_[address].stamp, 0};
    SetSettledFree(address, false);
    SetBit(&occupied_, address, false);
  });
  SetOrigin(new_origin);
}

MapUpdateSummary VoxelMap::Insert(const Vector3& origin_W, const std::vector<Eigen::Vector3f>& points_W) {
  MapUpdateSummary summary;
  const std::uint64_t frame_index = frames_inserted_++;  // clearing_stride counts every frame given
  if (!origin_W.allFinite()) {
    summary.points_dropped = static_cast<int>(points_W.size());
    return summary;
  }
  // Stamps: 2f marks a miss in frame f, 2f + 1 a hit (hits win over misses in the same frame).
  // One byte per voxel: frames count 1..127 and the stamps restart after that, a clear of the
  // window every 12.7 s at 10 Hz.
  if (++frame_ > 127) {
    for (Cell& c : cells_) c.stamp = 0;
    frame_ = 1;
  }
  const std::uint8_t miss = static_cast<std::uint8_t>(2 * frame_), hit = static_cast<std::uint8_t>(2 * frame_ + 1);
  // Pass 1: the returns' voxels, hit once each, and one ray per hit voxel (from the same origin
  // the other returns in it crossed nearly the same voxels; ego-planner's per-frame voxel cache
  // makes the same trade). Returns outside the window still clear the window along their rays.
  // A hit voxel is not missed in the same frame: its skip bit is set until the frame is done, so
  // that pass 2's walks do not list it (MarkHandled).
  // The returns' addresses are computed first, so that the loop that hits them can prefetch the
  // cells ahead: a return's first touch of its cell is a cache miss in a window larger than the
  // caches (a quarter of pass 1's time before). The hits still happen in the returns' order.
  std::vector<std::uint32_t>& return_addresses = return_addresses_;
  return_addresses.resize(points_W.size());
  for (std::size_t k = 0; k < points_W.size(); ++k) {
    const Vector3 p = points_W[k].cast<double>();
    std::uint32_t code = kNonFiniteReturn;
    if (p.allFinite()) {
      const Index end = ToIndex(p);
      code = InWindow(end) ? static_cast<std::uint32_t>(Address(end)) : kReturnOutsideWindow;
    }
    return_addresses[k] = code;
  }
  std::vector<Vector3>& rays = ray_ends_;
  rays.clear();
  int hits = 0;
  constexpr std::size_t kReturnPrefetchAhead = 16;
  for (std::size_t k = 0; k < points_W.size(); ++k) {
    if (k + kReturnPrefetchAhead < points_W.size() && return_addresses[k + kReturnPrefetchAhead] < kReturnOutsideWindow) {
      __builtin_prefetch(cells_.data() + return_addresses[k + kReturnPrefetchAhead], 1);
    }
    const std::uint32_t address = return_addresses[k];
    if (address == kNonFiniteReturn) {
      ++summary.points_dropped;
      continue;
    }
    if (address == kReturnOutsideWindow) {
      ++summary.points_dropped;
      rays.push_back(points_W[k].cast<double>());
      continue;
    }
    ++summary.points_used;
    if (cells_[address].stamp == hit) continue;
    cells_[address].stamp = hit;
    Observe(address, hit_q_);
    MarkHandled(address);
    ++hits;
    rays.push_back(points_W[k].cast<double>());
  }
  // Pass 2: free space along each ray the frame walks (every ray, or one in clearing_stride, a
  // different residue each frame), up to the clearing range. A voxel hit in this frame is not
  // missed; one missed already is not missed twice; a settled free one is left alone (its miss
  // would change nothing). The whole walk: stopping where another ray already passed leaves gaps
  // between converging rays, and obstacles that moved away with them (even only within 2 m of the
  // sensor, where the rays are denser than the voxels: a repeated frame then never clears 14 of a
  // moved wall's 382 voxels). The stride instead thins the rays evenly and moves its choice every
  // frame, so a voxel that rays of every residue cross is still missed every frame.
  // The walks are the cost (a forest frame takes some 800 000 steps with every ray): a batch of
  // rays is started, then walked by a kernel that lists each voxel whose settled bit is clear (see
  // ListUnsettledPortable and ListUnsettledAvx2). The voxels a batch lists are updated after,
  // each prefetched ahead, so that the memory latencies of a window larger than the caches
  // overlap. The order of the list changes nothing: a frame misses a voxel at most once, and what
  // a miss changes besides the cell (the count, the settled and occupied bits) commutes.
  // The rays this frame walks (clearing_stride): the others' returns were hit all the same.
  const auto stride = static_cast<std::size_t>(options_.clearing_stride);
  if (stride > 1) {
    std::size_t kept = 0;
    for (std::size_t i = frame_index % stride; i < rays.size(); i += stride) rays[kept++] = rays[i];
    rays.resize(kept);
  }
  summary.rays_walked = static_cast<int>(rays.size());
  const double inv_res = 1.0 / res_;
  const Vector3 o = origin_W * inv_res;
  const double max_cells = options_.max_clearing_range_m / res_;
  long steps = 0, listed_total = 0;
  int missed = 0;
  constexpr std::size_t kRaysPerBatch = 64, kPrefetchAhead = 32;
  Cell* const cells = cells_.data();
  // Room for a batch's walks (a walk crosses at most size_.sum() voxels) and the AVX2 kernel's
  // last store.
  addresses_.resize(kRaysPerBatch * static_cast<std::size_t>(size_.sum()) + 4);
#if defined(__AVX2__)
  const auto list_unsettled =
      options_.walk_kernel == VoxelMapOptions::WalkKernel::kAuto ? ListUnsettledAvx2 : ListUnsettledPortable;
#else
  const auto list_unsettled = ListUnsettledPortable;
#endif
  for (std::size_t first = 0; first < rays.size(); first += kRaysPerBatch) {
    const std::size_t last = std::min(rays.size(), first + kRaysPerBatch);
    walks_.clear();
    for (std::size_t k = first; k < last; ++k) {
      Vector3 e = rays[k] * inv_res;
      const double len = (e - o).norm();
      if (len > max_cells) e = o + (e - o) * (max_cells / len);
      WindowWalk w;
      if (!StartWalk(o, e, &w)) continue;
      steps += w.steps + 1;
      walks_.push_back(w);
    }
    const std::uint32_t* const addresses = addresses_.data();
    const std::uint32_t* const end = list_unsettled(walks_.data(), walks_.size(), settled_free_.data(),
                                                    origin_residues_, field_top_bits_, addresses_.data());
    const std::size_t listed = static_cast<std::size_t>(end - addresses);
    listed_total += static_cast<long>(listed);
    for (std::size_t k = 0; k < listed; ++k) {
      if (k + kPrefetchAhead < listed) __builtin_prefetch(cells + addresses[k + kPrefetchAhead], 1);
      const std::uint32_t address = addresses[k];
      Cell& c = cells[address];
      if (c.stamp < miss) {
        c.stamp = miss;
        Observe(address, miss_q_);
        MarkHandled(address);
        ++missed;
      }
    }
  }
  // The frame is done: the voxels it marked handled get back their settled bits (clear: the
  // settled ones were never marked).
  for (const std::uint32_t address : handled_) SetSettledFree(address, false);
  handled_.clear();
  summary.voxels_traversed = steps;
  summary.voxels_skipped = steps - listed_total;
  summary.voxels_updated = hits + missed;
  return summary;
}

std::uint32_t* VoxelMap::ListUnsettledPortable(const WindowWalk* walks, std::size_t count, const std::uint64_t* settled,
                                               std::uint64_t residues, std::uint64_t top_bits, std::uint32_t* out) {
  // Each step is a chain of dependent compares and adds, so two rays are walked side by side and
  // their chains overlap. The list is written through a local pointer: push_back would store and
  // reload the vector's end on every step.
  std::size_t next = 0;
  const auto start_next = [&](WindowWalk* w) {
    if (next < count) {
      *w = walks[next++];
    } else {
      *w = WindowWalk{};
      w->steps = -1;  // idle
    }
  };
  const auto list = [&](std::uint64_t relative) {
    out = ListUnlessSettled(AddressOfRelative(relative, residues, top_bits), settled, out);
  };
  // Each lane's changing state in locals (registers), its constants in its WindowWalk.
  WindowWalk lane0, lane1;
  start_next(&lane0);
  start_next(&lane1);
  std::int64_t tx0 = lane0.tx, ty0 = lane0.ty, tz0 = lane0.tz, n0 = lane0.steps;
  std::int64_t tx1 = lane1.tx, ty1 = lane1.ty, tz1 = lane1.tz, n1 = lane1.steps;
  std::uint64_t r0 = lane0.relative, r1 = lane1.relative;
  while (n0 >= 0 || n1 >= 0) {
    // Both lanes step until one is in its last voxel (n counts the steps left).
    const std::int64_t both = std::min(n0, n1);
    for (std::int64_t n = 0; n < both; ++n) {
      list(r0);
      list(r1);
      WindowWalk::Advance(lane0, tx0, ty0, tz0, r0);
      WindowWalk::Advance(lane1, tx1, ty1, tz1, r1);
    }
    if (both > 0) n0 -= both, n1 -= both;
    // A lane in its last voxel, or walking alone (the other idle), finishes its ray and takes the
    // next.
    const auto finish = [&](WindowWalk& lane, std::int64_t& tx, std::int64_t& ty, std::int64_t& tz, std::int64_t& n,
                            std::uint64_t& r, std::int64_t other_n) {
      if (!(n == 0 || (n > 0 && other_n < 0))) return;
      for (; n > 0; --n) list(r), WindowWalk::Advance(lane, tx, ty, tz, r);
      list(r);
      start_next(&lane);
      tx = lane.tx, ty = lane.ty, tz = lane.tz, n = lane.steps, r = lane.relative;
    };
    finish(lane0, tx0, ty0, tz0, n0, r0, n1);
    finish(lane1, tx1, ty1, tz1, n1, r1, n0);
  }
  return out;
}

#if defined(__AVX2__)
std::uint32_t* VoxelMap::ListUnsettledAvx2(const WindowWalk* walks, std::size_t count, const std::uint64_t* settled,
                                           std::uint64_t residues, std::uint64_t top_bits, std::uint32_t* out) {
  // Four rays, one per 64-bit lane of each register: a step of all four is the portable kernel's
  // step for one (Advance) in vector compares and masks, and the listing is the four addresses in
  // one vector, each lane's settled bit read with a scalar load (a vector gather measured 11-14 %
  // slower over the whole frame), and a compress of the lanes to keep (a permutation looked up by
  // their mask) stored four at a time. Between runs of steps the lanes live in arrays, where a
  // lane that finished its ray takes the next; a lane with no ray left idles (zero increments,
  // no steps counted, its listing masked off) until all do.
  constexpr std::int64_t kIdle = std::numeric_limits<std::int64_t>::max();
  alignas(32) std::int64_t tx[4], ty[4], tz[4], dx[4], dy[4], dz[4], n[4];
  alignas(32) std::uint64_t rel[4], sx[4], sy[4], sz[4];
  std::size_t next = 0;
  const auto take_next = [&](int k) {
    if (next < count) {
      const WindowWalk& w = walks[next++];
      tx[k] = w.tx, ty[k] = w.ty, tz[k] = w.tz, dx[k] = w.dx, dy[k] = w.dy, dz[k] = w.dz;
      rel[k] = w.relative, sx[k] = w.step_x, sy[k] = w.step_y, sz[k] = w.step_z;
      n[k] = w.steps;
    } else {
      tx[k] = ty[k] = tz[k] = dx[k] = dy[k] = dz[k] = 0;
      rel[k] = sx[k] = sy[k] = sz[k] = 0;  // relative 0: the lane's address stays valid
      n[k] = kIdle;
    }
  };
  for (int k = 0; k < 4; ++k) take_next(k);
  // Lane k's dword in the low half of the 64-bit lane, 2k; the 16 masks' permutations put the
  // kept lanes' dwords first, in lane order.
  alignas(32) static constexpr std::array<std::array<std::int32_t, 8>, 16> kCompress = [] {
    std::array<std::array<std::int32_t, 8>, 16> table{};
    for (int mask = 0; mask < 16; ++mask) {
      int j = 0;
      for (int k = 0; k < 4; ++k) {
        if (mask & (1 << k)) table[mask][j++] = 2 * k;
      }
    }
    return table;
  }();
  const auto load = [](const void* p) { return _mm256_load_si256(static_cast<const __m256i*>(p)); };
  const __m256i low_fields = _mm256_set1_epi64x(static_cast<long long>(~top_bits));
  const __m256i top = _mm256_set1_epi64x(static_cast<long long>(top_bits));
  const __m256i residues_v = _mm256_set1_epi64x(static_cast<long long>(residues));
  const __m256i residues_low = _mm256_and_si256(residues_v, low_fields);
  for (;;) {
    const std::int64_t both = std::min(std::min(n[0], n[1]), std::min(n[2], n[3]));
    if (both == kIdle) break;
    __m256i vtx = load(tx), vty = load(ty), vtz = load(tz), vrel = load(rel);
    const __m256i vdx = load(dx), vdy = load(dy), vdz = load(dz), vsx = load(sx), vsy = load(sy), vsz = load(sz);
    int active_mask = 0;
    for (int k = 0; k < 4; ++k) active_mask |= static_cast<int>(n[k] != kIdle) << k;
    for (std::int64_t i = 0; i < both; ++i) {
      // List: AddressOfRelative, the settled bit, the compress.
      const __m256i address = _mm256_xor_si256(_mm256_add_epi64(_mm256_and_si256(vrel, low_fields), residues_low),
                                               _mm256_and_si256(_mm256_xor_si256(vrel, residues_v), top));
      alignas(32) std::uint64_t a[4];
      _mm256_store_si256(reinterpret_cast<__m256i*>(a), address);
      int mask = active_mask;
      for (int k = 0; k < 4; ++k) mask &= ~(static_cast<int>(SettledFree(settled, a[k])) << k);
      const __m256i packed = _mm256_permutevar8x32_epi32(address, load(kCompress[mask].data()));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm256_castsi256_si128(packed));
      out += std::popcount(static_cast<unsigned>(mask));
      // Advance: on_x where tx <= ty and tx <= tz, on_y where not on_x and ty <= tz, else on_z
      // (the portable kernel's choice, ties included).
      const __m256i not_x = _mm256_or_si256(_mm256_cmpgt_epi64(vtx, vty), _mm256_cmpgt_epi64(vtx, vtz));
      const __m256i y_after_z = _mm256_cmpgt_epi64(vty, vtz);
      const __m256i on_y = _mm256_andnot_si256(y_after_z, not_x), on_z = _mm256_and_si256(y_after_z, not_x);
      vrel = _mm256_add_epi64(
          vrel, _mm256_or_si256(_mm256_andnot_si256(not_x, vsx),
                                _mm256_or_si256(_mm256_and_si256(on_y, vsy), _mm256_and_si256(on_z, vsz))));
      vtx = _mm256_add_epi64(vtx, _mm256_andnot_si256(not_x, vdx));
      vty = _mm256_add_epi64(vty, _mm256_and_si256(on_y, vdy));
      vtz = _mm256_add_epi64(vtz, _mm256_and_si256(on_z, vdz));
    }
    _mm256_store_si256(reinterpret_cast<__m256i*>(tx), vtx);
    _mm256_store_si256(reinterpret_cast<__m256i*>(ty), vty);
    _mm256_store_si256(reinterpret_cast<__m256i*>(tz), vtz);
    _mm256_store_si256(reinterpret_cast<__m256i*>(rel), vrel);
    // Lanes in their last voxel list it and take the next ray.
    for (int k = 0; k < 4; ++k) {
      if (n[k] == kIdle) continue;
      n[k] -= both;
      if (n[k] != 0) continue;
      out = ListUnlessSettled(AddressOfRelative(rel[k], residues, top_bits), settled, out);
      take_next(k);
    }
  }
  return out;
}
#endif

void VoxelMap::MarkOccupied(const Vector3& p) {
  if (!InWindow(p)) return;
  const std::size_t address = Address(ToIndex(p));
  Observe(address, max_q_ - min_q_);  // from anywhere to the upper clamp
}

bool VoxelMap::IsOccupied(const Vector3& p) const {
  if (!InWindow(p)) return false;
  return Occupied(cells_[Address(ToIndex(p))]);
}

bool VoxelMap::IsKnown(const Vector3& p) const { return InWindow(p) && cells_[Address(ToIndex(p))].known != 0; }

bool VoxelMap::IsInflated(const Vector3& p) const { return InWindow(p) && Inflated(Address(ToIndex(p))); }

std::optional<NearestObstacle> VoxelMap::Nearest(const Vector3& p, double radius_m) const {
  if (!p.allFinite() || !(radius_m >= 0.0)) return std::nullopt;
  const Index c = ToIndex(p);
  std::optional<NearestObstacle> best;
  Index best_index;
  // Voxel i at distance d: nearer than the best, or as near and of lower index.
  const auto consider = [&](const Index& i, const Vector3& q, double d) {
    if (d > radius_m) return;
    if (best && (d > best->distance_m ||
                 (d == best->distance_m && !std::lexicographical_compare(i.data(), i.data() + 3, best_index.data(),
                                                                          best_index.data() + 3)))) {
      return;
    }
    const Vector3 n = d > 1e-12 ? Vector3((p - q) / d) : Vector3::UnitZ();
    best = NearestObstacle{q, d, n};
    best_index = i;
  };
  if (radius_m <= FastNearestRadiusM(res_)) {
    // The query lies within half a voxel's diagonal in the plane of its voxel's centre there, so
    // a column whose centre is d from that centre holds no voxel nearer than d - that: the columns,
    // visited by increasing d, can stop once the bound exceeds the radius or the best distance.
    const double planar_half_diagonal = 0.5 * std::numbers::sqrt2 * res_;
    for (const SortedColumn& col : sorted_columns_) {
      const double bound = best ? best->distance_m : radius_m;
      const double planar = col.distance * res_ - planar_half_diagonal;
      if (planar > bound) break;
      // Heights whose centres lie within the bound of p's (a voxel more each way: the candidates
      // are measured exactly).
      const double in_plane = std::max(planar, 0.0);
      const double dz = std::sqrt(std::max(bound * bound - in_plane * in_plane, 0.0));
      const int x = c.x() + col.dx, y = c.y() + col.dy;
      const int z0 = static_cast<int>(std::floor((p.z() - dz) / res_)) - 1;
      const int z1 = static_cast<int>(std::floor((p.z() + dz) / res_)) + 1;
      ForEachOccupiedRun(x, y, z0, z1, [&](int z, std::uint64_t bits) {
        for (; bits != 0; bits &= bits - 1) {
          const Index i(x, y, z + std::countr_zero(bits));
          const Vector3 q = Center(i);
          consider(i, q, (p - q).norm());
        }
        return true;
      });
    }
    return best;
  }
  const int r = static_cast<int>(std::ceil(radius_m / res_)) + 1;
  for (int x = -r; x <= r; ++x) {
    for (int y = -r; y <= r; ++y) {
      for (int z = -r; z <= r; ++z) {
        const Index i = c + Index(x, y, z);
        if (!InWindow(i) || !OccupiedBit(Address(i))) continue;
        const Vector3 q = Center(i);
        consider(i, q, (p - q).norm());
      }
    }
  }
  return best;
}

bool VoxelMap::SegmentCollides(const Vector3& a, const Vector3& b) const {
  if (!a.allFinite() || !b.allFinite()) return true;  // a corrupt query is never declared safe
  bool collides = false;
  TraverseWindow(a / res_, b / res_, [&](std::uint32_t address) {
    if (Inflated(address)) {
      collides = true;
      return false;
    }
    return true;
  });
  return collides;
}

std::vector<Vector3> VoxelMap::OccupiedVoxels() const {
  // The occupied bits in memory order, 64 addresses a word (most words are zero), unwrapping only
  // the occupied addresses.
  std::vector<Vector3> out;
  out.reserve(static_cast<std::size_t>(occupied_count_));
  for (std::size_t w = 0; w < occupied_.size(); ++w) {
    for (std::uint64_t bits = occupied_[w]; bits != 0; bits &= bits - 1) {
      out.push_back(Center(IndexOf(64 * w + static_cast<std::size_t>(std::countr_zero(bits)))));
    }
  }
  return out;
}

}  // namespace rotorguard::perception
