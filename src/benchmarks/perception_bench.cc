
#include "rotorguard/benchmarks/perception_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <unordered_set>
#include <vector>

#include "rotorguard/benchmarks/octomap_reference.h"
#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/harness/world_raster.h"
#include "rotorguard/perception/lidar_mapper.h"
#include "rotorguard/perception/lio.h"
#include "rotorguard/sim/lidar.h"
#include "rotorguard/sim/sensors.h"
#include "rotorguard/stack/estimator.h"

namespace rotorguard::benchmarks {

namespace {

/// The prescribed motion: level, yawing at the spin rate, along a line (forest) or a circle (room).
/// With ramp_s > 0 the speed and the spin rise from rest over that time as a smoothstep
/// (3u² − 2u³), so that the flight starts at rest as a vehicle does.
struct Path {
  Vector3 start_W = Vector3::Zero();
  double speed_m_s = 1.0;
  double spin_rad_s = 11.0;
  double circle_radius_m = 0.0;  // 0: a straight line along +x
  Vector3 circle_center_W = Vector3::Zero();
  double ramp_s = 0.0;

  /// The integral of the unit rate that starts smoothly, the rate, and its derivative:
  /// ramp (u³ − u⁴/2), 3u² − 2u³, (6u − 6u²) / ramp while ramping (u = t / ramp); t − ramp/2, 1, 0 after.
  Vector3 SmoothStart(double t) const {
    if (ramp_s <= 0.0 || t >= ramp_s) return Vector3(t - 0.5 * std::max(ramp_s, 0.0), 1.0, 0.0);
    const double u = std::max(t, 0.0) / ramp_s;
    return Vector3(ramp_s * (u * u * u - 0.5 * u * u * u * u), 3.0 * u * u - 2.0 * u * u * u,
                   (6.0 * u - 6.0 * u * u) / ramp_s);
  }
  /// Distance along the path, and its first and second derivatives.
  Vector3 Arc(double t) const { return speed_m_s * SmoothStart(t); }
  Vector3 Position(double t) const {
    const double s = Arc(t).x();
    if (circle_radius_m <= 0.0) return start_W + Vector3(s, 0.0, 0.0);
    const double a = s / circle_radius_m;
    return circle_center_W + circle_radius_m * Vector3(std::cos(a), std::sin(a), 0.0);
  }
  Vector3 Velocity(double t) const {
    const Vector3 arc = Arc(t);
    if (circle_radius_m <= 0.0) return Vector3(arc.y(), 0.0, 0.0);
    const double a = arc.x() / circle_radius_m;
    return arc.y() * Vector3(-std::sin(a), std::cos(a), 0.0);
  }
  Vector3 Acceleration(double t) const {
    const Vector3 arc = Arc(t);
    if (circle_radius_m <= 0.0) return Vector3(arc.z(), 0.0, 0.0);
    const double a = arc.x() / circle_radius_m;
    // Tangential s̈ and centripetal ṡ²/r.
    return arc.z() * Vector3(-std::sin(a), std::cos(a), 0.0) -
           (arc.y() * arc.y() / circle_radius_m) * Vector3(std::cos(a), std::sin(a), 0.0);
  }
  Quaternion Attitude(double t) const {
    return Quaternion(Eigen::AngleAxisd(spin_rad_s * SmoothStart(t).x(), Vector3::UnitZ()));
  }
  sim::BodyPose Pose(TimeNs t) const { return {Position(ToSeconds(t)), Attitude(ToSeconds(t))}; }
  /// The truth the sensor models read at time t: the state `x` (position, attitude, velocity, body
  /// rate about z) and the accelerations, `truth` pointing at `x`.
  void Sample(TimeNs t, vehicle::StateVector* x, sim::TruthSample* truth) const {
    const double ts = ToSeconds(t);
    const Vector3 smooth = SmoothStart(ts);
    x->segment<3>(vehicle::StateIndex::kPosition) = Position(ts);
    const Quaternion q = Attitude(ts);
    x->segment<4>(vehicle::StateIndex::kQuaternion) << q.w(), q.x(), q.y(), q.z();
    x->segment<3>(vehicle::StateIndex::kVelocity) = Velocity(ts);
    x->segment<3>(vehicle::StateIndex::kBodyRate) = Vector3(0.0, 0.0, spin_rad_s * smooth.y());
    truth->t_ns = t;
    truth->x = x;
    truth->acc.a_W = Acceleration(ts);
    truth->acc.alpha_B = Vector3(0.0, 0.0, spin_rad_s * smooth.z());
  }
};

struct Scene {
  std::string name;
  sim::World world;
  Path path;
};

/// Voxels as one 64-bit key (21 bits per axis, offset to stay positive).
std::int64_t VoxelKey(const Vector3& p, double res) {
  const auto axis = [res](double v) { return static_cast<std::int64_t>(std::floor(v / res)) + (1 << 20); };
  return (axis(p.x()) << 42) | (axis(p.y()) << 21) | axis(p.z());
}

Vector3 KeyCenter(std::int64_t key, double res) {
  const auto axis = [](std::int64_t k) { return static_cast<double>(k - (1 << 20)) + 0.5; };
  return res * Vector3(axis(key >> 42), axis((key >> 21) & ((1 << 21) - 1)), axis(key & ((1 << 21) - 1)));
}

nlohmann::json RunScene(const Scene& scene, bool deskew, const PerceptionBenchOptions& options) {
  sim::LidarOptions lidar_options;
  lidar_options.enabled = true;
  const sim::ImuOptions imu_options;
  const sim::OdometryOptions odometry_options;
  sim::LidarSimulator lidar(lidar_options, scene.world, DeriveSeed(options.seed, 1));
  sim::ImuModel imu(imu_options, DeriveSeed(options.seed, 2));
  sim::OdometryModel odometry(odometry_options, scene.world, DeriveSeed(options.seed, 3));
  sim::RateTimer imu_timer(imu_options.rate_hz), odometry_timer(odometry_options.rate_hz);
  stack::OdometryImuEstimator estimator(1.0);  // no ESC telemetry here: the coefficient is unused
  perception::LidarMapperOptions mapper_options;
  mapper_options.deskew_frames = deskew;
  mapper_options.deskew.sensor_position_m = lidar_options.position_m;
  perception::LidarMapper mapper(mapper_options);
  // The reference: OctoMap fed the very frames the mapper inserted (its world-frame points and
  // sensor origin, in order), at the map's resolution and with its sensor model, out to the
  // sensor's range.
  OctomapReference reference(mapper_options.map);

  const double res = mapper_options.map.resolution_m;
  std::unordered_set<std::int64_t> seen;  // voxels of the returns placed with their true poses
  vehicle::StateVector x = vehicle::StateVector::Zero(13 + 4);
  double lidar_s = 0.0, map_s = 0.0, first_frame_ms = 0.0;
  long frames = 0, points = 0;
  std::vector<double> frame_ms, octomap_ms;
  const TimeNs step = 1'000'000, end = FromSeconds(options.duration_s);
  // Each step as the simulator orders it: the sensors sample at the step's end, so the frame that
  // ends there arrives with the IMU and odometry samples of the same instant.
  for (TimeNs t = step; t <= end; t += step) {
    sim::TruthSample truth;
    scene.path.Sample(t, &x, &truth);
    if (imu_timer.Due(t)) {
      const ImuSample s = imu.Sample(truth);
      estimator.OnImu(s);
      mapper.OnImu(s);
    }
    if (odometry_timer.Due(t)) odometry.Measure(truth);
    if (OdometrySample o; odometry.Deliver(t, &o)) estimator.OnOdometry(o);
    const Stopwatch lidar_clock;
    const std::optional<LidarFrame> frame = lidar.Step(t - step, scene.path.Pose(t - step), t, scene.path.Pose(t));
    lidar_s += lidar_clock.seconds();
    if (!frame) continue;
    for (std::size_t i = 0; i < frame->points_S.size(); ++i) {
      const sim::BodyPose p = scene.path.Pose(frame->t_start_ns + frame->offset_ns[i]);
      seen.insert(VoxelKey(p.p_W + p.q_WB * (lidar_options.position_m + frame->points_S[i].cast<double>()), res));
    }
    const StateEstimate estimate = estimator.Estimate(frame->t_end_ns);
    const Stopwatch map_clock;
    mapper.OnFrame(*frame, estimate);
    const double dt = map_clock.seconds();
    const Stopwatch octomap_clock;
    reference.Insert(mapper.last_origin_W(), mapper.last_points_W(), lidar_options.max_range_m);
    const double octomap_dt = octomap_clock.seconds();
    // The first frame also allocates the map (tens of MB, once per flight): reported apart, and
    // OctoMap's first frame left out with it, so that both means cover the same frames.
    if (frames == 0) {
      first_frame_ms = 1e3 * dt;
    } else {
      map_s += dt;
      frame_ms.push_back(1e3 * dt);
      octomap_ms.push_back(1e3 * octomap_dt);
    }
    ++frames;
    points += static_cast<long>(frame->points_S.size());
  }
  const perception::VoxelMap* map = mapper.map();
  double recall = 0.0, octomap_recall = 0.0, octomap_precision = 0.0;
  long truth_voxels = 0, octomap_occupied = 0;
  if (map) {
    // A surface voxel the sensor saw counts as found when the map has an occupied voxel within one
    // voxel of it: the 26 neighbours' centres lie within sqrt(3) voxels, the next ones at 2.
    // OctoMap is asked the same of the same cells: one of the 27 cells occupied (an unknown one is
    // not), only those in the map's window, as Nearest sees no voxel outside it.
    long found = 0, octomap_found = 0;
    for (const std::int64_t key : seen) {
      const Vector3 c = KeyCenter(key, res);
      if (!map->InWindow(c)) continue;
      ++truth_voxels;
      found += map->Nearest(c, 1.8 * res) ? 1 : 0;
      bool hit = false;
      for (int dx = -1; dx <= 1 && !hit; ++dx) {
        for (int dy = -1; dy <= 1 && !hit; ++dy) {
          for (int dz = -1; dz <= 1 && !hit; ++dz) {
            const Vector3 n = c + res * Vector3(dx, dy, dz);
            hit = map->InWindow(n) && reference.IsOccupied(n);
          }
        }
      }
      octomap_found += hit ? 1 : 0;
    }
    const auto share = [](long part, long whole) {
      return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole) : 0.0;
    };
    recall = share(found, truth_voxels);
    octomap_recall = share(octomap_found, truth_voxels);
    // Precision over OctoMap's occupied cells in the map's final window: the map has forgotten
    // what left its window, OctoMap keeps the whole flight, so both are scored on the same region.
    const std::vector<Vector3> cells = reference.OccupiedCells(map->window_min_W(), map->window_max_W());
    octomap_occupied = static_cast<long>(cells.size());
    octomap_precision = harness::MapPrecision(cells, res, scene.world);
  }
  const double map_ms_p99 = Percentile(frame_ms, 0.99);
  std::sort(frame_ms.begin(), frame_ms.end());
  const auto n = static_cast<double>(std::max<long>(1, frames));
  const auto timed = static_cast<double>(std::max<std::size_t>(1, frame_ms.size()));
  const double map_ms_mean = 1e3 * map_s / timed;
  const double octomap_ms_mean = std::accumulate(octomap_ms.begin(), octomap_ms.end(), 0.0) / timed;
  return {{"scene", scene.name},
          {"deskew", deskew},
          {"frames", frames},
          {"points_per_frame_mean", static_cast<double>(points) / n},
          {"points_per_s_simulated", lidar_s > 0.0 ? static_cast<double>(lidar.pulses()) / lidar_s : 0.0},
          {"map_update_ms_mean", map_ms_mean},
          {"map_first_frame_ms", first_frame_ms},
          {"map_update_ms_median", frame_ms.empty() ? 0.0 : frame_ms[frame_ms.size() / 2]},
          {"map_update_ms_max", frame_ms.empty() ? 0.0 : frame_ms.back()},
          {"map_voxels_occupied", map ? map->occupied_count() : 0},
          {"truth_voxels_in_window", truth_voxels},
          {"map_precision", map ? harness::MapPrecision(*map, scene.world) : 0.0},
          {"map_recall", recall},
          {"map_update_ms_p99", map_ms_p99},
          {"octomap",
           {{"insert_ms_mean", octomap_ms_mean},
            {"insert_ms_p99", Percentile(octomap_ms, 0.99)},
            {"precision", octomap_precision},
            {"recall", octomap_recall},
            {"voxels_occupied_in_window", octomap_occupied},
            {"memory_bytes", reference.memory_bytes()}}},
          // Against the mapper's whole frame (deskewing, placement and insertion; OctoMap is given the
          // frame already placed), so the ratio errs in OctoMap's favour by the deskewing's share.
          {"time_ratio_octomap_over_rotorguard", map_ms_mean > 0.0 ? octomap_ms_mean / map_ms_mean : 0.0}};
}

/// One condition of bench lio: the path flown for `duration_s` with the simulator's IMU (with the
/// airframe's vibration) and LiDAR, the odometry fed as the flight stack feeds it.
nlohmann::json RunLioScene(const Scene& scene, const std::string& motion, const LioBenchOptions& options) {
  sim::LidarOptions lidar_options;
  lidar_options.enabled = true;
  sim::ImuOptions imu_options;
  imu_options.vibration_m_s2 = 0.6;
  imu_options.vibration_reference_speed_rad_s = 900.0;
  sim::LidarSimulator lidar(lidar_options, scene.world, DeriveSeed(options.seed, 1));
  sim::ImuModel imu(imu_options, DeriveSeed(options.seed, 2));
  sim::RateTimer imu_timer(imu_options.rate_hz);
  perception::LioOptions lio_options;
  lio_options.imu_position_m = imu_options.position_m;
  lio_options.lidar_position_m = lidar_options.position_m;
  const Path& path = scene.path;
  perception::Lio lio(lio_options, path.Position(0.0), YawOf(path.Attitude(0.0)));
  vehicle::StateVector x = vehicle::StateVector::Zero(13 + 4);
  sim::TruthSample truth;
  truth.motor_speed_rad_s = RotorVector::Constant(4, 900.0);  // hover speed: the vibration's frequency
  double sum2 = 0.0, max_e = 0.0, att2 = 0.0, max_att = 0.0;
  long samples = 0, frames = 0, used = 0, degenerate = 0;
  std::vector<double> frame_ms;
  // The estimate's and the truth's positions at every 10 m travelled (flying), for the drift.
  std::vector<std::pair<Vector3, Vector3>> legs;
  bool diverged = false;
  const TimeNs step = 1'000'000, end = FromSeconds(options.duration_s);
  for (TimeNs t = step; t <= end; t += step) {
    path.Sample(t, &x, &truth);
    if (imu_timer.Due(t)) {
      lio.OnImu(imu.Sample(truth));
      const StateEstimate e = lio.Estimate();
      // Against the truth at the estimate's own time (the path gives it at any instant).
      const sim::BodyPose p = path.Pose(e.t_ns);
      const double err = (e.p_W - p.p_W).norm();
      const double att = LogSO3(p.q_WB.conjugate() * e.q_WB).norm();
      if (!std::isfinite(err) || err > 1.0) diverged = true;
      sum2 += err * err;
      att2 += att * att;
      max_e = std::max(max_e, std::isfinite(err) ? err : 1e9);
      max_att = std::max(max_att, att);
      ++samples;
      if (motion == "flying" && path.Arc(ToSeconds(e.t_ns)).x() >= 10.0 * static_cast<double>(legs.size())) {
        legs.emplace_back(e.p_W, p.p_W);
      }
    }
    const std::optional<LidarFrame> frame = lidar.Step(t - step, path.Pose(t - step), t, path.Pose(t));
    if (!frame) continue;
    const Stopwatch clock;
    const perception::LioFrameSummary f = lio.OnFrame(*frame);
    frame_ms.push_back(1e3 * clock.seconds());
    if (options.on_frame) {
      // The sensor's pose: the body's with the mount's offset (axes aligned, LidarOptions).
      const auto sensor = [&](TimeNs at) {
        const sim::BodyPose b = path.Pose(at);
        return sim::BodyPose{b.p_W + b.q_WB * lidar_options.position_m, b.q_WB};
      };
      TimeNs last = frame->t_start_ns;
      for (std::uint32_t o : frame->offset_ns) last = std::max(last, frame->t_start_ns + static_cast<TimeNs>(o));
      const StateEstimate e = lio.Estimate();
      options.on_frame(
          {scene.name, motion, path.spin_rad_s, *frame, sensor(last), e.p_W - path.Pose(e.t_ns).p_W, frame_ms.back()});
    }
    ++frames;
    used += f.used;
    degenerate += f.used && f.degenerate;
  }
  nlohmann::json drift = nullptr;
  if (legs.size() >= 2) {
    double sum = 0.0;
    for (std::size_t k = 1; k < legs.size(); ++k) {
      sum += ((legs[k].first - legs[k - 1].first) - (legs[k].second - legs[k - 1].second)).norm() / 10.0 * 100.0;
    }
    drift = sum / static_cast<double>(legs.size() - 1);
  }
  const double n = static_cast<double>(std::max<long>(1, samples));
  constexpr double kDeg = 180.0 / std::numbers::pi;
  return {{"scene", scene.name},
          {"motion", motion},
          {"spin_rad_s", path.spin_rad_s},
          {"ate_rmse_m", std::sqrt(sum2 / n)},
          {"ate_max_m", max_e},
          {"attitude_rmse_deg", kDeg * std::sqrt(att2 / n)},
          {"attitude_max_deg", kDeg * max_att},
          {"drift_percent", drift},
          {"frames", frames},
          {"frames_used", used},
          {"degenerate_fraction", used > 0 ? static_cast<double>(degenerate) / static_cast<double>(used) : 0.0},
          {"frame_ms_mean", frame_ms.empty() ? 0.0
                                             : std::accumulate(frame_ms.begin(), frame_ms.end(), 0.0) /
                                                   static_cast<double>(frame_ms.size())},
          {"frame_ms_p99", Percentile(frame_ms, 0.99)},
          {"map_points", lio.map().size()},
          {"diverged", diverged}};
}

}  // namespace

