#include "rotorguard/sim/raycast.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include "rotorguard/core/error.h"

namespace rotorguard::sim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Rotation of a world vector into a box frame yawed by `yaw` (and back with -yaw).
Vector3 RotateZ(const Vector3& v, double c, double s) { return Vector3(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()); }

/// Keeps the nearer of two hits.
void Nearer(const std::optional<RayHit>& candidate, std::optional<RayHit>* best) {
  if (candidate && (!*best || candidate->distance_m < (*best)->distance_m)) *best = candidate;
}

/// a * b + c, in one rounding where the build has FMA: the scalar test and the AVX2 kernel below
/// then compute every cylinder's distance to the same bit.
inline double MulAdd(double a, double b, double c) {
#if defined(__FMA__)
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

/// A ray as the cylinder tests take it, with |d_xy|^2 computed once. The reciprocals the tests
/// multiply by (of 2|d_xy|^2 and of d_z) stay in the tests: computed up front for every ray they
/// cost 3 % more in lidar_benchmark's CastForestRays, as many rays test no trunk at all.
struct CylinderRay {
  CylinderRay(const Vector3& origin, const Vector3& direction)
      : o(origin), d(direction), a(MulAdd(d.y(), d.y(), d.x() * d.x())) {}
  const Vector3 &o, &d;
  double a;
};

/// The distance at which a ray meets one vertical cylinder (centre (cx, cy), squared radius r2,
/// height `top`), or infinity: the side, entered from outside the circle, and the top cap, from
/// above; nothing for a ray starting inside the trunk. The AVX2 kernel (NearestInQuadAvx2) is
/// this, four cylinders at a time, operation for operation.
struct CylinderHit {
  double distance_m = kInf;
  bool top = false;  ///< on the cap rather than the side
};
inline CylinderHit HitCylinder(double cx, double cy, double r2, double top, const CylinderRay& ray, double max_m) {
  const Vector3 &o = ray.o, &d = ray.d;
  CylinderHit hit;
  const double ox = o.x() - cx, oy = o.y() - cy;
  const double oo = MulAdd(oy, oy, ox * ox);
  const bool inside_circle = oo < r2;
  if (inside_circle && o.z() >= 0.0 && o.z() <= top) return hit;  // inside the trunk
  // Side: |o2 + t d2|^2 = r^2, the smaller root.
  if (ray.a > 1e-15 && !inside_circle) {
    const double b = 2.0 * MulAdd(oy, d.y(), ox * d.x());
    const double disc = MulAdd(b, b, -((4.0 * ray.a) * (oo - r2)));
    if (disc >= 0.0) {
      const double t = (-b - std::sqrt(disc)) * (0.5 / ray.a);
      const double z = MulAdd(t, d.z(), o.z());
      if (t > 0.0 && t <= max_m && z >= 0.0 && z <= top) hit.distance_m = t;
    }
  }
  // Top cap, from above.
  if (o.z() > top && d.z() < 0.0) {
    const double t = (top - o.z()) * (1.0 / d.z());
    const double px = MulAdd(t, d.x(), ox), py = MulAdd(t, d.y(), oy);
    if (t <= max_m && MulAdd(py, py, px * px) <= r2 && t < hit.distance_m) hit = CylinderHit{t, true};
  }
  return hit;
}

/// The hit of `h` on `cyl` with its outward normal.
inline RayHit HitOf(const Cylinder& cyl, const Vector3& o, const Vector3& d, const CylinderHit& h) {
  if (h.top) return RayHit{h.distance_m, Vector3::UnitZ()};
  const Eigen::Vector2d n2 = (o.head<2>() - cyl.center_m + h.distance_m * d.head<2>()) / cyl.radius_m;
  return RayHit{h.distance_m, Vector3(n2.x(), n2.y(), 0.0)};
}

/// The nearest trunk hit so far of a ray that may already have hit something else at `range`
/// (`have`), updated trunk by trunk in the bin's order.
struct NearestTrunk {
  NearestTrunk(double range_m, bool have_hit) : range(range_m), have(have_hit) {}
  double range;
  bool have;
  int cylinder = -1;  ///< none nearer than the ray's earlier hit yet
  CylinderHit hit;
  /// Keeps `h` on cylinder `id` if it is nearer; of equal distances the first, as Nearer does,
  /// and a hit at exactly the range only when the ray has none.
  void Offer(const CylinderHit& h, int id) {
    if (!(h.distance_m < range || (!have && h.distance_m < kInf))) return;
    range = h.distance_m;
    have = true;
    cylinder = id;
    hit = h;
  }
};

#if defined(__AVX2__) && defined(__FMA__)
/// The first of the four cylinders nearest along the ray, its lane (-1: none) and hit, testing
/// only those within `limit` of horizontal travel (counted in `tested`, padding not); for
/// CastCylinders.
inline int NearestInQuadAvx2(const internal::CylinderQuad& q, const CylinderRay& ray, double range, double limit,
                             CylinderHit* hit, long* tested) {
  // HitCylinder on the four lanes, operation for operation (the same roundings), misses as +inf.
  const Vector3 &o = ray.o, &d = ray.d;
  const __m256d inf = _mm256_set1_pd(kInf), zero = _mm256_setzero_pd();
  const __m256d cx = _mm256_load_pd(q.cx), cy = _mm256_load_pd(q.cy), r2 = _mm256_load_pd(q.r2);
  const __m256d top = _mm256_load_pd(q.top);
  const __m256d dx = _mm256_set1_pd(d.x()), dy = _mm256_set1_pd(d.y()), dz = _mm256_set1_pd(d.z());
  const __m256d oz = _mm256_set1_pd(o.z()), vrange = _mm256_set1_pd(range);
  const __m256d ox = _mm256_sub_pd(_mm256_set1_pd(o.x()), cx), oy = _mm256_sub_pd(_mm256_set1_pd(o.y()), cy);
  const __m256d oo = _mm256_fmadd_pd(oy, oy, _mm256_mul_pd(ox, ox));
  const __m256d inside_circle = _mm256_cmp_pd(oo, r2, _CMP_LT_OQ);
  __m256d dist = inf;
  if (ray.a > 1e-15) {
    const __m256d b = _mm256_mul_pd(_mm256_set1_pd(2.0), _mm256_fmadd_pd(oy, dy, _mm256_mul_pd(ox, dx)));
    const __m256d disc = _mm256_fmsub_pd(b, b, _mm256_mul_pd(_mm256_set1_pd(4.0 * ray.a), _mm256_sub_pd(oo, r2)));
    const __m256d neg_b = _mm256_xor_pd(b, _mm256_set1_pd(-0.0));
    const __m256d t = _mm256_mul_pd(_mm256_sub_pd(neg_b, _mm256_sqrt_pd(disc)), _mm256_set1_pd(0.5 / ray.a));
    const __m256d z = _mm256_fmadd_pd(t, dz, oz);
    __m256d ok = _mm256_andnot_pd(inside_circle, _mm256_cmp_pd(disc, zero, _CMP_GE_OQ));
    ok = _mm256_and_pd(ok, _mm256_cmp_pd(t, zero, _CMP_GT_OQ));
    ok = _mm256_and_pd(ok, _mm256_cmp_pd(t, vrange, _CMP_LE_OQ));
    ok = _mm256_and_pd(ok, _mm256_cmp_pd(z, zero, _CMP_GE_OQ));
    ok = _mm256_and_pd(ok, _mm256_cmp_pd(z, top, _CMP_LE_OQ));
    dist = _mm256_blendv_pd(inf, t, ok);
  }
  __m256d on_top = zero;
  if (d.z() < 0.0) {
    const __m256d t = _mm256_mul_pd(_mm256_sub_pd(top, oz), _mm256_set1_pd(1.0 / d.z()));
    const __m256d px = _mm256_fmadd_pd(t, dx, ox), py = _mm256_fmadd_pd(t, dy, oy);
    on_top = _mm256_cmp_pd(oz, top, _CMP_GT_OQ);
    on_top = _mm256_and_pd(on_top, _mm256_cmp_pd(t, vrange, _CMP_LE_OQ));
    on_top = _mm256_and_pd(on_top, _mm256_cmp_pd(_mm256_fmadd_pd(py, py, _mm256_mul_pd(px, px)), r2, _CMP_LE_OQ));
    on_top = _mm256_and_pd(on_top, _mm256_cmp_pd(t, dist, _CMP_LT_OQ));
    dist = _mm256_blendv_pd(dist, t, on_top);
  }
  // HitCylinder's early return for an origin inside the trunk needs no lane here: inside the
  // circle rules out the side, and at or below the top the cap. Lanes beyond the ray's reach
  // (padding included) are dropped.
  const __m256d beyond = _mm256_cmp_pd(_mm256_load_pd(q.reach_m), _mm256_set1_pd(limit), _CMP_GT_OQ);
  *tested += std::popcount(
      static_cast<unsigned>(_mm256_movemask_pd(_mm256_andnot_pd(beyond, _mm256_cmp_pd(r2, r2, _CMP_ORD_Q)))));
  dist = _mm256_blendv_pd(dist, inf, beyond);
  // The first lane of the smallest distance, as the scalar loop keeps it.
  __m256d m = _mm256_min_pd(dist, _mm256_permute_pd(dist, 0b0101));
  m = _mm256_min_pd(m, _mm256_permute2f128_pd(m, m, 1));
  const double nearest = _mm256_cvtsd_f64(m);
  if (!(nearest < hit->distance_m)) return -1;
  const int lane = __builtin_ctz(static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(dist, m, _CMP_EQ_OQ))));
  *hit = CylinderHit{nearest, ((_mm256_movemask_pd(on_top) >> lane) & 1) != 0};
  return lane;
}
#endif

}  // namespace

