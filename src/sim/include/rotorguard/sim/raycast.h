#pragma once
/// Ray casting against the world (truth side, for the simulated LiDAR): exact intersections with
/// the ground plane, yawed boxes and vertical cylinders. Two indices spare a ray most of the tests:
/// - boxes lie in a uniform grid over the horizontal plane, so that a ray visits only the cells it
///   crosses (Amanatides and Woo, "A fast voxel traversal algorithm", Eurographics 1987);
/// - cylinders (trees) lie in an azimuth index seen from the sensor: a LiDAR casts all its rays
///   from nearly one point, and from a point a vertical cylinder covers only an interval of
///   azimuths, so a ray tests only the cylinders of its azimuth's bin, nearest first, and stops at
///   the first whose distance lies beyond its hit. In a 500-tree forest a LiDAR ray then tests 2.8
///   trunks on average (lidar_benchmark's CastForestRays/portable_kernel, trunk_tests_per_ray).
#include <cstdint>
#include <optional>
#include <vector>

#include "rotorguard/core/types.h"
#include "rotorguard/sim/world.h"

namespace rotorguard::sim {

/// The first surface a ray meets.
struct RayHit {
  double distance_m = 0.0;
  Vector3 normal_W = Vector3::UnitZ();  ///< unit surface normal, facing the ray's origin
};

/// Ray (origin o, unit direction d) against single primitives, for distances in (0, max_m].
/// Rays starting inside a solid report nothing for it (a sensor cannot see out of an obstacle).
std::optional<RayHit> IntersectGround(const Vector3& o, const Vector3& d, double max_m);
std::optional<RayHit> IntersectBox(const Box& box, const Vector3& o, const Vector3& d, double max_m);
/// The side and the top cap of a vertical cylinder standing on the ground.
std::optional<RayHit> IntersectCylinder(const Cylinder& cylinder, const Vector3& o, const Vector3& d, double max_m);

namespace internal {
/// Four cylinders of an azimuth bin, in the bin's order, a field per vector register (the ray
/// caster's AVX2 kernel tests them at once). Lanes past the bin's end have reach_m = +inf and a
/// NaN squared radius, which no ray hits.
struct alignas(32) CylinderQuad {
  double reach_m[4], cx[4], cy[4], r2[4], top[4];  // reach, centre, squared radius, height
  int id[4];                                       // index in World::cylinders, -1 for padding
};
}  // namespace internal

struct RayCasterOptions {
  double cell_size_m = 1.0;  ///< the boxes' grid cell edge [m], > 0
  /// Bins of the cylinders' azimuth index, in [8, 65536]: more bins, fewer candidates per ray.
  int azimuth_bins = 1024;
  /// The index serves rays from within this horizontal distance of the point it was built around
  /// [m], > 0; a ray from farther rebuilds it around its own origin (a flying sensor every
  /// `azimuth_margin_m` of travel). Larger: fewer rebuilds, more candidates per ray.
  double azimuth_margin_m = 0.25;
  /// How a ray tests the cylinders of its bin. Both give the same hits to the bit (a test casts
  /// with each and compares); they differ in speed only. kAuto tests four cylinders in one
  /// vector register when the build targets AVX2 (x86-64-v3), else one at a time; kPortable
  /// forces the latter.
  enum class CylinderKernel { kAuto, kPortable };
  CylinderKernel cylinder_kernel = CylinderKernel::kAuto;
  void Validate() const;
};

/// The static part of a world (ground, boxes in a grid, cylinders in the azimuth index), plus its
/// moving boxes tested directly at each ray's time. Not thread-safe (per-ray bookkeeping and the
/// index rebuilt as the origin moves); one per thread.
class RayCaster {
 public:
  explicit RayCaster(World world, const RayCasterOptions& options = {});
  /// The nearest hit of the ray (o, unit d) within max_m at time t [s] (moving boxes), if any.
  std::optional<RayHit> Cast(const Vector3& o, const Vector3& d, double max_m, double t);
  /// The world as the caster holds it: lifted so that its ground lies at z = 0.
  const World& world() const { return world_; }
  /// How often the azimuth index was built (at each ray from beyond the margin of the last build).
  int index_rebuilds() const { return rebuilds_; }
  /// Whether the AVX2 kernel tests the trunks (kAuto in a build that targets AVX2 and FMA).
  bool vector_kernel() const { return vector_kernel_; }
  /// Trunks tested so far by the rays that have an azimuth (the index's cost): each bin entry
  /// within a ray's reach when it was tested (for the AVX2 kernel, within the reach at the start
  /// of its quad).
  long cylinder_tests() const { return cylinder_tests_; }

 private:
  void CastBoxes(const Vector3& o, const Vector3& d, double max_m, std::optional<RayHit>* best);
  void CastCylinders(const Vector3& o, const Vector3& d, double max_m, std::optional<RayHit>* best);
  /// Rebuilds the azimuth index for rays from within azimuth_margin_m of `center` (horizontal).
  void IndexCylindersAround(const Eigen::Vector2d& center);
  /// The azimuth bin of the horizontal direction (x, y), not both zero.
  int AzimuthBin(double x, double y) const;

  World world_;
  double lift_m_ = 0.0;  // the world's ground depth: rays are cast in the ground's frame
  // Boxes: the grid.
  double cell_ = 1.0;
  Eigen::Vector2d min_ = Eigen::Vector2d::Zero();  // grid origin (lower corner)
  int nx_ = 0, ny_ = 0;
  double box_top_ = 0.0;         // the highest point of the boxes [m]
  std::vector<int> cell_start_;  // CSR: boxes of cell c are items_[cell_start_[c] .. cell_start_[c + 1])
  std::vector<int> items_;
  std::vector<std::uint32_t> last_ray_;  // mailbox: the ray that last tested each box
  std::uint32_t ray_id_ = 0;
  // Cylinders: the azimuth index around index_center_, a CSR of bins whose entries are sorted by
  // the horizontal distance a ray from the served disc must travel before it can reach them.
  struct AzimuthEntry {
    double reach_m;  // lower bound of that distance
    int cylinder;
  };
  int bins_ = 1024;
  double margin_ = 0.25;
  double cylinder_top_ = 0.0;  // the tallest cylinder [m]
  bool indexed_ = false;
  Eigen::Vector2d index_center_ = Eigen::Vector2d::Zero();
  std::vector<int> bin_start_;
  std::vector<AzimuthEntry> bin_items_;
  // For the AVX2 kernel, the same entries four at a time: bin b's are quads_[quad_start_[b] ..
  // quad_start_[b + 1]).
  std::vector<int> quad_start_;
  std::vector<internal::CylinderQuad> quads_;
  bool vector_kernel_ = false;  // the AVX2 kernel tests the quads
  // Scratch of a rebuild, kept to reuse its memory.
  std::vector<double> reach_;
  std::vector<int> order_, first_bin_, bin_count_, fill_;
  int rebuilds_ = 0;
  long cylinder_tests_ = 0;
};

}  // namespace rotorguard::sim