void PerceptionBenchOptions::Validate() const {
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowInvalidArgument("RunPerceptionBenchmark", std::string("PerceptionBenchOptions::") + field, v, rule);
  };
  require(duration_s > 0.0 && duration_s <= 600.0, "duration_s", duration_s, "a duration in (0, 600] s");
  require(spin_rad_s >= 0.0 && spin_rad_s <= 50.0, "spin_rad_s", spin_rad_s, "a rate in [0, 50] rad/s");
  require(speed_m_s >= 0.0 && speed_m_s <= 5.0, "speed_m_s", speed_m_s, "a speed in [0, 5] m/s");
}

sim::World PerceptionForest(std::uint64_t seed) {
  Rng rng(DeriveSeed(seed, 4));
  sim::World w;
  while (w.cylinders.size() < 500) {
    const sim::Cylinder c{Eigen::Vector2d(rng.Uniform(-15, 15), rng.Uniform(-10, 10)), rng.Uniform(0.05, 0.3),
                          rng.Uniform(3, 10)};
    if (std::abs(c.center_m.y()) - c.radius_m > 1.0) w.cylinders.push_back(c);  // the flight lane stays clear
  }
  return w;
}

sim::World PerceptionRoom() {
  sim::World w;
  w.boxes = {{Vector3(4.5, 0, 1.5), Vector3(1, 8, 3), 0.0},   {Vector3(-4.5, 0, 1.5), Vector3(1, 8, 3), 0.0},
             {Vector3(0, 3.5, 1.5), Vector3(10, 1, 3), 0.0},  {Vector3(0, -3.5, 1.5), Vector3(10, 1, 3), 0.0},
             {Vector3(2.8, -2.0, 0.4), Vector3(1.2, 0.8, 0.8), 0.3},  // a table-sized box
             {Vector3(-3.7, 1.5, 1.0), Vector3(0.4, 1.6, 2.0), 0.0}};  // a shelf against a wall
  w.cylinders = {{Eigen::Vector2d(1.5, 1.0), 0.2, 3.0}};
  return w;
}