std::optional<RayHit> IntersectGround(const Vector3& o, const Vector3& d, double max_m) {
  if (!(o.z() > 0.0) || !(d.z() < 0.0)) return std::nullopt;
  const double t = -o.z() / d.z();
  if (t > max_m) return std::nullopt;
  return RayHit{t, Vector3::UnitZ()};
}

std::optional<RayHit> IntersectBox(const Box& box, const Vector3& o, const Vector3& d, double max_m) {
  // Slab test in the box frame.
  const double c = std::cos(box.yaw_rad), s = std::sin(box.yaw_rad);
  const Vector3 lo = RotateZ(o - box.center_m, c, -s);
  const Vector3 ld = RotateZ(d, c, -s);
  const Vector3 h = 0.5 * box.size_m;
  double t_near = -kInf, t_far = kInf;
  int axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(ld[i]) < 1e-15) {
      if (std::abs(lo[i]) > h[i]) return std::nullopt;  // parallel to this slab and outside it
      continue;
    }
    double t1 = (-h[i] - lo[i]) / ld[i], t2 = (h[i] - lo[i]) / ld[i];
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > t_near) {
      t_near = t1;
      axis = i;
    }
    t_far = std::min(t_far, t2);
  }
  // Missed, behind, starting inside (t_near <= 0), or beyond the range.
  if (axis < 0 || t_near > t_far || !(t_near > 0.0) || t_near > max_m) return std::nullopt;
  Vector3 n = Vector3::Zero();
  n[axis] = ld[axis] > 0.0 ? -1.0 : 1.0;
  return RayHit{t_near, RotateZ(n, c, s)};
}

