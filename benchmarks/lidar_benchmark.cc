// The simulated MID-360 in a 500-tree forest, spinning at 11 rad/s while flying 1 m/s: one
// benchmark iteration is one 1 ms physics step (200 pulses). Items per second are pulses
// simulated per second (target >= 2 M/s). Run: build/bin/lidar_benchmark
#include <benchmark/benchmark.h>

#include "rotorguard/core/rng.h"
#include "rotorguard/sim/lidar.h"

namespace {

using namespace rotorguard;

sim::World Forest() {
  Rng rng(11);
  sim::World w;
  for (int i = 0; i < 500; ++i) {
    w.cylinders.push_back({Eigen::Vector2d(rng.Uniform(-15, 15), rng.Uniform(-10, 10)), rng.Uniform(0.05, 0.3),
                           rng.Uniform(3, 10)});
  }
  return w;
}

void BM_LidarForestStep(benchmark::State& state) {
  sim::LidarOptions o;
  o.enabled = true;
  sim::LidarSimulator lidar(o, Forest(), 1);
  const auto pose_at = [](TimeNs t) {
    const double s = ToSeconds(t);
    sim::BodyPose p;
    p.p_W = Vector3(-12.0 + std::fmod(s, 24.0), 0.3, 1.5);
    p.q_WB = Quaternion(Eigen::AngleAxisd(11.0 * s, Vector3::UnitZ()));
    return p;
  };
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

}  // namespace
