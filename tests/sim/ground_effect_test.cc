#include "rotorguard/sim/ground_effect.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/sim/simulator.h"
#include "vehicle_fixture.h"

namespace rotorguard::sim {
namespace {

using vehicle::StateIndex;
using vehicle::StateView;

constexpr double kRadius = 0.0635;  // a 5-inch propeller

vehicle::VehicleParams FiveInchQuad() {
  vehicle::VehicleParams p = testing::ReferenceQuad();
  p.propeller_radius_m = kRadius;
  return p;
}

/// A level state with the centre of gravity (and the hubs, which lie in its plane) at z.
vehicle::StateVector LevelAt(const vehicle::MultirotorModel& model, double z, const RotorVector& thrust) {
  return model.MakeState(Vector3(0.3, -0.2, z), 0.4, thrust);
}

TEST(GroundEffect, TheRatioIsCheesemanAndBennettsBoundedNearTheGround) {
  const vehicle::MultirotorModel model(FiveInchQuad());
  const GroundEffect nominal(model, {.strength = 1.0, .max_ratio = 1.5}, GroundPlane{});
  // 1 / (1 - (R/4z)^2): 16/15 at z = R, 64/63 at z = 2R.
  EXPECT_NEAR(nominal.Ratio(kRadius), 16.0 / 15.0, 1e-12);
  EXPECT_NEAR(nominal.Ratio(2.0 * kRadius), 64.0 / 63.0, 1e-12);
  EXPECT_LT(nominal.Ratio(1.0) - 1.0, 3e-4);
  const GroundEffect doubled(model, {.strength = 2.0, .max_ratio = 1.5}, GroundPlane{});
  EXPECT_NEAR(doubled.Ratio(kRadius), 8.0 / 7.0, 1e-12);
  // The bound is reached continuously and held down to the ground (and below it).
  const double z_bound = kRadius / 4.0 / std::sqrt(1.0 - 1.0 / 1.5);
  EXPECT_NEAR(nominal.Ratio(z_bound * (1.0 + 1e-9)), 1.5, 1e-6);
  EXPECT_DOUBLE_EQ(nominal.Ratio(0.5 * z_bound), 1.5);
  EXPECT_DOUBLE_EQ(nominal.Ratio(0.0), 1.5);
  EXPECT_DOUBLE_EQ(nominal.Ratio(-0.1), 1.5);
  double previous = 1.5;
  for (double z = 0.001; z < 1.0; z += 0.001) {
    const double r = nominal.Ratio(z);
    ASSERT_LE(r, previous + 1e-15) << "not decreasing with height at " << z;
    ASSERT_GE(r, 1.0);
    previous = r;
  }
  const GroundEffect none(model, {.strength = 0.0, .max_ratio = 1.5}, GroundPlane{});
  EXPECT_EQ(none.Ratio(0.01), 1.0);
}

TEST(GroundEffect, TheDefaultRadiusIsTheLargestPropellersThatDoNotOverlap) {
  vehicle::VehicleParams p = testing::ReferenceQuad();
  // Hubs at (+-a, +-a): the neighbours are 2a apart.
  EXPECT_NEAR(p.PropellerRadius(), std::abs(p.rotors[0].p_B.x()), 1e-12);
  p.propeller_radius_m = 0.1;
  EXPECT_EQ(p.PropellerRadius(), 0.1);
}

TEST(GroundEffect, ALevelVehicleGetsEachRotorsExtraThrustAlongItsAxis) {
  const vehicle::MultirotorModel model(FiveInchQuad());
  const double ground = -0.4, z = -0.33;  // hubs 7 cm above the ground
  const GroundEffect effect(model, {.strength = 1.0}, GroundPlane{.offset_m = ground});
  const RotorVector thrust = (RotorVector(4) << 2.0, 3.0, 2.5, 3.5).finished();
  vehicle::Disturbance d;
  effect.AddTo(LevelAt(model, z, thrust), vehicle::RotorFaults(4), &d);
  const double extra = effect.Ratio(z - ground) - 1.0;
  EXPECT_NEAR(extra, 1.0 / (1.0 - std::pow(kRadius / (4.0 * 0.07), 2)) - 1.0, 1e-12);
  EXPECT_TRUE(d.force_W.isApprox(Vector3(0, 0, extra * thrust.sum()), 1e-12));
  // Each rotor's extra thrust acts at its hub: the moment of the thrusts scaled by the ratio.
  Vector3 moment = Vector3::Zero();
  for (int i = 0; i < 4; ++i) moment += model.params().rotors[i].p_B.cross(Vector3(0, 0, extra * thrust[i]));
  EXPECT_TRUE(d.torque_B.isApprox(moment, 1e-12));
  EXPECT_GT(d.torque_B.norm(), 0.0);
}

TEST(GroundEffect, ATiltedVehicleNearTheGroundIsRightedItsLowerRotorsPushMore) {
  const vehicle::MultirotorModel model(FiveInchQuad());
  const GroundEffect effect(model, {.strength = 1.0}, GroundPlane{});
  vehicle::StateVector x = model.MakeState(Vector3(0, 0, 0.06), 0.0, model.HoverThrusts());
  for (const double roll : {0.2, -0.2}) {
    const Quaternion q(Eigen::AngleAxisd(roll, Vector3::UnitX()));
    x.segment<4>(StateIndex::kQuaternion) << q.w(), q.x(), q.y(), q.z();
    vehicle::Disturbance d;
    effect.AddTo(x, vehicle::RotorFaults(4), &d);
    // A positive roll lifts the +y rotors: the -y ones, nearer, push more and roll it back.
    EXPECT_LT(d.torque_B.x() * roll, 0.0) << "roll " << roll;
    EXPECT_NEAR(d.torque_B.y(), 0.0, 1e-12);
    // Closed form, rotor by rotor: its hub's height, its ratio, its moment.
    double torque_x = 0.0;
    for (int i = 0; i < 4; ++i) {
      const Vector3 p = model.params().rotors[i].p_B;
      const double h = 0.06 + p.y() * std::sin(roll) + p.z() * std::cos(roll);
      torque_x += p.y() * (effect.Ratio(h) - 1.0) * model.HoverThrusts()[i];
    }
    EXPECT_NEAR(d.torque_B.x(), torque_x, 1e-12);
  }
  // Upside down, the wakes blow away from the ground.
  const Quaternion flipped(Eigen::AngleAxisd(std::numbers::pi, Vector3::UnitX()));
  x.segment<4>(StateIndex::kQuaternion) << flipped.w(), flipped.x(), flipped.y(), flipped.z();
  vehicle::Disturbance d;
  effect.AddTo(x, vehicle::RotorFaults(4), &d);
  EXPECT_EQ(d.force_W, Vector3::Zero());
}

TEST(GroundEffect, ARotorWithoutItsPropellerGetsNone) {
  const vehicle::MultirotorModel model(FiveInchQuad());
  const GroundEffect effect(model, {.strength = 1.0}, GroundPlane{});
  const vehicle::StateVector x = LevelAt(model, 0.07, RotorVector::Constant(4, 3.0));
  vehicle::RotorFaults faults(4);
  vehicle::Disturbance healthy, lost;
  effect.AddTo(x, faults, &healthy);
  faults[0].kind = vehicle::FaultKind::kPropellerLoss;
  effect.AddTo(x, faults, &lost);
  EXPECT_NEAR(lost.force_W.z(), 0.75 * healthy.force_W.z(), 1e-12);
}

TEST(GroundEffect, OptionsOutOfRangeAreRejectedByKey) {
  const vehicle::MultirotorModel model(FiveInchQuad());
  try {
    GroundEffect(model, {.strength = 1.0, .max_ratio = 0.9}, GroundPlane{});
    FAIL() << "a ratio below 1 was accepted";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "max_ratio");
  }
  SimulatorOptions o;
  o.ground_effect.strength = -1.0;
  try {
    o.Validate(model.params());
    FAIL() << "a negative strength was accepted";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "sim.ground_effect.strength");
  }
}

