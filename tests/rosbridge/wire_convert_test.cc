// The stack's messages on the wire: quaternion order and frame conventions (REP-103/105) against
// hand-made poses, and the round trips a bag or a topic makes of each message.
#include "rotorguard/rosbridge/wire_convert.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace rotorguard::rosbridge {
namespace {

constexpr double kHalf = std::numbers::sqrt2 / 2.0;

// A body at (1, 2, 3) facing north (yaw +90 deg about the world's z up): q_WB = (cos 45, 0, 0,
// sin 45). ROS stores x, y, z, w; flying forward at 1 m/s in the body is north in the world, and
// nav_msgs/Odometry carries that velocity in the child frame (the body): (1, 0, 0).
TEST(WireConvert, AHandMadePoseHasRosOrderAndFrames) {
  StateEstimate e;
  e.t_ns = 2'000'000;
  e.p_W = {1.0, 2.0, 3.0};
  e.q_WB = Quaternion(Eigen::AngleAxisd(std::numbers::pi / 2.0, Vector3::UnitZ()));
  e.v_W = {0.0, 1.0, 0.0};  // north
  e.w_B = {0.0, 0.0, 0.5};  // yawing left
  const ros1::Odometry o = EstimateToWire(e, TimeBase{5'000'000'000});
  EXPECT_EQ(o.frame_id, "odom");
  EXPECT_EQ(o.child_frame_id, "base_link");
  EXPECT_EQ(o.stamp, 5'002'000'000);
  EXPECT_NEAR(o.pose.orientation_xyzw[0], 0.0, 1e-15);
  EXPECT_NEAR(o.pose.orientation_xyzw[1], 0.0, 1e-15);
  EXPECT_NEAR(o.pose.orientation_xyzw[2], kHalf, 1e-15);  // z
  EXPECT_NEAR(o.pose.orientation_xyzw[3], kHalf, 1e-15);  // w last
  EXPECT_NEAR(o.linear[0], 1.0, 1e-15);  // forward
  EXPECT_NEAR(o.linear[1], 0.0, 1e-15);
  EXPECT_EQ(o.angular, (ros1::Vec3{0.0, 0.0, 0.5}));
  const StateEstimate back = EstimateFromWire(o, TimeBase{5'000'000'000}, true);
  EXPECT_EQ(back.t_ns, e.t_ns);
  EXPECT_TRUE(back.p_W.isApprox(e.p_W));
  EXPECT_NEAR(back.q_WB.angularDistance(e.q_WB), 0.0, 1e-15);
  EXPECT_NEAR((back.v_W - e.v_W).norm(), 0.0, 1e-15);
}

// An IMU at rest, level: the accelerometer reads +g up (REP-145), in the IMU's frame.
TEST(WireConvert, AnImuAtRestReadsGravityUp) {
  ImuSample s;
  s.t_ns = 7;
  s.specific_force_B = {0.0, 0.0, 9.81};
  s.w_B = {0.01, -0.02, 0.03};
  const ros1::Imu m = ToWire(s, TimeBase{1'000'000'000});
  EXPECT_EQ(m.frame_id, "imu_link");
  EXPECT_EQ(m.linear_acceleration, (ros1::Vec3{0.0, 0.0, 9.81}));
  EXPECT_EQ(m.stamp, 1'000'000'007);
  const ImuSample back = FromWire(m, TimeBase{1'000'000'000});
  EXPECT_EQ(back.t_ns, 7);
  EXPECT_EQ(back.w_B, s.w_B);
}

// A LiDAR frame: stamped at its first instant, each point's time after it as float32 seconds
// (within 8 ns over a 0.1 s sweep); a point stamped outside the sweep is not the frame's.
TEST(WireConvert, AFrameRoundTripsWithinFloatTimeAndDropsPointsOutsideItsSweep) {
  LidarFrame f;
  f.t_start_ns = 300'000'000;
  f.t_end_ns = 400'000'000;
  for (int i = 0; i < 1000; ++i) {
    f.points_S.emplace_back(0.01f * static_cast<float>(i), -1.0f, 2.5f);
    f.offset_ns.push_back(static_cast<std::uint32_t>(i) * 99'901u);
  }
  const TimeBase base;
  ros1::Cloud c = ToWire(f, base);
  EXPECT_EQ(c.frame_id, "lidar_link");
  EXPECT_EQ(c.stamp, base.ToStamp(f.t_start_ns));
  c.points.push_back({1.0f, 1.0f, 1.0f, 0.0f, 0.2f, 0});  // after the sweep's end
  c.points.push_back({1.0f, 1.0f, 1.0f, 0.0f, -0.001f, 0});  // before its start
  const LidarFrame back = FromWire(c, base, 100'000'000);
  EXPECT_EQ(back.t_start_ns, f.t_start_ns);
  EXPECT_EQ(back.t_end_ns, f.t_end_ns);
  EXPECT_EQ(back.dropped, 2);
  ASSERT_EQ(back.points_S.size(), f.points_S.size());
  for (std::size_t i = 0; i < f.points_S.size(); ++i) {
    EXPECT_EQ(back.points_S[i], f.points_S[i]);
    EXPECT_NEAR(static_cast<double>(back.offset_ns[i]), static_cast<double>(f.offset_ns[i]), 8.0) << i;
  }
}

// The simulated sensor stamps its returns as the wire reads them back, so a recorded frame
// replays on exactly the times the live stack saw: every nanosecond offset of a 10 Hz frame
// (and of a 1 Hz one, in steps), taken to the wire's resolution, crosses the wire unchanged,
// and lies within half the float32 spacing (3.7 ns at 0.1 s) of where it was.
TEST(WireConvert, AnOffsetAtTheWiresResolutionCrossesItUnchanged) {
  const auto check = [](std::uint32_t o) {
    const std::uint32_t q = LidarOffsetAsOnTheWire(o);
    ASSERT_EQ(LidarOffsetFromSeconds32(LidarOffsetToSeconds32(q)), static_cast<double>(q)) << o;
    const double spacing = 1e9 * std::nextafter(LidarOffsetToSeconds32(o), 1.0f) - 1e9 * LidarOffsetToSeconds32(o);
    ASSERT_LE(std::abs(static_cast<double>(q) - static_cast<double>(o)), 0.5 * spacing + 0.5) << o;
  };
  for (std::uint32_t o = 0; o < 100'000'000u; ++o) check(o);
  for (std::uint32_t o = 100'000'000u; o < 1'000'000'000u; o += 997u) check(o);
}

TEST(WireConvert, ACycleRoundTrips) {
  runtime::CycleTelemetry c;
  c.command = {.cycle = 12, .state_t_ns = 1'500'000'000, .sent_t_ns = 1'500'400'000, .compute_s = 0.0004, .inputs = 321,
               .lio_serial = 9, .held = 0, .thrust_n = RotorVector::Constant(4, 2.5), .release_parachute = true};
  c.mode = stack::FlightMode::kFailureRecovery;
  c.estimate.t_ns = 1'500'000'000;
  c.estimate.valid = true;
  c.estimate.p_W = {1, 2, 3};
  c.reference.p_W = {4, 5, 6};
  c.reference.yaw_rate = 0.3;
  c.reference.s_W = {0.7, -0.1, 2.5};
  c.fdd_rotors = 4;
  c.health[0] = {fdd::RotorHealth::kPropellerFailed, 1.0f, 0.25f, 3.0f};
  const runtime::CycleTelemetry back = FromWire(ToWire(c, TimeBase{}), TimeBase{});
  EXPECT_EQ(back.command.cycle, 12u);
  EXPECT_EQ(back.command.state_t_ns, c.command.state_t_ns);
  EXPECT_EQ(back.command.sent_t_ns, c.command.sent_t_ns);
  EXPECT_EQ(back.command.inputs, 321u);
  EXPECT_EQ(back.command.lio_serial, 9u);
  EXPECT_EQ(back.command.thrust_n, c.command.thrust_n);
  EXPECT_TRUE(back.command.release_parachute);
  EXPECT_EQ(back.mode, stack::FlightMode::kFailureRecovery);
  EXPECT_TRUE(back.estimate.valid);
  EXPECT_EQ(back.estimate.p_W, c.estimate.p_W);
  EXPECT_EQ(back.reference.p_W, c.reference.p_W);
  EXPECT_EQ(back.reference.yaw_rate, 0.3);
  EXPECT_EQ(back.reference.s_W, c.reference.s_W);
  ASSERT_EQ(back.fdd_rotors, 4);
  EXPECT_EQ(back.health[0].health, fdd::RotorHealth::kPropellerFailed);
  EXPECT_EQ(back.health[0].motor_index, 0.25f);
  EXPECT_EQ(back.health[1].health, fdd::RotorHealth::kOk);
}

TEST(WireConvert, TelemetryOfMoreRotorsThanTheStackHoldsIsRefused) {
  ros1::Esc esc{1, std::vector<double>(kMaxRotors + 1, 100.0)};
  EXPECT_FALSE(FromWire(esc, TimeBase{}).has_value());
  esc.motor_speed_rad_s.resize(4);
  EXPECT_EQ(FromWire(esc, TimeBase{})->motor_speed_rad_s.size(), 4);
}

}  // namespace
}  // namespace rotorguard::rosbridge
