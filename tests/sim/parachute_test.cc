#include "rotorguard/sim/parachute.h"

#include <gtest/gtest.h>

#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/sim/simulator.h"
#include "vehicle_fixture.h"

namespace rotorguard::sim {
namespace {

using vehicle::StateView;

TEST(Parachute, TheCanopyFillsWithTheSquareOfTimeAfterItsEjection) {
  Parachute p({.fitted = true, .ejection_delay_s = 0.1, .inflation_time_s = 0.4, .drag_area_m2 = 0.8});
  EXPECT_EQ(p.DragAreaAt(FromSeconds(5.0)), 0.0) << "not released";
  p.Release(FromSeconds(1.0));
  p.Release(FromSeconds(2.0));  // a later release changes nothing
  ASSERT_TRUE(p.released_ns());
  EXPECT_EQ(*p.released_ns(), FromSeconds(1.0));
  EXPECT_EQ(p.DragAreaAt(FromSeconds(1.05)), 0.0) << "still in its container";
  EXPECT_NEAR(p.DragAreaAt(FromSeconds(1.3)), 0.8 * 0.25, 1e-12) << "half the filling time: a quarter";
  EXPECT_NEAR(p.DragAreaAt(FromSeconds(1.5)), 0.8, 1e-12);
  EXPECT_NEAR(p.DragAreaAt(FromSeconds(9.0)), 0.8, 1e-12);
  // None fitted: the release is recorded, nothing drags.
  Parachute none({.fitted = false});
  none.Release(FromSeconds(0.5));
  EXPECT_TRUE(none.released_ns());
  EXPECT_EQ(none.DragAreaAt(FromSeconds(3.0)), 0.0);
}

TEST(Parachute, ItsDragOpposesTheAirspeedWithItsSquare) {
  const vehicle::MultirotorModel model(testing::ReferenceQuad());
  Parachute p({.fitted = true, .ejection_delay_s = 0.0, .inflation_time_s = 0.0, .drag_area_m2 = 1.0, .air_density_kg_m3 = 1.2});
  p.Release(0);
  p.Update(0);
  vehicle::StateVector x = model.MakeState(Vector3(0, 0, 10), 0.0, RotorVector::Zero(4));
  x.segment<3>(vehicle::StateIndex::kVelocity) = Vector3(1.0, 0.0, -4.0);
  vehicle::Disturbance d;
  d.wind_W = Vector3(1.0, 0.0, 0.0);  // the air moves with the vehicle sideways: the airspeed is (0, 0, -4)
  p.AddTo(x, &d);
  EXPECT_NEAR(d.force_W.x(), 0.0, 1e-12);
  EXPECT_NEAR(d.force_W.y(), 0.0, 1e-12);
  EXPECT_NEAR(d.force_W.z(), 0.5 * 1.2 * 1.0 * 16.0, 1e-12);
  EXPECT_EQ(d.torque_B, Vector3::Zero());
}

// Motors stopped, the canopy open from the release on, no other drag: a fall from rest in still
// air follows v(t) = v_t tanh(g t / v_t), v_t = sqrt(2 m g / (rho C_D S)); in a wind, the vehicle
// ends up drifting with it at the same v_t.
TEST(Parachute, AFallUnderTheOpenCanopyFollowsTheClosedFormAndDriftsWithTheWind) {
  vehicle::VehicleParams v = testing::ReferenceQuad();
  v.rotor_drag_kg_s = Vector3::Zero();
  const vehicle::MultirotorModel model(v);
  const double v_t = std::sqrt(2.0 * v.mass_kg * kGravity / (1.225 * 0.9));
  const RotorVector off = RotorVector::Zero(4);
  for (const double wind : {0.0, 2.0}) {
    SimulatorOptions o;
    o.parachute = {.fitted = true, .ejection_delay_s = 0.0, .inflation_time_s = 0.0, .drag_area_m2 = 0.9};
    o.wind.mean_m_s = Vector3(wind, 0.0, 0.0);
    Simulator sim(model, {}, {}, o, 1, model.MakeState(Vector3(0, 0, 200), 0.0, off));
    for (int step = 1; step <= 8000; ++step) {
      sim.Step(RotorCommand{sim.time_ns(), off, true});
      if (wind == 0.0 && step % 500 == 0) {
        const double t = sim.time_s();
        ASSERT_FALSE(sim.crashed()) << *sim.crash_reason();
        EXPECT_NEAR(StateView(sim.state()).v_W().z(), -v_t * std::tanh(kGravity * t / v_t), 1e-6) << "t = " << t;
      }
    }
    EXPECT_NEAR(StateView(sim.state()).v_W().x(), wind, 1e-3) << "drifting with the wind";
    EXPECT_NEAR(StateView(sim.state()).v_W().z(), -v_t, 1e-3);
    EXPECT_EQ(*sim.parachute().released_ns(), 0);
  }
}

TEST(Parachute, TheReleaseActsWithTheCommandCarryingItAfterTheEscsLatency) {
  const vehicle::MultirotorModel model(testing::ReferenceQuad());
  SimulatorOptions o;
  o.esc.command_latency_s = 0.0125;  // between two physics steps
  o.parachute.fitted = true;
  Simulator sim(model, {}, {}, o, 1, model.MakeState(Vector3(0, 0, 2), 0.0, model.HoverThrusts()));
  for (int step = 0; step < 100; ++step) sim.Step(RotorCommand{sim.time_ns(), model.HoverThrusts(), false});
  EXPECT_FALSE(sim.parachute().released_ns());
  const TimeNs sent = sim.time_ns();
  for (int step = 0; step < 30; ++step) sim.Step(RotorCommand{sim.time_ns(), RotorVector::Zero(4), true});
  ASSERT_TRUE(sim.parachute().released_ns());
  EXPECT_EQ(*sim.parachute().released_ns(), sent + FromSeconds(0.0125));
}

TEST(Parachute, BadOptionsAreRejectedByTheirKey) {
  const vehicle::MultirotorModel model(testing::ReferenceQuad());
  SimulatorOptions o;
  o.parachute.drag_area_m2 = 0.0;
  try {
    o.Validate(model.params());
    FAIL() << "a canopy without drag area was accepted";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "sim.parachute.drag_area_m2");
  }
}

}  // namespace
}  // namespace rotorguard::sim