sim::World LioRoom() {
  sim::World w = PerceptionRoom();
  w.boxes.push_back({Vector3(0.0, 0.0, 3.25), Vector3(10.0, 8.0, 0.5), 0.0});
  return w;
}

nlohmann::json RunPerceptionBenchmark(const PerceptionBenchOptions& options) {
  options.Validate();
  Path line, circle;
  line.start_W = Vector3(-12.0, 0.0, 1.5);
  circle.circle_radius_m = 1.5;
  circle.circle_center_W = Vector3(-0.5, 0.0, 1.5);
  for (Path* p : {&line, &circle}) {
    p->speed_m_s = options.speed_m_s;
    p->spin_rad_s = options.spin_rad_s;
  }
  const std::vector<Scene> scenes = {{"forest", PerceptionForest(options.seed), line},
                                     {"room", PerceptionRoom(), circle}};
  nlohmann::json runs = nlohmann::json::array();
  double pulses_per_s_min = std::numeric_limits<double>::infinity();
  int done = 0;
  for (const Scene& scene : scenes) {
    for (const bool deskew : {true, false}) {
      runs.push_back(RunScene(scene, deskew, options));
      const double pps = runs.back()["points_per_s_simulated"].get<double>();
      pulses_per_s_min = std::min(pulses_per_s_min, pps);
      if (options.progress) options.progress(++done, 4);
    }
  }
  // Targets (the issue): with deskew precision and recall >= 0.95; <= 5 ms per 20k-point frame;
  // >= 2 M simulated points per second.
  bool quality = true, speed = true;
  for (const nlohmann::json& r : runs) {
    if (!r["deskew"].get<bool>()) continue;
    quality = quality && r["map_precision"].get<double>() >= 0.95 && r["map_recall"].get<double>() >= 0.95;
    speed = speed && r["map_update_ms_mean"].get<double>() <= 5.0;
  }
  return {{"benchmark", "perception"},
          {"duration_s", options.duration_s},
          {"spin_rad_s", options.spin_rad_s},
          {"speed_m_s", options.speed_m_s},
          {"seed", options.seed},
          {"runs", runs},
          {"points_per_s_simulated", pulses_per_s_min},
          {"meets_quality_targets", quality},
          {"meets_map_speed_target", speed},
          {"meets_simulation_speed_target", pulses_per_s_min >= 2e6},
          {"host", buildinfo::HostInfo()}};
}

