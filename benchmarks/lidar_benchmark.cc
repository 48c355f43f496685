// The simulated MID-360 in the 500-tree forest of `rotorguard bench perception`, spinning at
// 11 rad/s while flying 1 m/s. BM_LidarForestStep: one iteration is one 1 ms physics step (200
// pulses); items per second are pulses simulated per second (target >= 2 M/s).
// CastForestRays/<kernel>: the ray caster alone on those pulses, per cylinder kernel, with the
// trunks tested per ray (RayCaster::cylinder_tests).
// BM_DeskewFrame: one forest frame's points moved to the sensor frame at its end.
// BM_MapInsertFrame/N: one iteration inserts one 10 Hz frame of a sensor sending N pulses per
// second into the occupancy map (target <= 5 ms for a 20k-point frame): the MID-360's 200 000
// (about 15 500 returns per frame in the forest, the rest sky) and 260 000 (about 20 000
// returns); MapInsertFrame/portable_kernel/N the same with the portable walk kernel instead of
// the AVX2 one, MapInsertFrame/clearing_stride_2/N with every other ray walked.
// Run: build/bin/lidar_benchmark
#include <benchmark/benchmark.h>

#include "rotorguard/benchmarks/perception_bench.h"
#include "rotorguard/campaign_kinds/planner_bench.h"
#include "rotorguard/perception/deskew.h"
#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/sim/lidar.h"