std::optional<RayHit> IntersectCylinder(const Cylinder& cyl, const Vector3& o, const Vector3& d, double max_m) {
  const double r2 = cyl.radius_m * cyl.radius_m;
  const CylinderHit h = HitCylinder(cyl.center_m.x(), cyl.center_m.y(), r2, cyl.height_m, CylinderRay(o, d), max_m);
  if (!(h.distance_m < kInf)) return std::nullopt;
  return HitOf(cyl, o, d, h);
}

void RayCasterOptions::Validate() const {
  if (!(cell_size_m > 0.0) || !std::isfinite(cell_size_m)) {
    ThrowValidation("RayCasterOptions", "cell_size_m", cell_size_m, "a cell edge > 0 m");
  }
  if (azimuth_bins < 8 || azimuth_bins > 65536) {
    ThrowValidation("RayCasterOptions", "azimuth_bins", azimuth_bins, "a count in [8, 65536]");
  }
  if (!(azimuth_margin_m > 0.0) || !std::isfinite(azimuth_margin_m)) {
    ThrowValidation("RayCasterOptions", "azimuth_margin_m", azimuth_margin_m, "a distance > 0 m");
  }
}

RayCaster::RayCaster(World world, const RayCasterOptions& options) : world_(std::move(world)) {
  options.Validate();
  // Rays are cast in the ground's frame (the ground at z = 0, where the kernels put it): the world
  // lifted by the ground's depth, each ray's origin with it.
  lift_m_ = -world_.ground_z_m;
  if (!std::isfinite(lift_m_)) ThrowInvalidArgument("RayCaster", "world.ground_z_m", world_.ground_z_m, "a finite height");
  for (Cylinder& cy : world_.cylinders) cy.height_m += lift_m_;
  for (Box& b : world_.boxes) b.center_m.z() += lift_m_;
  for (MovingBox& m : world_.moving_boxes) {
    for (Vector3& w : m.waypoints_m) w.z() += lift_m_;
  }
  world_.ground_z_m = 0.0;
  cell_ = options.cell_size_m;
#if defined(__AVX2__) && defined(__FMA__)
  vector_kernel_ = options.cylinder_kernel == RayCasterOptions::CylinderKernel::kAuto;
#endif
  bins_ = options.azimuth_bins;
  margin_ = options.azimuth_margin_m;
  for (const Cylinder& cy : world_.cylinders) cylinder_top_ = std::max(cylinder_top_, cy.height_m);
  // Horizontal bounding boxes of the boxes.
  const int n_boxes = static_cast<int>(world_.boxes.size());
  std::vector<Eigen::Vector4d> bounds;  // min x, min y, max x, max y
  bounds.reserve(static_cast<std::size_t>(n_boxes));
  for (const Box& b : world_.boxes) {
    const double c = std::abs(std::cos(b.yaw_rad)), s = std::abs(std::sin(b.yaw_rad));
    const double ex = 0.5 * (c * b.size_m.x() + s * b.size_m.y()), ey = 0.5 * (s * b.size_m.x() + c * b.size_m.y());
    bounds.emplace_back(b.center_m.x() - ex, b.center_m.y() - ey, b.center_m.x() + ex, b.center_m.y() + ey);
    box_top_ = std::max(box_top_, b.center_m.z() + 0.5 * b.size_m.z());
  }
  last_ray_.assign(static_cast<std::size_t>(n_boxes), 0);
  if (n_boxes == 0) return;
  Eigen::Vector2d lo(kInf, kInf), hi(-kInf, -kInf);
  for (const Eigen::Vector4d& b : bounds) {
    lo = lo.cwiseMin(b.head<2>());
    hi = hi.cwiseMax(b.tail<2>());
  }
  // At most 2048 cells per side: a huge world gets larger cells rather than a huge grid.
  cell_ = std::max(cell_, (hi - lo).maxCoeff() / 2048.0);
  min_ = lo;
  nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell_)));
  ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell_)));
  const auto cell_range = [&](const Eigen::Vector4d& b, int* x0, int* y0, int* x1, int* y1) {
    *x0 = std::clamp(static_cast<int>(std::floor((b[0] - min_.x()) / cell_)), 0, nx_ - 1);
    *y0 = std::clamp(static_cast<int>(std::floor((b[1] - min_.y()) / cell_)), 0, ny_ - 1);
    *x1 = std::clamp(static_cast<int>(std::floor((b[2] - min_.x()) / cell_)), 0, nx_ - 1);
    *y1 = std::clamp(static_cast<int>(std::floor((b[3] - min_.y()) / cell_)), 0, ny_ - 1);
  };
  // Compressed rows: count, prefix-sum, fill.
  cell_start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
  int x0, y0, x1, y1;
  for (const Eigen::Vector4d& b : bounds) {
    cell_range(b, &x0, &y0, &x1, &y1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) ++cell_start_[static_cast<std::size_t>(y) * nx_ + x + 1];
    }
  }
  for (std::size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
  items_.resize(static_cast<std::size_t>(cell_start_.back()));
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (int i = 0; i < n_boxes; ++i) {
    cell_range(bounds[static_cast<std::size_t>(i)], &x0, &y0, &x1, &y1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) items_[static_cast<std::size_t>(fill[static_cast<std::size_t>(y) * nx_ + x]++)] = i;
    }
  }
}