std::string PerceptionMarkdown(const nlohmann::json& r) {
  std::string md = fmt::format(
      "Spinning at {:.1f} rad/s, flying {:.1f} m/s, {:.0f} s per run; LiDAR simulated at {:.2f} M points/s (slowest run).\n\n",
      r["spin_rad_s"].get<double>(), r["speed_m_s"].get<double>(), r["duration_s"].get<double>(),
      r["points_per_s_simulated"].get<double>() / 1e6);
  md += "| scene | deskew | points/frame | map update ms (mean / median / max) | precision | recall |\n";
  md += "|---|---|---|---|---|---|\n";
  for (const nlohmann::json& x : r["runs"]) {
    md += fmt::format("| {} | {} | {:.0f} | {:.2f} / {:.2f} / {:.2f} | {:.3f} | {:.3f} |\n", x["scene"].get<std::string>(),
                      x["deskew"].get<bool>() ? "on" : "off", x["points_per_frame_mean"].get<double>(),
                      x["map_update_ms_mean"].get<double>(), x["map_update_ms_median"].get<double>(),
                      x["map_update_ms_max"].get<double>(), x["map_precision"].get<double>(),
                      x["map_recall"].get<double>());
  }
  md +=
      "\nThe same frames inserted into OctoMap at the same resolution, with the same sensor model, scored the same way "
      "(ms per frame without the first; the map's time is its whole frame, deskewing included):\n\n";
  md +=
      "| scene | deskew | map ms (mean / p99) | OctoMap ms (mean / p99) | OctoMap / map time | OctoMap precision | "
      "OctoMap recall | OctoMap memory MB |\n";
  md += "|---|---|---|---|---|---|---|---|\n";
  for (const nlohmann::json& x : r["runs"]) {
    const nlohmann::json& o = x["octomap"];
    md += fmt::format("| {} | {} | {:.2f} / {:.2f} | {:.1f} / {:.1f} | {:.1f} | {:.3f} | {:.3f} | {:.1f} |\n",
                      x["scene"].get<std::string>(), x["deskew"].get<bool>() ? "on" : "off",
                      x["map_update_ms_mean"].get<double>(), x["map_update_ms_p99"].get<double>(),
                      o["insert_ms_mean"].get<double>(), o["insert_ms_p99"].get<double>(),
                      x["time_ratio_octomap_over_rotorguard"].get<double>(), o["precision"].get<double>(),
                      o["recall"].get<double>(), static_cast<double>(o["memory_bytes"].get<std::size_t>()) / 1e6);
  }
  md += fmt::format("\nTargets: quality (precision and recall >= 0.95 with deskew) {}; map update <= 5 ms {}; "
                    "simulation >= 2 M points/s {}.\n",
                    r["meets_quality_targets"].get<bool>() ? "met" : "NOT met",
                    r["meets_map_speed_target"].get<bool>() ? "met" : "NOT met",
                    r["meets_simulation_speed_target"].get<bool>() ? "met" : "NOT met");
  return md;
}

}  // namespace rotorguard::benchmarks