namespace {

using namespace rotorguard;

sim::World Forest() { return benchmarks::PerceptionForest(11); }

sim::BodyPose PoseAt(TimeNs t) {
  const double s = ToSeconds(t);
  sim::BodyPose p;
  p.p_W = Vector3(-12.0 + std::fmod(s, 24.0), 0.0, 1.5);  // along the forest's clear lane
  p.q_WB = Quaternion(Eigen::AngleAxisd(11.0 * s, Vector3::UnitZ()));
  return p;
}

void BM_LidarForestStep(benchmark::State& state) {
  sim::LidarOptions o;
  o.enabled = true;
  sim::LidarSimulator lidar(o, Forest(), 1);
  const auto pose_at = PoseAt;
  TimeNs t = 0;
  std::size_t points = 0;
  for (auto _ : state) {
    if (auto f = lidar.Step(t, pose_at(t), t + 1'000'000, pose_at(t + 1'000'000))) points += f->points_S.size();
    t += 1'000'000;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(lidar.pulses()));
  state.counters["returns_per_frame"] =
      benchmark::Counter(static_cast<double>(points) / std::max(1.0, ToSeconds(t) * 10.0));
}
BENCHMARK(BM_LidarForestStep);

// The ray caster alone on the same pulses, with each cylinder kernel: one iteration casts one
// physics step's 200 pulses from the sensor's pose at the step's start.
void CastForestRays(benchmark::State& state, const sim::World& forest, sim::RayCasterOptions::CylinderKernel kernel) {
  sim::LidarOptions o;
  sim::RayCasterOptions ro;
  ro.cylinder_kernel = kernel;
  sim::RayCaster caster(forest, ro);
  const sim::LidarPattern pattern(o);
  TimeNs t = 0;
  std::uint64_t k = 0;
  std::size_t hits = 0;
  for (auto _ : state) {
    const sim::BodyPose pose = PoseAt(t);
    const Matrix3 R = pose.q_WB.toRotationMatrix();
    const Vector3 origin = pose.p_W + R * o.position_m;
    for (int i = 0; i < 200; ++i, ++k)
      hits += caster.Cast(origin, R * pattern.Direction(k), o.max_range_m, 0.0) ? 1 : 0;
    t += 1'000'000;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(k));
  const double rays = std::max<double>(1.0, static_cast<double>(k));
  state.counters["hit_share"] = benchmark::Counter(static_cast<double>(hits) / rays);
  state.counters["trunk_tests_per_ray"] = benchmark::Counter(static_cast<double>(caster.cylinder_tests()) / rays);
}
BENCHMARK_CAPTURE(CastForestRays, auto_kernel, Forest(), sim::RayCasterOptions::CylinderKernel::kAuto);
BENCHMARK_CAPTURE(CastForestRays, portable_kernel, Forest(), sim::RayCasterOptions::CylinderKernel::kPortable);
// The same in a forest of `rotorguard bench nav` (fewer, thicker trees).
BENCHMARK_CAPTURE(CastForestRays, nav_forest_auto_kernel, benchmarks::PlannerForest(22),
                  sim::RayCasterOptions::CylinderKernel::kAuto);
BENCHMARK_CAPTURE(CastForestRays, nav_forest_portable_kernel, benchmarks::PlannerForest(22),
                  sim::RayCasterOptions::CylinderKernel::kPortable);

void MapInsertFrame(benchmark::State& state, perception::VoxelMapOptions::WalkKernel kernel, int clearing_stride = 1) {
  // Frames of the flight above in the world frame (each point placed with its true pose),
  // simulated between timed iterations so that the window moves as in flight.
  sim::LidarOptions o;
  o.enabled = true;
  o.points_per_s = static_cast<double>(state.range(0));
  sim::LidarSimulator lidar(o, Forest(), 1);
  perception::VoxelMapOptions map_options;
  map_options.walk_kernel = kernel;
  map_options.clearing_stride = clearing_stride;
  perception::VoxelMap map(map_options);
  map.Recenter(PoseAt(0).p_W);
  TimeNs t = 0;
  std::size_t frames = 0, points = 0;
  double steps = 0.0, updated = 0.0, skipped = 0.0;
  std::vector<Eigen::Vector3f> world;
  for (auto _ : state) {
    state.PauseTiming();
    std::optional<LidarFrame> f;
    while (!f) {
      f = lidar.Step(t, PoseAt(t), t + 1'000'000, PoseAt(t + 1'000'000));
      t += 1'000'000;
    }
    world.clear();
    for (std::size_t i = 0; i < f->points_S.size(); ++i) {
      const sim::BodyPose p = PoseAt(f->t_start_ns + f->offset_ns[i]);
      world.push_back((p.p_W + p.q_WB * (o.position_m + f->points_S[i].cast<double>())).cast<float>());
    }
    const sim::BodyPose end = PoseAt(f->t_end_ns);
    const Vector3 origin = end.p_W + end.q_WB * o.position_m;
    state.ResumeTiming();
    map.Recenter(origin);
    const perception::MapUpdateSummary s = map.Insert(origin, world);
    steps += s.voxels_traversed;
    skipped += s.voxels_skipped;
    updated += s.voxels_updated;
    points += world.size();
    ++frames;
  }
  const double n = static_cast<double>(std::max<std::size_t>(1, frames));
  state.counters["points_per_frame"] = benchmark::Counter(static_cast<double>(points) / n);
  state.counters["ray_steps_per_frame"] = benchmark::Counter(steps / n);
  state.counters["voxels_updated_per_frame"] = benchmark::Counter(updated / n);
  state.counters["skipped_step_share"] = benchmark::Counter(steps > 0.0 ? skipped / steps : 0.0);
}
void BM_MapInsertFrame(benchmark::State& state) {
  MapInsertFrame(state, perception::VoxelMapOptions::WalkKernel::kAuto);
}
BENCHMARK(BM_MapInsertFrame)->Arg(200000)->Arg(260000)->Unit(benchmark::kMillisecond);
// The same with the portable walk kernel (two interleaved rays instead of four in a vector).
BENCHMARK_CAPTURE(MapInsertFrame, portable_kernel, perception::VoxelMapOptions::WalkKernel::kPortable)
    ->Arg(200000)
    ->Unit(benchmark::kMillisecond);
// The same with clearing_stride 2, as forest.yaml (and so every bench nav trial) maps: half the
// rays walked.
BENCHMARK_CAPTURE(MapInsertFrame, clearing_stride_2, perception::VoxelMapOptions::WalkKernel::kAuto, 2)
    ->Arg(200000)
    ->Unit(benchmark::kMillisecond);

// One forest frame of the MID-360 (200 000 pulses/s) deskewed with a 333 Hz gyro history of
// the 11 rad/s spin: per frame, and per point as items.
void BM_DeskewFrame(benchmark::State& state) {
  sim::LidarOptions o;
  o.enabled = true;
  sim::LidarSimulator lidar(o, Forest(), 1);
  std::optional<LidarFrame> f;
  TimeNs t = 0;
  for (; !f || f->t_start_ns == 0; t += 1'000'000) f = lidar.Step(t, PoseAt(t), t + 1'000'000, PoseAt(t + 1'000'000));
  perception::Deskewer deskewer{perception::DeskewOptions{}};
  for (TimeNs s = 0; s <= f->t_end_ns; s += 3'000'000) {
    ImuSample imu;
    imu.t_ns = s;
    imu.w_B = Vector3(0.0, 0.0, 11.0);
    deskewer.OnImu(imu);
  }
  std::vector<Eigen::Vector3f> out;
  for (auto _ : state) {
    deskewer.Deskew(*f, Vector3(1.0, 0.0, 0.0), PoseAt(f->t_end_ns).q_WB, &out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * f->points_S.size()));
}
BENCHMARK(BM_DeskewFrame)->Unit(benchmark::kMicrosecond);

}  // namespace