int RayCaster::AzimuthBin(double x, double y) const {
  // A pseudo-angle in [0, 4) increasing with the azimuth like atan2 (a quarter turn per unit), for
  // two divisions' cost: y / (|x| + |y|) turned into each quadrant.
  double p;
  if (y >= 0.0) {
    p = x >= 0.0 ? y / (x + y) : 1.0 - x / (y - x);
  } else {
    p = x < 0.0 ? 2.0 - y / (-x - y) : 3.0 + x / (x - y);
  }
  return std::min(bins_ - 1, static_cast<int>(p * (0.25 * bins_)));
}

void RayCaster::IndexCylindersAround(const Eigen::Vector2d& center) {
  // A ray from o, |o - center| <= margin, that meets the disc (x, r) runs parallel to the ray from
  // center at most `margin` beside it, so that ray meets the disc (x, r + margin): its azimuth is
  // within asin((r + margin) / |x - center|) of the direction to x. And it travels at least
  // |x - center| - r - margin horizontally before it can reach the trunk.
  ++rebuilds_;
  indexed_ = true;
  index_center_ = center;
  const int n = static_cast<int>(world_.cylinders.size());
  reach_.resize(static_cast<std::size_t>(n));
  first_bin_.resize(static_cast<std::size_t>(n));
  bin_count_.resize(static_cast<std::size_t>(n));
  bin_start_.assign(static_cast<std::size_t>(bins_) + 1, 0);
  for (int i = 0; i < n; ++i) {
    const Cylinder& cy = world_.cylinders[static_cast<std::size_t>(i)];
    const Eigen::Vector2d v = cy.center_m - center;
    const double dist = v.norm(), padded = cy.radius_m + margin_;
    reach_[static_cast<std::size_t>(i)] = std::max(0.0, dist - padded);
    int first = 0, count = bins_;
    if (dist > padded) {
      // The tangent directions, u rotated by -+alpha with sin(alpha) = padded / dist; a bin more
      // on each side for the rounding of the endpoints.
      const double s = padded / dist, c = std::sqrt(1.0 - s * s);
      const Eigen::Vector2d u = v / dist;
      const int lo = AzimuthBin(c * u.x() + s * u.y(), c * u.y() - s * u.x());
      const int hi = AzimuthBin(c * u.x() - s * u.y(), c * u.y() + s * u.x());
      first = (lo - 1 + bins_) % bins_;
      count = std::min(bins_, (hi - lo + bins_) % bins_ + 3);  // alpha < pi/2: under half a turn
    }
    first_bin_[static_cast<std::size_t>(i)] = first;
    bin_count_[static_cast<std::size_t>(i)] = count;
    for (int k = 0; k < count; ++k) ++bin_start_[static_cast<std::size_t>((first + k) % bins_) + 1];
  }
  for (std::size_t b = 1; b < bin_start_.size(); ++b) bin_start_[b] += bin_start_[b - 1];
  bin_items_.resize(static_cast<std::size_t>(bin_start_.back()));
  // Filled nearest first, so each bin's entries come sorted by reach.
  order_.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order_[static_cast<std::size_t>(i)] = i;
  std::sort(order_.begin(), order_.end(),
            [&](int a, int b) { return reach_[static_cast<std::size_t>(a)] < reach_[static_cast<std::size_t>(b)]; });
  fill_.assign(bin_start_.begin(), bin_start_.end() - 1);
  for (const int i : order_) {
    const std::size_t ii = static_cast<std::size_t>(i);
    for (int k = 0; k < bin_count_[ii]; ++k) {
      const std::size_t b = static_cast<std::size_t>((first_bin_[ii] + k) % bins_);
      bin_items_[static_cast<std::size_t>(fill_[b]++)] = AzimuthEntry{reach_[ii], i};
    }
  }
  // For the AVX2 kernel, the same entries four to a quad, the last quad of a bin padded with
  // entries that never hit.
  if (!vector_kernel_) return;
  quad_start_.resize(static_cast<std::size_t>(bins_) + 1);
  quad_start_[0] = 0;
  for (int b = 0; b < bins_; ++b) {
    const int entries = bin_start_[static_cast<std::size_t>(b) + 1] - bin_start_[static_cast<std::size_t>(b)];
    quad_start_[static_cast<std::size_t>(b) + 1] = quad_start_[static_cast<std::size_t>(b)] + (entries + 3) / 4;
  }
  quads_.resize(static_cast<std::size_t>(quad_start_.back()));
  for (int b = 0; b < bins_; ++b) {
    const int first = bin_start_[static_cast<std::size_t>(b)],
              entries = bin_start_[static_cast<std::size_t>(b) + 1] - first;
    for (int k = 0; k < 4 * ((entries + 3) / 4); ++k) {
      internal::CylinderQuad& q = quads_[static_cast<std::size_t>(quad_start_[static_cast<std::size_t>(b)] + k / 4)];
      const int lane = k % 4;
      if (k >= entries) {  // a lane no ray can hit, whatever its reach limit (NaN fails every test)
        q.reach_m[lane] = kInf;
        q.cx[lane] = q.cy[lane] = q.top[lane] = 0.0;
        q.r2[lane] = std::numeric_limits<double>::quiet_NaN();
        q.id[lane] = -1;
        continue;
      }
      const AzimuthEntry& e = bin_items_[static_cast<std::size_t>(first + k)];
      const Cylinder& cy = world_.cylinders[static_cast<std::size_t>(e.cylinder)];
      q.reach_m[lane] = e.reach_m;
      q.cx[lane] = cy.center_m.x();
      q.cy[lane] = cy.center_m.y();
      q.r2[lane] = cy.radius_m * cy.radius_m;
      q.top[lane] = cy.height_m;
      q.id[lane] = e.cylinder;
    }
  }
}