// A vehicle whose rotors hold less than its weight sinks until the ground effect makes up the
// difference: with each rotor at T = m g / (4 k), it floats where 1 / (1 - (R/4h)^2) = k,
// h = R / (4 sqrt(1 - 1/k)), its feet clear of the ground. Without the effect, it lands.
TEST(GroundEffect, AVehicleHoldingLessThanItsWeightFloatsOnTheCushionWhereTheRatioMakesItUp) {
  const vehicle::MultirotorModel model(FiveInchQuad());
  constexpr double k = 1.05;
  const double hub_height = kRadius / (4.0 * std::sqrt(1.0 - 1.0 / k));
  const double ground = -model.params().RestingHeight();
  const double z_float = ground + hub_height;  // the hubs lie level with the centre of gravity
  ASSERT_GT(z_float - model.params().RestingHeight(), ground + 0.02) << "the feet would touch";
  RotorCommand command;
  command.thrust_n = model.HoverThrusts() / k;
  for (const double strength : {1.0, 0.0}) {
    SimulatorOptions o;
    o.ground_effect.strength = strength;
    Simulator sim(model, {}, {}, o, 1, model.MakeState(Vector3(0, 0, z_float + 0.01), 0.0, command.thrust_n));
    // Lightly damped (rotor drag alone, zeta ~ 0.08): 40 s are about 11 of its decay times.
    for (int step = 0; step < 40000; ++step) sim.Step(command);
    const StateView s(sim.state());
    ASSERT_FALSE(sim.crashed()) << *sim.crash_reason();
    if (strength > 0.0) {
      EXPECT_NEAR(s.p_W().z(), z_float, 1e-5);
      EXPECT_FALSE(sim.landed());
      EXPECT_LT(TiltOf(s.q_WB()), 1e-6);
    } else {
      EXPECT_TRUE(sim.landed());
    }
  }
}

}  // namespace
}  // namespace rotorguard::sim
