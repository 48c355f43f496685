#include "rotorguard/sim/battery.h"

#include <gtest/gtest.h>

#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/sim/simulator.h"
#include "vehicle_fixture.h"

namespace rotorguard::sim {
namespace {

TEST(Battery, ALipoCellRestsAtItsTablesVoltages) {
  EXPECT_DOUBLE_EQ(Battery::OpenCircuitVoltagePerCell(1.0), 4.20);
  EXPECT_DOUBLE_EQ(Battery::OpenCircuitVoltagePerCell(0.5), 3.84);
  EXPECT_DOUBLE_EQ(Battery::OpenCircuitVoltagePerCell(0.0), 3.27);
  EXPECT_NEAR(Battery::OpenCircuitVoltagePerCell(0.525), 0.5 * (3.84 + 3.85), 1e-12);  // linear between 5 % points
  EXPECT_DOUBLE_EQ(Battery::OpenCircuitVoltagePerCell(1.5), 4.20);
  EXPECT_DOUBLE_EQ(Battery::OpenCircuitVoltagePerCell(-0.1), 3.27);
  double previous = 0.0;
  for (double c = 0.0; c <= 1.0; c += 0.001) {
    ASSERT_GE(Battery::OpenCircuitVoltagePerCell(c), previous) << c;
    previous = Battery::OpenCircuitVoltagePerCell(c);
  }
}

// The rotors' electrical power P = sum kappa T w / eta through the internal resistance R: the
// terminal voltage V and current I satisfy V = E - I R and V I = P (Ohm's and Joule's laws).
TEST(Battery, TheTerminalVoltageAndCurrentDeliverTheRotorsPowerThroughTheResistance) {
  const vehicle::VehicleParams v = testing::ReferenceQuad();
  BatteryOptions o{.fitted = true, .cells = 4, .internal_resistance_ohm = 0.05, .initial_charge = 0.6, .efficiency = 0.8};
  Battery b(o, v);
  const double e = 4.0 * Battery::OpenCircuitVoltagePerCell(0.6);
  EXPECT_DOUBLE_EQ(b.voltage_v(), e) << "no load yet";
  RotorVector thrust(4), speed(4);
  thrust << 3.0, 3.0, 2.5, 2.5;
  speed << 1500.0, 1500.0, 1400.0, 1400.0;
  double p = 0.0;
  for (int i = 0; i < 4; ++i) p += v.rotors[i].yaw_coefficient_m * thrust[i] * speed[i];
  p /= 0.8;
  b.Step(thrust, speed, 0.0);
  EXPECT_NEAR(b.voltage_v() * b.current_a(), p, 1e-9);
  EXPECT_NEAR(e - b.current_a() * 0.05, b.voltage_v(), 1e-9);
  EXPECT_GT(b.current_a(), 5.0);
  // A load beyond what the pack can give (E^2 < 4 R P): it gives its most, at E / 2.
  b.Step(thrust * 100.0, speed * 10.0, 0.0);
  EXPECT_NEAR(b.voltage_v(), 0.5 * e, 1e-12);
  EXPECT_NEAR(b.current_a(), e / (2.0 * 0.05), 1e-9);
}

TEST(Battery, TheChargeFallsByTheCurrentsIntegralOverTheCapacity) {
  const vehicle::VehicleParams v = testing::ReferenceQuad();
  Battery b({.fitted = true, .capacity_mah = 1000.0, .internal_resistance_ohm = 0.02}, v);
  const RotorVector thrust = RotorVector::Constant(4, 2.8), speed = RotorVector::Constant(4, 1480.0);
  double coulombs = 0.0;
  for (int step = 0; step < 60000; ++step) {  // a minute at 1 kHz
    b.Step(thrust, speed, 0.001);
    coulombs += b.current_a() * 0.001;
  }
  EXPECT_NEAR(b.charge(), 1.0 - coulombs / 3600.0, 1e-9);  // 1000 mAh = 3600 C
  EXPECT_LT(b.charge(), 0.9);
  EXPECT_GT(b.charge(), 0.5);
}

TEST(Battery, TheRotorsLargestThrustScalesWithTheVoltageSquaredNeverAboveTheFiles) {
  const vehicle::VehicleParams v = testing::ReferenceQuad();
  Battery none({.fitted = false}, v);
  EXPECT_EQ(none.thrust_limit_ratio(), 1.0);
  Battery b({.fitted = true, .initial_charge = 0.3, .reference_voltage_v = 16.0}, v);
  const double e = 4.0 * Battery::OpenCircuitVoltagePerCell(0.3);
  EXPECT_NEAR(b.thrust_limit_ratio(), (e / 16.0) * (e / 16.0), 1e-12);
  Battery full({.fitted = true, .initial_charge = 1.0, .reference_voltage_v = 16.0}, v);
  EXPECT_EQ(full.thrust_limit_ratio(), 1.0) << "16.8 V at rest: the file's T_bar, not more";
}

// In the simulator, rotors commanded to their file's T_bar on a pack at 30 % give T_bar (V/V_ref)^2,
// V the pack's voltage under that load; the power module reports it at its rate.
TEST(Battery, InTheSimulatorASaggingPackCapsTheRotorsThrustAndIsReported) {
  const vehicle::MultirotorModel model(testing::ReferenceQuad());
  SimulatorOptions o;
  o.battery = {.fitted = true, .initial_charge = 0.3, .reference_voltage_v = 16.0, .rate_hz = 10.0};
  Simulator sim(model, {}, {}, o, 1, model.MakeState(Vector3(0, 0, 100), 0.0, model.HoverThrusts()));
  int messages = 0;
  double last_v = 0.0;
  for (int step = 0; step < 1000; ++step) {
    const SensorOutputs& out = sim.Step(RotorCommand{sim.time_ns(), model.max_thrust()});
    if (out.battery) {
      ++messages;
      last_v = out.battery->voltage_v;
      EXPECT_EQ(out.battery->voltage_v, sim.battery().voltage_v());
      EXPECT_EQ(out.battery->current_a, sim.battery().current_a());
    }
  }
  EXPECT_EQ(messages, 10);
  EXPECT_GT(last_v, 0.0);
  const double ratio = sim.battery().thrust_limit_ratio();
  EXPECT_LT(ratio, 0.85) << "a 4S pack at 30 % under full load sags well below 16 V";
  for (int i = 0; i < 4; ++i) {
    // The motors' lag (30 ms) has settled over the second: the thrust is the capped command.
    EXPECT_NEAR(sim.rotor_thrusts()[i], ratio * model.max_thrust()[i], 0.01 * model.max_thrust()[i]) << i;
  }
  EXPECT_LT(sim.battery().charge(), 0.3);
}

TEST(Battery, BadOptionsAreRejectedByTheirKey) {
  const vehicle::MultirotorModel model(testing::ReferenceQuad());
  SimulatorOptions o;
  o.battery.cells = 0;
  try {
    o.Validate(model.params());
    FAIL() << "a pack without cells was accepted";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "sim.battery.cells");
  }
}

}  // namespace
}  // namespace rotorguard::sim
