// Paper 004's UKF fault estimation on a closed-loop flight of the Qball-X4-like vehicle: the full
// nonlinear model (motor lag, rotor drag) flown by the LQR baseline, with IMU noise; the truth is
// the loss injected into the model.

#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/control/lqr.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/fdd/ukf_fdd.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/vehicle/multirotor.h"
#include "rotorguard/vehicle/pwm_model.h"
#include "vehicle_fixture.h"

namespace rotorguard::fdd {
namespace {

struct Outcome {
  Eigen::VectorXd loss;
  std::optional<double> detected_s;
  int detected_rotor = -1;
  double max_healthy_loss = 0.0;  ///< largest ŵ of a healthy rotor after the first second
  bool settled = false;
};

/// Hovers 1 m up for `seconds`; rotor `faulty` (or none when < 0) loses `w` at `onset_s`.
Outcome Fly(int faulty, double w, double onset_s, double seconds, std::uint64_t seed) {
  const vehicle::VehicleParams vp = ::rotorguard::testing::QballX4();
  const vehicle::MultirotorModel model(vp);
  control::LqrController lqr(vehicle::PwmQuadModel::FromVehicle(vp), control::LqrControllerOptions{});
  UkfFdd fdd(vp, UkfFddOptions{});
  planning::HoverOptions hover;
  hover.position_m = Vector3(0, 0, 1);
  const planning::HoverReference ref(hover);
  vehicle::StateVector x = model.MakeState(hover.position_m, 0.0, model.HoverThrusts());
  vehicle::Rk4Integrator rk4(model);
  vehicle::RotorFaults faults(4);
  RotorVector u = model.HoverThrusts();
  Rng rng(seed);
  Outcome out;
  vehicle::StateVector x_dot(x.size());
  for (int k = 0; k * 1e-3 < seconds; ++k) {
    const double t = k * 1e-3;
    if (faulty >= 0 && t >= onset_s) {
      faults[faulty].kind = vehicle::FaultKind::kLossOfEffectiveness;
      faults[faulty].eta = w;
    }
    const vehicle::StateView s(x);
    if (k % 3 == 0) {  // IMU at 333 Hz: specific force R'(a + g e_z), white noise of the simulator's order
      model.Derivative(x, u, faults, vehicle::Disturbance{}, &x_dot);
      const Vector3 a_W = x_dot.segment<3>(vehicle::StateIndex::kVelocity);
      ImuSample imu;
      imu.t_ns = FromSeconds(t);
      imu.specific_force_B = s.q_WB().conjugate() * (a_W + Vector3(0, 0, kGravity));
      imu.w_B = s.w_B();
      for (int i = 0; i < 3; ++i) {
        imu.specific_force_B[i] += 0.04 * rng.Normal();
        imu.w_B[i] += 0.003 * rng.Normal();
      }
      fdd.OnImu(imu);
    }
    if (k % 5 == 0) {  // estimate and control at 200 Hz
      const StateEstimate e = rotorguard::testing::ExactEstimate(x, FromSeconds(t));
      fdd.SetEstimate(e);
      lqr.Compute(e, ref, t, 0.005, &u);
      fdd.SetCommand(RotorCommand{FromSeconds(t), u});
    }
    rk4.Step(u, faults, vehicle::Disturbance{}, 1e-3, &x);
    if (t > 1.0) {
      for (int i = 0; i < 4; ++i) {
        if (i != faulty) out.max_healthy_loss = std::max(out.max_healthy_loss, fdd.loss()[i]);
      }
    }
  }
  out.loss = fdd.loss();
  out.settled = fdd.settled();
  out.detected_s = fdd.detected_s();
  for (int i = 0; i < 4; ++i) {
    if (fdd.rotors()[i].detected_s) out.detected_rotor = i;
  }
  return out;
}

TEST(UkfFdd, IdentifiesA40PercentLossOnEachRotor) {
  for (int rotor = 0; rotor < 4; ++rotor) {
    const Outcome o = Fly(rotor, 0.4, 2.0, 10.0, 11 + rotor);
    EXPECT_NEAR(o.loss[rotor], 0.4, 0.05) << "rotor " << rotor;
    EXPECT_LT(o.max_healthy_loss, 0.1) << "rotor " << rotor;
    ASSERT_TRUE(o.detected_s) << "rotor " << rotor;
    EXPECT_EQ(o.detected_rotor, rotor);
    EXPECT_GT(*o.detected_s, 2.0);
    EXPECT_LT(*o.detected_s, 3.0) << "rotor " << rotor;
    EXPECT_TRUE(o.settled) << "rotor " << rotor;
  }
}

TEST(UkfFdd, SmallerAndLargerLossesAreIdentifiedToo) {
  for (const double w : {0.25, 0.6}) {
    const Outcome o = Fly(2, w, 1.5, 10.0, 5);
    EXPECT_NEAR(o.loss[2], w, 0.05) << w;
    EXPECT_EQ(o.detected_rotor, 2) << w;
  }
}

TEST(UkfFdd, NoFalseEstimateWithoutAFault) {
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    const Outcome o = Fly(-1, 0.0, 0.0, 20.0, seed);
    EXPECT_FALSE(o.detected_s) << seed;
    EXPECT_LT(o.max_healthy_loss, 0.1) << seed;
  }
}

TEST(UkfFdd, OptionsValidationNamesTheField) {
  UkfFddOptions o;
  o.detection_threshold = 0.95;
  try {
    o.Validate();
    ADD_FAILURE();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "detection_threshold");
  }
}

}  // namespace
}  // namespace rotorguard::fdd