void RayCaster::CastCylinders(const Vector3& o, const Vector3& d, double max_m, std::optional<RayHit>* best) {
  const Eigen::Vector2d o2 = o.head<2>();
  if (!indexed_ || (o2 - index_center_).squaredNorm() > margin_ * margin_) IndexCylindersAround(o2);
  const double h = d.head<2>().norm();  // horizontal travel per metre along the ray
  // A vertical ray has no azimuth, and only a trunk under or over its origin can meet it.
  if (!(h > 0.0)) {
    for (const Cylinder& cy : world_.cylinders) {
      Nearer(IntersectCylinder(cy, o, d, *best ? (*best)->distance_m : max_m), best);
    }
    return;
  }
  // A rising ray is above every trunk once past the tallest's height.
  const double beyond_top = d.z() > 0.0 ? (cylinder_top_ - o.z()) / d.z() : kInf;
  const CylinderRay ray(o, d);
  NearestTrunk nearest(*best ? (*best)->distance_m : max_m, best->has_value());
  const std::size_t b = static_cast<std::size_t>(AzimuthBin(d.x(), d.y()));
  if (vector_kernel_) {  // never set without the kernel
#if defined(__AVX2__) && defined(__FMA__)
    for (int k = quad_start_[b]; k < quad_start_[b + 1]; ++k) {
      const internal::CylinderQuad& q = quads_[static_cast<std::size_t>(k)];
      const double limit = std::min(nearest.range, beyond_top) * h;
      if (q.reach_m[0] > limit) break;  // this quad and all later lie beyond
      CylinderHit hit;
      const int lane = NearestInQuadAvx2(q, ray, nearest.range, limit, &hit, &cylinder_tests_);
      if (lane >= 0) nearest.Offer(hit, q.id[lane]);
    }
#endif
  } else {
    for (int k = bin_start_[b]; k < bin_start_[b + 1]; ++k) {
      const AzimuthEntry& e = bin_items_[static_cast<std::size_t>(k)];
      if (e.reach_m > std::min(nearest.range, beyond_top) * h) break;  // this one and all later lie beyond
      const Cylinder& cy = world_.cylinders[static_cast<std::size_t>(e.cylinder)];
      ++cylinder_tests_;
      nearest.Offer(
          HitCylinder(cy.center_m.x(), cy.center_m.y(), cy.radius_m * cy.radius_m, cy.height_m, ray, nearest.range),
          e.cylinder);
    }
  }
  if (nearest.cylinder >= 0) {
    *best = HitOf(world_.cylinders[static_cast<std::size_t>(nearest.cylinder)], o, d, nearest.hit);
  }
}

