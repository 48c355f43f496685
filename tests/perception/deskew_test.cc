
#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

#include "rotorguard/perception/deskew.h"
#include "rotorguard/sim/lidar.h"
#include "room_fixture.h"

namespace rotorguard::perception {
namespace {

// With perfect estimates (exact gyro at 333 Hz, exact velocity and frame-end attitude) the
// deskewed points, placed with the frame-end pose, lie on the room's surfaces to float precision,
// for a spin of 11 rad/s with a tumble; without deskewing they are tens of centimetres off.
TEST(Deskew, IsExactWithPerfectEstimates) {
  sim::LidarOptions lo;
  lo.enabled = true;
  lo.range_noise_m = 0.0;
  lo.dropout_probability = 0.0;
  const sim::World room = rotorguard::testing::Room();
  sim::LidarSimulator lidar(lo, room, 2);
  const Vector3 w_B(0.8, -0.5, 11.0);  // constant body rate: R(t) = R0 Exp(w t)
  const Vector3 v_W(0.6, -0.3, 0.1);
  const Quaternion q0(Eigen::AngleAxisd(0.1, Vector3::UnitX()));
  const auto pose_at = [&](TimeNs t) {
    sim::BodyPose p;
    p.p_W = Vector3(-1.0, 0.0, 1.2) + v_W * ToSeconds(t);
    const Vector3 theta = w_B * ToSeconds(t);
    p.q_WB = q0 * Quaternion(Eigen::AngleAxisd(theta.norm(), theta.normalized()));
    return p;
  };
  DeskewOptions o;
  o.sensor_position_m = lo.position_m;
  Deskewer deskewer(o);
  const TimeNs imu_period = PeriodFromRate(333.0);
  TimeNs next_imu = 0;
  int frames = 0;
  for (TimeNs t = 0; t < 350'000'000; t += 1'000'000) {
    while (next_imu <= t) {
      deskewer.OnImu(ImuSample{next_imu, Vector3(0, 0, 9.81), w_B});
      next_imu += imu_period;
    }
    auto frame = lidar.Step(t, pose_at(t), t + 1'000'000, pose_at(t + 1'000'000));
    if (!frame) continue;
    ++frames;
    std::vector<Eigen::Vector3f> out;
    const sim::BodyPose end = pose_at(frame->t_end_ns);
    const DeskewSummary s = deskewer.Deskew(*frame, v_W, end.q_WB, &out);
    ASSERT_EQ(out.size(), frame->points_S.size());
    EXPECT_EQ(s.points, static_cast<int>(out.size()));
    double deskewed_max = 0.0, raw_mean = 0.0;
    for (std::size_t i = 0; i < out.size(); ++i) {
      deskewed_max = std::max(deskewed_max,
                              room.DistanceToSurface(end.p_W + end.q_WB * (o.sensor_position_m + out[i].cast<double>()), 0.0));
      raw_mean +=
          room.DistanceToSurface(end.p_W + end.q_WB * (o.sensor_position_m + frame->points_S[i].cast<double>()), 0.0);
    }
    raw_mean /= static_cast<double>(out.size());
    EXPECT_LT(deskewed_max, 5e-4) << "frame " << frames;
    EXPECT_GT(raw_mean, 0.1) << "frame " << frames;
  }
  EXPECT_EQ(frames, 3);
}

// A rate about body z only that changes at every gyro sample: the rotations commute, so a point's
// rotation to the frame's end is about z by the integral of the held rate, a closed form. Every
// point must find its own gyro segment, in time order and shuffled.
TEST(Deskew, PiecewiseConstantRatesMatchTheClosedFormInAnyPointOrder) {
  DeskewOptions o;
  o.sensor_position_m = Vector3(0.05, -0.02, 0.08);
  Deskewer d(o);
  const TimeNs period = 3'000'000;  // 333 Hz
  const auto rate = [](TimeNs i) { return 4.0 + 7.0 * static_cast<double>(i % 3) - 2.0 * static_cast<double>(i % 5); };
  for (TimeNs i = 0; i < 60; ++i) d.OnImu(ImuSample{i * period, Vector3(0, 0, 9.81), Vector3(0, 0, rate(i))});
  LidarFrame f;
  f.t_start_ns = 50'500'000;
  f.t_end_ns = 150'500'000;
  std::mt19937 gen(3);
  std::uniform_real_distribution<float> coordinate(-5.0f, 5.0f);
  for (std::uint32_t i = 0; i < 2000; ++i) {
    f.offset_ns.push_back(i * 50'000 + static_cast<std::uint32_t>(gen() % 50'000));  // increasing
    f.points_S.emplace_back(coordinate(gen), coordinate(gen), coordinate(gen));
  }
  // The angle turned from t to the frame's end, each sample's rate held until the next sample.
  const auto angle_to_end = [&](TimeNs t) {
    double angle = 0.0;
    for (TimeNs s = t; s < f.t_end_ns;) {
      const TimeNs i = s / period, next = std::min((i + 1) * period, f.t_end_ns);
      angle += rate(i) * ToSeconds(next - s);
      s = next;
    }
    return angle;
  };
  const auto expect_closed_form = [&](const LidarFrame& frame, const std::vector<Eigen::Vector3f>& out) {
    ASSERT_EQ(out.size(), frame.points_S.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
      const double angle = angle_to_end(frame.t_start_ns + frame.offset_ns[i]);
      // A world-fixed point seen from a body turned by +angle about z: Rz(-angle) in the end frame.
      const Vector3 expected =
          Eigen::AngleAxisd(-angle, Vector3::UnitZ()) * (o.sensor_position_m + frame.points_S[i].cast<double>()) -
          o.sensor_position_m;
      ASSERT_LT((out[i].cast<double>() - expected).norm(), 2e-5) << "point " << i;
    }
  };
  std::vector<Eigen::Vector3f> out;
  d.Deskew(f, Vector3::Zero(), Quaternion::Identity(), &out);
  expect_closed_form(f, out);
  std::vector<std::size_t> order(f.points_S.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), gen);
  LidarFrame shuffled = f;
  for (std::size_t i = 0; i < order.size(); ++i) {
    shuffled.points_S[i] = f.points_S[order[i]];
    shuffled.offset_ns[i] = f.offset_ns[order[i]];
  }
  d.Deskew(shuffled, Vector3::Zero(), Quaternion::Identity(), &out);
  expect_closed_form(shuffled, out);
}

// Bad points (non-finite) are skipped, an empty frame gives nothing, and without gyro samples the
// points are only translated.
TEST(Deskew, SkipsNonFinitePointsAndHandlesEmptyFrames) {
  Deskewer d(DeskewOptions{});
  LidarFrame f;
  f.t_start_ns = 0;
  f.t_end_ns = 100'000'000;
  std::vector<Eigen::Vector3f> out;
  EXPECT_EQ(d.Deskew(f, Vector3::Zero(), Quaternion::Identity(), &out).points, 0);
  EXPECT_TRUE(out.empty());
  f.points_S = {Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(std::nanf(""), 0, 0)};
  f.offset_ns = {0, 10};
  const DeskewSummary s = d.Deskew(f, Vector3(1, 0, 0), Quaternion::Identity(), &out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(s.points, 1);
  // Measured 0.1 s before the end while moving +1 m/s in x: 0.1 m further back.
  EXPECT_NEAR(out[0].x(), 0.9f, 1e-6f);
}

}  // namespace
}  // namespace rotorguard::perception
