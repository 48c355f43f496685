
#include <type_traits>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/stack/flight_stack.h"
#include "test_util.h"
#include "vehicle_fixture.h"

namespace rotorguard::stack {
namespace {

using rotorguard::testing::ReferenceQuad;

std::shared_ptr<const ReferenceTrajectory> HoverAt(double z) {
  planning::HoverOptions o;
  o.position_m = Vector3(0, 0, z);
  return std::make_shared<planning::HoverReference>(o);
}

// The stack's inputs are sensor messages and nothing else: pin the signatures.
static_assert(std::is_same_v<decltype(&FlightStack::OnImu), void (FlightStack::*)(const ImuSample&)>);
static_assert(std::is_same_v<decltype(&FlightStack::OnEscTelemetry), void (FlightStack::*)(const EscTelemetry&)>);
static_assert(std::is_same_v<decltype(&FlightStack::OnOdometry), void (FlightStack::*)(const OdometrySample&)>);
static_assert(std::is_same_v<decltype(&FlightStack::OnBattery), void (FlightStack::*)(const BatteryStatus&)>);
static_assert(std::is_same_v<decltype(&FlightStack::Update), const RotorCommand& (FlightStack::*)(TimeNs)>);

TEST(FlightStack, IdlesUntilItHasSensorData) {
  FlightStack st(ReferenceQuad(), HoverAt(1.0), {});
  const RotorCommand& c = st.Update(0);
  EXPECT_EQ(c.thrust_n.size(), 4);
  EXPECT_EQ(c.thrust_n.norm(), 0.0);
  EXPECT_FALSE(st.estimate().valid);
}

TEST(FlightStack, HoldsHoverThrustAtTheReference) {
  FlightStack st(ReferenceQuad(), HoverAt(1.0), {});
  ImuSample imu;
  imu.specific_force_B = Vector3(0, 0, kGravity);
  OdometrySample odom;
  odom.p_W = Vector3(0, 0, 1.0);
  st.OnImu(imu);
  st.OnOdometry(odom);
  const RotorCommand& c = st.Update(0);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(c.thrust_n[i], 1.15 * kGravity / 4.0, 1e-9);
}

TEST(FlightStack, KeepsThePowerModulesNewestMessageAndReportsItsLowestVoltage) {
  FlightStack st(ReferenceQuad(), HoverAt(1.0), {});
  EXPECT_FALSE(st.battery());
  EXPECT_FALSE(st.Summarize().battery_min_voltage_v);
  st.OnBattery({100, 16.2, 12.0});
  st.OnBattery({200, 15.1, 30.0});
  st.OnBattery({300, std::nan(""), 10.0});  // a glitch: dropped, the last good one stays
  st.OnBattery({400, 15.6, 14.0});
  ASSERT_TRUE(st.battery());
  EXPECT_EQ(st.battery()->t_ns, 400);
  EXPECT_EQ(st.battery()->voltage_v, 15.6);
  EXPECT_EQ(st.Summarize().battery_min_voltage_v, 15.1);
}

TEST(FlightStack, CorruptSensorDataNeverReachesTheMotorsAsNan) {
  FlightStack st(ReferenceQuad(), HoverAt(1.0), {});
  ImuSample imu;
  OdometrySample odom;
  odom.p_W = Vector3(0, 0, 1.0);
  st.OnImu(imu);
  st.OnOdometry(odom);
  odom.p_W.x() = std::nan("");
  imu.w_B.z() = std::numeric_limits<double>::infinity();
  st.OnOdometry(odom);
  st.OnImu(imu);
  const RotorCommand& c = st.Update(5'000'000);
  EXPECT_TRUE(c.thrust_n.allFinite());
  EXPECT_TRUE(st.estimate().p_W.allFinite());  // the corrupt sample was dropped
}

TEST(FlightStack, RejectsAHandedInControllerOfAnotherKind) {
  FlightStackOptions o;
  o.controller = ControllerKind::kNmpc;
  const vehicle::MultirotorModel model(ReferenceQuad());
  RG_EXPECT_THROW_WITH(
      FlightStack(ReferenceQuad(), HoverAt(1.0), o, std::make_unique<control::NominalController>(model, o.nominal)),
      ValidationError, "controller = nmpc");
  o.controller = ControllerKind::kAssembly;  // built by its module: the stack cannot make it
  RG_EXPECT_THROW_WITH(FlightStack(ReferenceQuad(), HoverAt(1.0), o), ValidationError, "controller = assembly");
}

// Every kind's name is written once and reads back to the same kind.
TEST(FlightStack, KindNamesRoundTrip) {
  for (const auto& n : EnumNames<ControllerKind>()) EXPECT_EQ(FromName<ControllerKind>(n.name), n.value);
  for (const auto& n : EnumNames<FddKind>()) EXPECT_EQ(FromName<FddKind>(n.name), n.value);
  for (const auto& n : EnumNames<NavigationMethod>()) EXPECT_EQ(FromName<NavigationMethod>(n.name), n.value);
  EXPECT_EQ(EnumNames<ControllerKind>().size(), 6u);
  EXPECT_STREQ(ToName(FddKind::kFixedTime), "fixedtime");
  EXPECT_FALSE(FromName<ControllerKind>("magic").has_value());
}

}  // namespace
}  // namespace rotorguard::stack
