
#include <gtest/gtest.h>

#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/vehicle/vehicle_params.h"
#include "vehicle_fixture.h"

namespace rotorguard::sim {
namespace {

using rotorguard::testing::ReferenceQuad;
using vehicle::FaultKind;
using vehicle::StateView;

struct Rig {
  explicit Rig(std::vector<FaultSpec> faults = {}, double z = 2.0, std::uint64_t seed = 1, World world = {})
      : model(ReferenceQuad()),
        sim(model, std::move(world), std::move(faults), SimulatorOptions{}, seed,
            model.MakeState(Vector3(0, 0, z), 0.0, z > 0 ? model.HoverThrusts() : RotorVector::Zero(4))) {
    hover.thrust_n = model.HoverThrusts();
  }
  /// Steps for `seconds` holding `command`, keeping the latest telemetry.
  void Run(double seconds, const RotorCommand& command) {
    const auto steps = std::llround(seconds / ToSeconds(sim.step_ns()));
    for (long long k = 0; k < steps; ++k) {
      const SensorOutputs& o = sim.Step(command);
      if (o.esc) esc = *o.esc;
      if (o.imu) imu = *o.imu;
    }
  }
  vehicle::MultirotorModel model;
  Simulator sim;
  RotorCommand hover;
  EscTelemetry esc;
  ImuSample imu;
};

FaultSpec AtTime(int rotor, FaultKind kind, double t) {
  FaultSpec s;
  s.rotor = rotor;
  s.kind = kind;
  s.onset = {FaultOnset::Kind::kAtTime, t};
  return s;
}

TEST(Simulator, SameSeedGivesIdenticalSensorStreamsDifferentSeedsDiffer) {
  Rig a({}, 2.0, 42), b({}, 2.0, 42), c({}, 2.0, 43);
  bool any_difference = false;
  for (int k = 0; k < 2000; ++k) {
    const SensorOutputs oa = a.sim.Step(a.hover), ob = b.sim.Step(b.hover), oc = c.sim.Step(c.hover);
    ASSERT_EQ(oa.imu.has_value(), ob.imu.has_value());
    if (oa.imu) {
      ASSERT_EQ(oa.imu->specific_force_B, ob.imu->specific_force_B) << "step " << k;
      ASSERT_EQ(oa.imu->w_B, ob.imu->w_B);
      any_difference = any_difference || oa.imu->w_B != oc.imu->w_B;
    }
    if (oa.odometry) {
      ASSERT_EQ(oa.odometry->p_W, ob.odometry->p_W);
    }
  }
  EXPECT_EQ(a.sim.state(), b.sim.state());
  EXPECT_TRUE(any_difference);
}

TEST(Simulator, PropellerLossKeepsTelemetryHighWithZeroThrust) {
  Rig rig({AtTime(0, FaultKind::kPropellerLoss, 0.1)});
  rig.Run(0.3, rig.hover);
  EXPECT_EQ(rig.sim.rotor_thrusts()[0], 0.0);
  // Telemetry: the unloaded motor reads ~10 % above the loaded ones (noise 20 rpm, 10 rpm steps).
  const double ratio = rig.esc.motor_speed_rad_s[0] / rig.esc.motor_speed_rad_s[2];
  EXPECT_NEAR(ratio, 1.1, 0.01);
}

TEST(Simulator, MotorStopCollapsesTelemetry) {
  Rig rig({AtTime(1, FaultKind::kMotorStop, 0.1)});
  rig.Run(0.14, rig.hover);  // 40 ms after onset, telemetry 1 ms old
  EXPECT_LT(rig.esc.motor_speed_rad_s[1], 0.2 * rig.esc.motor_speed_rad_s[0]);
  EXPECT_LT(rig.sim.rotor_thrusts()[1], 0.01 * rig.sim.rotor_thrusts()[0]);
}

TEST(Simulator, RestsOnTheGroundReadingGravityUntilThrustExceedsWeight) {
  Rig rig({}, 0.0);
  RotorCommand idle;
  idle.thrust_n = RotorVector::Constant(4, 1.0);
  rig.Run(1.0, idle);
  EXPECT_TRUE(rig.sim.landed());
  EXPECT_EQ(rig.sim.contact().points_in_contact(), 4);
  // On its feet: the centre of gravity at z = 0, sunk by the feet's springs under the weight
  // left over by the idle thrust, raised by the ground effect at the hubs' height (Hooke), and still.
  const double hub_height = StateView(rig.sim.state()).p_W().z() + rig.model.params().RestingHeight();
  const double pressing = rig.model.params().weight_n() - 4.0 * rig.sim.ground_effect().Ratio(hub_height);
  EXPECT_NEAR(StateView(rig.sim.state()).p_W().z(), -pressing / (4.0 * rig.sim.contact().point_stiffness_n_m()), 1e-6);
  EXPECT_LT(StateView(rig.sim.state()).v_W().norm(), 1e-6);
  EXPECT_NEAR(rig.imu.specific_force_B.z(), kGravity, 0.3);  // noise and bias
  RotorCommand climb;
  climb.thrust_n = RotorVector::Constant(4, 4.0);
  rig.Run(1.0, climb);
  EXPECT_FALSE(rig.sim.landed());
  EXPECT_GT(StateView(rig.sim.state()).p_W().z(), 0.5);
  EXPECT_FALSE(rig.sim.crashed());
}

TEST(Simulator, AStartOnTheGroundStandsOnTheFeetWhereverTheDrawnCentreOfGravityPutsThem) {
  // The file's feet 5 cm below its body origin put the ground at z = -0.05; a truth whose centre
  // of gravity sits 1 cm lower has its feet 4 cm below it. Started at z = 0, it stands on the
  // ground (1 cm lower, sunk by its weight), not 1 cm above it waiting to drop.
  vehicle::VehicleParams truth = ReferenceQuad();
  truth.landing_gear_B = {{0.05, 0.05, -0.04}, {0.05, -0.05, -0.04}, {-0.05, 0.05, -0.04}, {-0.05, -0.05, -0.04}};
  const vehicle::MultirotorModel model(truth);
  SimulatorOptions options;
  options.ground_z_m = -0.05;
  Simulator sim(model, World{}, {}, options, 1, model.MakeState(Vector3::Zero(), 0.0, RotorVector::Zero(4)));
  const double sink = truth.weight_n() / (4.0 * sim.contact().point_stiffness_n_m());
  EXPECT_TRUE(sim.landed());
  EXPECT_NEAR(StateView(sim.state()).p_W().z(), -0.01 - sink, 1e-12);
  RotorCommand off;
  off.thrust_n = RotorVector::Zero(4);
  for (int k = 0; k < 200; ++k) sim.Step(off);
  EXPECT_NEAR(StateView(sim.state()).p_W().z(), -0.01 - sink, 1e-6);
  EXPECT_LT(StateView(sim.state()).v_W().norm(), 1e-6);
}

TEST(Simulator, AVehicleThatLosesARotorAtLiftOffTipsOverTheFeetUnderIt) {
  // Spun up to lift off, propeller 0 (front right) gone: the ground no longer holds the vehicle
  // level. The thrust of the other three turns it about the feet under the lost rotor, which stay
  // on the ground while the opposite ones rise, until it tips over (a crash: the propellers strike).
  sim::FaultSpec loss;
  loss.rotor = 0;
  loss.kind = vehicle::FaultKind::kPropellerLoss;
  loss.onset = {FaultOnset::Kind::kAtTime, 0.0};
  Rig rig({loss}, 0.0);
  RotorCommand lift;
  lift.thrust_n = RotorVector::Constant(4, 0.3 * rig.model.params().weight_n());
  bool pivoted = false;
  for (int k = 0; k < 2000 && !rig.sim.crashed(); ++k) {
    rig.sim.Step(lift);
    const vehicle::StateView s(rig.sim.state());
    // Pivoting: tilted, with the feet of the lost rotor's side still touching and not all four.
    const Vector3 hub_W = s.q_WB() * rig.model.params().rotors[0].p_B + s.p_W();
    if (TiltOf(s.q_WB()) > 0.1 && rig.sim.contact().points_in_contact() > 0 &&
        rig.sim.contact().points_in_contact() < 4 && hub_W.z() < s.p_W().z()) {
      pivoted = true;
    }
  }
  EXPECT_TRUE(pivoted);
  ASSERT_TRUE(rig.sim.crashed());
  EXPECT_NE(rig.sim.crash_reason()->find("tilted"), std::string::npos);
}

TEST(Simulator, FallingOntoTheGroundIsACrash) {
  Rig rig({}, 5.0);
  RotorCommand off;
  off.thrust_n = RotorVector::Zero(4);
  rig.Run(3.0, off);
  ASSERT_TRUE(rig.sim.crashed());
  EXPECT_NE(rig.sim.crash_reason()->find("ground impact"), std::string::npos);
  EXPECT_LT(rig.sim.time_s(), 1.2);  // ~1 s to fall 5 m; the simulator stops there
}

TEST(Simulator, FlyingIntoABoxIsACollision) {
  World w;
  w.boxes.push_back(Box{Vector3(0, 0, 3.0), Vector3(2, 2, 0.5), 0.0});
  Rig rig({}, 2.0, 1, w);
  RotorCommand up;
  up.thrust_n = RotorVector::Constant(4, 4.0);
  rig.Run(2.0, up);
  ASSERT_TRUE(rig.sim.crashed());
  EXPECT_EQ(*rig.sim.crash_reason(), "collision with box 0");
}

/// A body made of two spheres 0.8 m apart (an assembly's footprint) hovering beside a box that
/// lies inside the bounding sphere but clear of both spheres: no collision; the same box under
/// one of the spheres is one.
TEST(Simulator, CollisionSpheresAreTheBodysShape) {
  vehicle::VehicleParams p = ReferenceQuad();
  p.collision_radius_m = 0.6;
  p.collision_spheres = {{Vector3(0.4, 0.0, 0.0), 0.15}, {Vector3(-0.4, 0.0, 0.0), 0.15}};
  const auto hover_beside = [&](const Vector3& box_centre) {
    World w;
    w.boxes.push_back(Box{box_centre, Vector3(0.1, 0.1, 0.1), 0.0});
    vehicle::MultirotorModel model(p);
    Simulator sim(model, std::move(w), {}, SimulatorOptions{}, 1,
                  model.MakeState(Vector3(0, 0, 2.0), 0.0, model.HoverThrusts()));
    RotorCommand hover;
    hover.thrust_n = model.HoverThrusts();
    for (int k = 0; k < 100; ++k) sim.Step(hover);
    return sim.crashed();
  };
  // 0.35 m beside the centre: within the 0.6 m bounding sphere, 0.48 m from either sphere's centre.
  EXPECT_FALSE(hover_beside(Vector3(0.0, 0.35, 2.0)));
  // Under the sphere at x = 0.4: its 0.15 m reach touches the box's top face 0.1 m below.
  EXPECT_TRUE(hover_beside(Vector3(0.4, 0.0, 1.85)));
  p.collision_spheres[1].radius_m = 0.3;  // beyond the bounding sphere: invalid
  EXPECT_THROW(p.Validate(), ValidationError);
}

TEST(Simulator, NonFiniteCommandsReachTheMotorsAsZero) {
  Rig rig({}, 2.0);
  RotorCommand bad = rig.hover;
  bad.thrust_n[2] = std::nan("");
  rig.sim.Step(bad);
  EXPECT_EQ(rig.sim.applied_command()[2], 0.0);
  EXPECT_TRUE(rig.sim.state().allFinite());
}

// A command acts from its own instant, the sending time plus the ESCs' latency, inside a physics
// step: a motor's thrust then follows eq. (6)'s lag from that instant, T(t) = u + (T0 - u)
// exp(-(t - t_a) / σ). Rounding the instant to the 1 ms step would move the curve by up to 1 ms,
// a thrust error of (u - T0) dt / σ: 0.1 N here, far above the tolerance.
TEST(Simulator, ACommandActsFromItsOwnInstantWithinAStep) {
  const vehicle::MultirotorModel model(ReferenceQuad());
  SimulatorOptions o;
  o.esc.command_latency_s = 0.00137;
  const RotorVector hover = model.HoverThrusts();
  Simulator sim(model, {}, {}, o, 1, model.MakeState(Vector3(0, 0, 2), 0.0, hover));
  RotorCommand up;
  up.thrust_n = hover + RotorVector::Constant(4, 1.0);
  const TimeNs sent = 400'000;  // 0.4 ms into the first step
  sim.Send(up, sent);
  const double t_acts = ToSeconds(sent) + o.esc.command_latency_s;  // inside the second step
  const double sigma = model.params().motor_time_constant_s;
  for (int k = 0; k < 20; ++k) {
    sim.Step();
    const double t = sim.time_s();
    const double expected = t <= t_acts ? hover[0] : up.thrust_n[0] + (hover[0] - up.thrust_n[0]) * std::exp(-(t - t_acts) / sigma);
    // RK4 on the motors' linear lag with (dt / σ)^5 / 120 ~ 3e-10 of relative error per step.
    EXPECT_NEAR(sim.rotor_thrusts()[0], expected, 1e-8) << "t = " << t;
  }
  EXPECT_EQ(sim.applied_command()[0], up.thrust_n[0]);
}

// Commands act in the order sent: one sent before the instant of one still waiting acts after it,
// and a full queue lets its oldest act at once (counted), so that nothing waits unboundedly.
TEST(Simulator, CommandsActInTheOrderSentAndAFullQueueIsCounted) {
  const vehicle::MultirotorModel model(ReferenceQuad());
  SimulatorOptions o;
  o.esc.command_latency_s = 0.002;
  Simulator sim(model, {}, {}, o, 1, model.MakeState(Vector3(0, 0, 2), 0.0, model.HoverThrusts()));
  RotorCommand a, b;
  a.thrust_n = RotorVector::Constant(4, 1.0);
  b.thrust_n = RotorVector::Constant(4, 2.0);
  sim.Send(a, 1'000'000);  // acts at 3 ms
  sim.Send(b, 500'000);    // would act at 2.5 ms; waits for a
  sim.Step();
  sim.Step();
  EXPECT_NE(sim.applied_command()[0], 1.0);  // at 2 ms neither acts yet
  sim.Step();
  EXPECT_EQ(sim.applied_command()[0], 2.0) << "a acted at 3 ms, then b at once";
  EXPECT_THROW(sim.Send(a, 0), std::invalid_argument) << "a command cannot be sent in the past";
  for (int k = 0; k < Simulator::kCommandQueue + 3; ++k) sim.Send(k % 2 ? a : b, sim.time_ns());
  EXPECT_EQ(sim.commands_overrun(), 3u);
}

TEST(Simulator, RejectsAStepTooLongForTheMotors) {
  SimulatorOptions o;
  o.physics_rate_hz = 100.0;  // 10 ms > half the 5 ms stop time constant
  const vehicle::MultirotorModel model(ReferenceQuad());
  const vehicle::StateVector x0 = model.MakeState(Vector3(0, 0, 1), 0, model.HoverThrusts());
  EXPECT_THROW(Simulator(model, {}, {}, o, 1, x0), rotorguard::ValidationError);
}

}  // namespace
}  // namespace rotorguard::sim
