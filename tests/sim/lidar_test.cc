
#include "rotorguard/sim/lidar.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <set>

#include "room_fixture.h"
#include "rotorguard/core/error.h"
#include "test_util.h"

namespace rotorguard::sim {
namespace {

/// Fraction of equal-solid-angle cells of the field of view (2 degrees of azimuth by 1/60 of the
/// sine-of-elevation band) that the first n pulses visit.
double Coverage(std::uint64_t n, const LidarOptions& o) {
  const LidarPattern pattern(o);
  constexpr int kAz = 180, kEl = 60;
  std::vector<bool> seen(kAz * kEl, false);
  const double s0 = std::sin(o.min_elevation_rad), s1 = std::sin(o.max_elevation_rad);
  for (std::uint64_t k = 0; k < n; ++k) {
    const Vector3 d = pattern.Direction(k);
    const double az = std::atan2(d.y(), d.x()) + std::numbers::pi;
    const int a = std::min(kAz - 1, static_cast<int>(az / (2.0 * std::numbers::pi) * kAz));
    const int e = std::min(kEl - 1, static_cast<int>((d.z() - s0) / (s1 - s0) * kEl));
    seen[static_cast<std::size_t>(e * kAz + a)] = true;
  }
  return static_cast<double>(std::count(seen.begin(), seen.end(), true)) / seen.size();
}

TEST(LidarPattern, StaysInTheFieldOfViewAndCoversItMoreTheLongerItIntegrates) {
  const LidarOptions o;
  const LidarPattern pattern(o);
  for (std::uint64_t k = 0; k < 200000; ++k) {
    const Vector3 d = pattern.Direction(k);
    ASSERT_NEAR(d.norm(), 1.0, 1e-12);
    const double el = std::asin(d.z());
    ASSERT_GE(el, o.min_elevation_rad - 1e-12);
    ASSERT_LE(el, o.max_elevation_rad + 1e-12);
  }
  // 10 800 cells: 1 ms of pulses (200) covers under 2 %, one 10 Hz frame (20 000) nearly all.
  const double c1 = Coverage(200, o), c10 = Coverage(2000, o), c100 = Coverage(20000, o);
  EXPECT_LT(c1, 0.02);
  EXPECT_LT(c1, c10);
  EXPECT_LT(c10, c100);
  EXPECT_GT(c100, 0.95);
  // Non-repetitive: the second frame's directions are not the first's.
  std::set<std::pair<long, long>> first;
  for (std::uint64_t k = 0; k < 20000; ++k) {
    const Vector3 d = pattern.Direction(k);
    first.insert({std::lround(d.x() * 1e6), std::lround(d.y() * 1e6)});
  }
  int repeated = 0;
  for (std::uint64_t k = 20000; k < 40000; ++k) {
    const Vector3 d = pattern.Direction(k);
    repeated += first.count({std::lround(d.x() * 1e6), std::lround(d.y() * 1e6)}) > 0 ? 1 : 0;
  }
  EXPECT_EQ(repeated, 0);
}

/// Flies the sensor for `duration_s` with 1 ms steps along poses given by `pose_at(t)`; returns
/// the frames.
std::vector<LidarFrame> Fly(LidarSimulator* lidar, double duration_s, const std::function<BodyPose(double)>& pose_at) {
  std::vector<LidarFrame> frames;
  const TimeNs dt = 1'000'000;
  for (TimeNs t = 0; t < FromSeconds(duration_s); t += dt) {
    if (auto f = lidar->Step(t, pose_at(ToSeconds(t)), t + dt, pose_at(ToSeconds(t + dt)))) frames.push_back(std::move(*f));
  }
  return frames;
}

// Every point, put back in the world with the sensor's exact pose at its own time, lies on a
// surface of the room; with the frame-end pose instead, a vehicle spinning at 11 rad/s smears
// them (the distortion deskewing removes).
/// A noiseless sensor without dropouts: every point exactly where its pulse hit.
LidarOptions ExactLidar() {
  LidarOptions o;
  o.enabled = true;
  o.range_noise_m = 0.0;
  o.dropout_probability = 0.0;
  return o;
}

/// Drifting at 0.2 m/s, 1 m up, spinning at 11 rad/s.
BodyPose SpinningPose(double t) {
  BodyPose p;
  p.p_W = Vector3(0.2 * t, 0.0, 1.0);
  p.q_WB = Quaternion(Eigen::AngleAxisd(11.0 * t, Vector3::UnitZ()));
  return p;
}

TEST(LidarSimulator, PointsLieOnSurfacesFromTheirOwnPoseAndSmearFromTheFrameEnd) {
  const LidarOptions o = ExactLidar();
  const World room = rotorguard::testing::Room();
  LidarSimulator lidar(o, room, 3);
  const auto pose_at = SpinningPose;
  const std::vector<LidarFrame> frames = Fly(&lidar, 0.35, pose_at);
  ASSERT_EQ(frames.size(), 3u);
  for (const LidarFrame& f : frames) {
    EXPECT_EQ(f.t_end_ns - f.t_start_ns, 100'000'000);
    EXPECT_EQ(static_cast<int>(f.points_S.size()) + f.dropped, 20000) << "every pulse is a point or a drop";
    EXPECT_EQ(f.points_S.size(), f.offset_ns.size());
    double own_max = 0.0, end_mean = 0.0;
    const BodyPose end = pose_at(ToSeconds(f.t_end_ns));
    for (std::size_t i = 0; i < f.points_S.size(); ++i) {
      ASSERT_EQ(f.offset_ns[i], LidarOffsetAsOnTheWire(f.offset_ns[i])) << "stamped as the driver publishes";
      const BodyPose at = pose_at(ToSeconds(f.t_start_ns + f.offset_ns[i]));
      const Vector3 p_S = f.points_S[i].cast<double>();
      own_max = std::max(own_max, room.DistanceToSurface(at.p_W + at.q_WB * (o.position_m + p_S), 0.0));
      end_mean += room.DistanceToSurface(end.p_W + end.q_WB * (o.position_m + p_S), 0.0);
    }
    end_mean /= static_cast<double>(f.points_S.size());
    EXPECT_LT(own_max, 2e-4) << "float precision";
    EXPECT_GT(end_mean, 0.1) << "the spin distorts the frame";
  }
}

// A sensor mounted turned and with its clock off (the truth's draw, never told to the stack): each
// point lies on a surface when placed with the true mount rotation at its true capture time, and
// the frame's stamps are the capture times plus the offset. Placed as the stack would place it (no
// rotation, the stamps taken as capture times) it misses the surfaces.
TEST(LidarSimulator, ATurnedMountAndAnOffClockLeavePointsWhereOnlyTheTrueMountPlacesThem) {
  LidarOptions o = ExactLidar();
  o.rotation = Quaternion(Eigen::AngleAxisd(0.0087, Vector3(1, -1, 0.5).normalized()));
  o.clock_offset_s = 0.0017;
  const World room = rotorguard::testing::Room();
  LidarSimulator lidar(o, room, 3);
  const auto pose_at = SpinningPose;
  const std::vector<LidarFrame> frames = Fly(&lidar, 0.35, pose_at);
  ASSERT_EQ(frames.size(), 3u);
  const TimeNs offset = FromSeconds(o.clock_offset_s);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const LidarFrame& f = frames[k];
    EXPECT_EQ(f.t_start_ns, static_cast<TimeNs>(k) * 100'000'000 + offset);
    double true_max = 0.0, assumed_mean = 0.0;
    for (std::size_t i = 0; i < f.points_S.size(); ++i) {
      const TimeNs stamp = f.t_start_ns + f.offset_ns[i];
      const BodyPose at = pose_at(ToSeconds(stamp - offset)), assumed = pose_at(ToSeconds(stamp));
      const Vector3 p_S = f.points_S[i].cast<double>();
      true_max = std::max(true_max, room.DistanceToSurface(at.p_W + at.q_WB * (o.position_m + o.rotation * p_S), 0.0));
      assumed_mean += room.DistanceToSurface(assumed.p_W + assumed.q_WB * (o.position_m + p_S), 0.0);
    }
    assumed_mean /= static_cast<double>(f.points_S.size());
    EXPECT_LT(true_max, 2e-4) << "float precision";
    // 0.5° of mount and 1.7 ms at 11 rad/s (1.1°) put the room's points (2-4 m away) 1 cm off.
    EXPECT_GT(assumed_mean, 0.005);
  }
}

// Open sky over flat ground, the sensor 1 m up: only pulses steeper than asin(1 / 40 m) below the
// horizon meet the ground within the 40 m range; every other pulse is counted as dropped. Random
// dropouts remove their share.
TEST(LidarSimulator, CountsPulsesWithoutReturnAndDropouts) {
  LidarOptions o;
  o.enabled = true;
  o.range_noise_m = 0.0;
  o.dropout_probability = 0.0;
  const auto hover = [](double) {
    BodyPose p;
    p.p_W = Vector3(0, 0, 1.0 - 0.06);  // the sensor 1 m above the ground
    return p;
  };
  LidarSimulator clean(o, World{}, 1);
  const std::vector<LidarFrame> frames = Fly(&clean, 0.25, hover);
  ASSERT_EQ(frames.size(), 2u);
  const double s0 = std::sin(o.min_elevation_rad), s1 = std::sin(o.max_elevation_rad);
  const double below = (-s0 - 1.0 / o.max_range_m) / (s1 - s0);  // share with sin(el) < -1/40 (uniform in sin)
  EXPECT_NEAR(frames[0].points_S.size() / 20000.0, below, 0.005);
  for (const Eigen::Vector3f& p : frames[0].points_S) {
    ASSERT_LT(p.z(), 0.0f);
    ASSERT_LE(p.norm(), o.max_range_m + 1e-3);
  }
  o.dropout_probability = 0.3;
  LidarSimulator lossy(o, World{}, 1);
  const std::vector<LidarFrame> lossy_frames = Fly(&lossy, 0.25, hover);
  EXPECT_NEAR(lossy_frames[0].points_S.size() / 20000.0, below * 0.7, 0.01);
  EXPECT_EQ(static_cast<int>(lossy_frames[0].points_S.size()) + lossy_frames[0].dropped, 20000);
}

// Found by generating flights (tests/fuzz): 4.9e-324 points per second put the second pulse at
// +inf s, whose integer time came out negative, and the simulator never left its first step. Such
// rates are refused now; pulse times saturate as FromSeconds does (SaturatedNs, tested with RateTimer).
TEST(LidarOptions, APulseRateTooSlowToTimeIsRefused) {
  LidarOptions o;
  o.enabled = true;
  o.points_per_s = 4.9e-324;
  RG_EXPECT_THROW_WITH(o.Validate(), rotorguard::ValidationError, "points_per_s");
  EXPECT_THROW(LidarSimulator(o, World{}, 1), rotorguard::ValidationError);
  o.points_per_s = 1.0;
  EXPECT_NO_THROW(o.Validate());
}

TEST(LidarSimulator, RangeNoiseHasTheConfiguredSpread) {
  LidarOptions o;
  o.enabled = true;
  o.range_noise_m = 0.02;
  o.dropout_probability = 0.0;
  // Straight down onto the ground from 2 m: a pulse at elevation e measures 2 / sin(-e).
  LidarSimulator lidar(o, World{}, 7);
  const auto hover = [](double) {
    BodyPose p;
    p.p_W = Vector3(0, 0, 2.0 - 0.06);
    return p;
  };
  const std::vector<LidarFrame> frames = Fly(&lidar, 0.15, hover);
  ASSERT_FALSE(frames.empty());
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  for (const Eigen::Vector3f& pf : frames[0].points_S) {
    const Vector3 p = pf.cast<double>();
    const double truth = 2.0 / (-p.normalized().z());
    const double e = p.norm() - truth;
    sum += e;
    sum2 += e * e;
    ++n;
  }
  ASSERT_GT(n, 1000);
  EXPECT_NEAR(sum / n, 0.0, 0.002);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.02, 0.002);
}

TEST(LidarOptions, ValidationNamesTheField) {
  LidarOptions o;
  o.points_per_s = 0.0;
  try {
    o.Validate();
    ADD_FAILURE();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "points_per_s");
  }
  o = {};
  o.max_range_m = 0.05;
  EXPECT_THROW(o.Validate(), ValidationError);
}

}  // namespace
}  // namespace rotorguard::sim