std::optional<RayHit> RayCaster::Cast(const Vector3& origin, const Vector3& d, double max_m, double t) {
  const Vector3 o(origin.x(), origin.y(), origin.z() + lift_m_);
  std::optional<RayHit> best = IntersectGround(o, d, max_m);
  for (const MovingBox& m : world_.moving_boxes) Nearer(IntersectBox(m.At(t), o, d, max_m), &best);
  if (!o.allFinite() || !d.allFinite()) return best;
  if (!world_.cylinders.empty()) CastCylinders(o, d, max_m, &best);
  if (nx_ > 0) CastBoxes(o, d, max_m, &best);
  return best;
}

void RayCaster::CastBoxes(const Vector3& o, const Vector3& d, double max_m, std::optional<RayHit>* best_out) {
  std::optional<RayHit>& best = *best_out;
  if (++ray_id_ == 0) {  // the mailbox counter wrapped: forget every mark
    std::fill(last_ray_.begin(), last_ray_.end(), 0u);
    ray_id_ = 1;
  }
  // The part of the ray inside the grid's horizontal bounds and below the boxes' top: [t_in,
  // t_out]. (Most of a LiDAR's pulses are sky: those that rise leave every box behind once above
  // the tallest, long before the grid's edge.)
  const Eigen::Vector2d o2 = o.head<2>(), d2 = d.head<2>();
  const Eigen::Vector2d hi = min_ + cell_ * Eigen::Vector2d(nx_, ny_);
  double t_in = 0.0, t_out = best ? best->distance_m : max_m;
  const double t_top = d.z() > 0.0 ? (box_top_ - o.z()) / d.z() : kInf;
  t_out = std::min(t_out, t_top);
  for (int i = 0; i < 2; ++i) {
    if (std::abs(d2[i]) < 1e-15) {
      if (o2[i] < min_[i] || o2[i] > hi[i]) return;
      continue;
    }
    double t1 = (min_[i] - o2[i]) / d2[i], t2 = (hi[i] - o2[i]) / d2[i];
    if (t1 > t2) std::swap(t1, t2);
    t_in = std::max(t_in, t1);
    t_out = std::min(t_out, t2);
  }
  if (t_in > t_out) return;
  // Amanatides-Woo traversal of the cells the ray crosses, nearest first.
  const Eigen::Vector2d start = o2 + t_in * d2;
  int cx = std::clamp(static_cast<int>(std::floor((start.x() - min_.x()) / cell_)), 0, nx_ - 1);
  int cy = std::clamp(static_cast<int>(std::floor((start.y() - min_.y()) / cell_)), 0, ny_ - 1);
  const int step_x = d2.x() > 0.0 ? 1 : -1, step_y = d2.y() > 0.0 ? 1 : -1;
  const auto boundary_t = [&](int i, int cell, int step) {
    if (std::abs(d2[i]) < 1e-15) return kInf;
    const double edge = min_[i] + cell_ * (cell + (step > 0 ? 1 : 0));
    return (edge - o2[i]) / d2[i];
  };
  double t_next_x = boundary_t(0, cx, step_x), t_next_y = boundary_t(1, cy, step_y);
  const double dt_x = std::abs(d2.x()) < 1e-15 ? kInf : cell_ / std::abs(d2.x());
  const double dt_y = std::abs(d2.y()) < 1e-15 ? kInf : cell_ / std::abs(d2.y());
  double t_cell = t_in;
  while (true) {
    const double range = best ? best->distance_m : max_m;
    if (t_cell > range || t_cell > t_top) break;  // every later cell lies beyond the nearest hit or above the top
    const std::size_t c = static_cast<std::size_t>(cy) * nx_ + cx;
    for (int k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
      const int obstacle = items_[static_cast<std::size_t>(k)];
      if (last_ray_[static_cast<std::size_t>(obstacle)] == ray_id_) continue;
      last_ray_[static_cast<std::size_t>(obstacle)] = ray_id_;
      Nearer(IntersectBox(world_.boxes[static_cast<std::size_t>(obstacle)], o, d, range), &best);
    }
    if (t_next_x < t_next_y) {
      cx += step_x;
      t_cell = t_next_x;
      t_next_x += dt_x;
    } else {
      cy += step_y;
      t_cell = t_next_y;
      t_next_y += dt_y;
    }
    if (cx < 0 || cx >= nx_ || cy < 0 || cy >= ny_) break;
  }
}

}  // namespace rotorguard::sim