namespace rotorguard::benchmarks {

void LioBenchOptions::Validate() const {
  const auto require = [](bool ok, const std::string& field, double v, const char* rule) {
    if (!ok) ThrowInvalidArgument("RunLioBenchmark", "LioBenchOptions::" + field, v, rule);
  };
  require(duration_s > 0.0 && duration_s <= 600.0, "duration_s", duration_s, "a duration in (0, 600] s");
  require(speed_m_s > 0.0 && speed_m_s <= 5.0, "speed_m_s", speed_m_s, "a speed in (0, 5] m/s");
  require(!spins.empty(), "spins", 0.0, "at least one rate");
  for (double w : spins) require(w >= 0.0 && w <= 30.0, "spins", w, "rates in [0, 30] rad/s");
}

nlohmann::json RunLioBenchmark(const LioBenchOptions& options) {
  options.Validate();
  const sim::World forest = PerceptionForest(options.seed), room = LioRoom();
  const int total = 4 * static_cast<int>(options.spins.size());
  int done = 0;
  nlohmann::json runs = nlohmann::json::array();
  for (const double spin : options.spins) {
    for (const std::string motion : {"hover", "flying"}) {
      const double speed = motion == "flying" ? options.speed_m_s : 0.0;
      Path line, circle;
      // Hovering in the forest's lane, or flying along it; in the room, on a 1.5 m circle.
      line.start_W = motion == "flying" ? Vector3(-12.0, 0.0, 1.5) : Vector3(0.0, 0.0, 1.5);
      circle.circle_radius_m = 1.5;
      circle.circle_center_W = Vector3(-0.5, 0.0, 1.5);
      for (Path* p : {&line, &circle}) {
        p->speed_m_s = speed;
        p->spin_rad_s = spin;
        p->ramp_s = 2.0;  // from rest, as the odometry starts, up to speed and spin in 2 s
      }
      for (const Scene& scene : {Scene{"forest", forest, line}, Scene{"room", room, circle}}) {
        runs.push_back(RunLioScene(scene, motion, options));
        if (options.progress) options.progress(++done, total);
      }
    }
  }
  return {{"benchmark", "lio"},
          {"duration_s", options.duration_s},
          {"speed_m_s", options.speed_m_s},
          {"seed", options.seed},
          {"runs", runs},
          {"host", buildinfo::HostInfo()}};
}

std::string LioMarkdown(const nlohmann::json& r) {
  std::string md = fmt::format("LiDAR-inertial odometry, {:.0f} s per condition, flying at {:.1f} m/s.\n\n",
                               r["duration_s"].get<double>(), r["speed_m_s"].get<double>());
  md +=
      "| scene | motion | spin (rad/s) | ATE RMSE / max (m) | attitude RMSE / max (deg) | drift (% per 10 m) | "
      "frame ms mean / p99 | degenerate | diverged |\n";
  md += "|---|---|---|---|---|---|---|---|---|\n";
  for (const nlohmann::json& x : r["runs"]) {
    md += fmt::format(
        "| {} | {} | {:.0f} | {:.3f} / {:.3f} | {:.2f} / {:.2f} | {} | {:.2f} / {:.2f} | {:.1f} % | {} |\n",
        x["scene"].get<std::string>(), x["motion"].get<std::string>(), x["spin_rad_s"].get<double>(),
        x["ate_rmse_m"].get<double>(), x["ate_max_m"].get<double>(), x["attitude_rmse_deg"].get<double>(),
        x["attitude_max_deg"].get<double>(),
        x["drift_percent"].is_null() ? std::string("-") : fmt::format("{:.2f}", x["drift_percent"].get<double>()),
        x["frame_ms_mean"].get<double>(), x["frame_ms_p99"].get<double>(),
        100.0 * x["degenerate_fraction"].get<double>(), x["diverged"].get<bool>() ? "yes" : "no");
  }
  return md;
}

}  // namespace rotorguard::benchmarks
