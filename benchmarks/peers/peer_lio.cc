// peer_lio: rotorguard's LiDAR-inertial odometry beside KISS-ICP (LiDAR only) on the same frames of
// `rotorguard bench lio` (docs/performance.md): the forest and the room with a ceiling, hovering and
// flying 1 m/s, spinning at 0, 5, 11 and 20 rad/s, 20 s a condition, the simulated MID-360 and IMU.
//
//   peer_lio [--seed 1] [--duration 20]
//
// Each frame goes to rotorguard's Lio (inside the benchmark, with the IMU) and then to a KissICP of
// its own per condition, its points in the sensor frame with their times (KISS-ICP deskews them by
// its constant-velocity model to the frame's last point). KISS-ICP's configuration is its own
// defaults with the LiDAR's range: max_range 40 m (the sensor's), voxel_size max_range / 100 (KISS-
// ICP's rule when none is given), min_range 0, deskew on, one thread (the benchmark's one core).
// Both start at the true pose (KISS-ICP's at its first frame's last point). Scored per frame, after it: the position error of rotorguard's body
// estimate and of KISS-ICP's sensor pose (placed at the sensor's true first pose) against the
// truth; RMSE and largest over the frames; diverged when an error passes 1 m. Times: each frame's
// Lio::OnFrame and KissICP::RegisterFrame, medians. Prints one JSON object.
#include <kiss_icp/pipeline/KissICP.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "rotorguard/benchmarks/perception_bench.h"
#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/core/statistics.h"

namespace {

using namespace rotorguard;
using Clock = std::chrono::steady_clock;

struct Condition {
  std::unique_ptr<kiss_icp::pipeline::KissICP> kiss;
  Sophus::SE3d start;  // the sensor's true pose where KISS-ICP's first pose is
  std::vector<double> lio_error, kiss_error, lio_ms, kiss_ms;
};

double Rmse(const std::vector<double>& e) {
  double s = 0.0;
  for (double x : e) s += x * x;
  return e.empty() ? 0.0 : std::sqrt(s / static_cast<double>(e.size()));
}

constexpr const char* kUsage = "peer_lio [--seed S] [--duration SECONDS in (0, 600]]";

int Usage(const std::string& why) {
  std::fprintf(stderr, "peer_lio: %s\nusage: %s\n", why.c_str(), kUsage);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  benchmarks::LioBenchOptions options;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      std::printf("usage: %s\n", kUsage);
      return 0;
    }
    const std::string a = argv[i];
    if ((a == "--seed" || a == "--duration") && i + 1 < argc) {
      char* end = nullptr;
      const std::string v = argv[++i];
      if (a == "--seed") {
        options.seed = std::strtoull(v.c_str(), &end, 10);
        if (v.empty() || v[0] == '-' || *end != '\0') return Usage("--seed: expected an integer, got '" + v + "'");
      } else {
        options.duration_s = std::strtod(v.c_str(), &end);
        if (*end != '\0' || !(options.duration_s > 0.0 && options.duration_s <= 600.0)) {
          return Usage("--duration: expected seconds in (0, 600], got '" + v + "'");
        }
      }
    } else {
      return Usage("unknown argument '" + a + "'");
    }
  }
  kiss_icp::pipeline::KISSConfig config;
  config.max_range = sim::LidarOptions{}.max_range_m;
  config.voxel_size = config.max_range / 100.0;
  config.min_range = 0.0;
  config.deskew = true;
  config.max_num_threads = 1;

  std::map<std::tuple<std::string, std::string, double>, Condition> conditions;
  std::vector<std::tuple<std::string, std::string, double>> order;
  options.on_frame = [&](const benchmarks::LioFrameEvent& f) {
    const auto key = std::make_tuple(f.scene, f.motion, f.spin_rad_s);
    Condition& c = conditions[key];
    if (!c.kiss) {
      c.kiss = std::make_unique<kiss_icp::pipeline::KissICP>(config);
      // KISS-ICP's first pose is the identity at the first frame's last point: placed there.
      c.start = Sophus::SE3d(f.sensor_truth.q_WB.normalized(), f.sensor_truth.p_W);
      order.push_back(key);
    }
    std::vector<Eigen::Vector3d> points(f.frame.points_S.size());
    std::vector<double> times(f.frame.points_S.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      points[k] = f.frame.points_S[k].cast<double>();
      times[k] = 1e-9 * static_cast<double>(f.frame.offset_ns[k]);
    }
    const auto t0 = Clock::now();
    c.kiss->RegisterFrame(points, times);
    c.kiss_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    const Eigen::Vector3d kiss_p = (c.start * c.kiss->pose()).translation();
    const double kiss_error = (kiss_p - f.sensor_truth.p_W).norm();
    c.kiss_error.push_back(std::isfinite(kiss_error) ? kiss_error : 1e9);
    c.lio_error.push_back(f.lio_position_error_m.norm());
    c.lio_ms.push_back(f.lio_frame_ms);
  };
  benchmarks::RunLioBenchmark(options);

  nlohmann::json runs = nlohmann::json::array();
  for (const auto& key : order) {
    const Condition& c = conditions.at(key);
    const auto largest = [](const std::vector<double>& e) { return e.empty() ? 0.0 : *std::max_element(e.begin(), e.end()); };
    runs.push_back({{"scene", std::get<0>(key)},
                    {"motion", std::get<1>(key)},
                    {"spin_rad_s", std::get<2>(key)},
                    {"frames", c.lio_error.size()},
                    {"rotorguard_error_rmse_m", Rmse(c.lio_error)},
                    {"rotorguard_error_max_m", largest(c.lio_error)},
                    {"rotorguard_diverged", largest(c.lio_error) > 1.0},
                    {"rotorguard_frame_ms_median", Percentile(c.lio_ms, 0.5)},
                    {"kiss_icp_error_rmse_m", Rmse(c.kiss_error)},
                    {"kiss_icp_error_max_m", largest(c.kiss_error)},
                    {"kiss_icp_diverged", largest(c.kiss_error) > 1.0},
                    {"kiss_icp_frame_ms_median", Percentile(c.kiss_ms, 0.5)}});
  }
  const nlohmann::json out = {{"benchmark", "peer_lio"},
                              {"seed", options.seed},
                              {"duration_s", options.duration_s},
                              {"kiss_icp", {{"max_range", config.max_range}, {"voxel_size", config.voxel_size},
                                            {"min_range", config.min_range}, {"deskew", config.deskew},
                                            {"max_num_threads", config.max_num_threads}}},
                              {"host", buildinfo::HostInfo()},
                              {"runs", runs}};
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
