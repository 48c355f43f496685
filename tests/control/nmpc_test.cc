
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "rotorguard/control/nmpc.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/vehicle/multirotor.h"
#include "test_util.h"
#include "vehicle_fixture.h"

namespace rotorguard::control {
namespace {

using rotorguard::testing::MatricesNear;
using rotorguard::testing::NumericalJacobian;
using rotorguard::testing::ReferenceQuad;

planning::HoverReference HoverAt(double z) {
  planning::HoverOptions o;
  o.position_m = Vector3(0, 0, z);
  return planning::HoverReference(o);
}

StateEstimate HoverEstimate(double z) {
  StateEstimate e;
  e.valid = true;
  e.p_W = Vector3(0, 0, z);
  e.motor_thrust_n = RotorVector::Constant(4, 1.15 * kGravity / 4.0);
  return e;
}

TEST(Nmpc, ResidualJacobianMatchesFiniteDifferences) {
  NmpcController nmpc(ReferenceQuad(), {});
  Rng rng(4);
  ReferencePoint ref;
  ref.p_W = Vector3(1, 2, 3);
  ref.v_W = Vector3(0.5, -0.2, 0.1);
  ref.a_W = Vector3(1.0, 0.5, -0.3);
  ref.yaw = 0.7;
  for (int failed = 0; failed < 2; ++failed) {
    if (failed) nmpc.SetRotorFailed(2);
    for (int trial = 0; trial < 10; ++trial) {
      Eigen::VectorXd x(17);
      x << rng.Normal(), rng.Normal(), rng.Normal(), 1.0, 0.2 * rng.Normal(), 0.2 * rng.Normal(), rng.Normal(),
          rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal(), 2.0, 3.0, 1.0, 4.0;
      x.segment<4>(3).normalize();
      Eigen::VectorXd y;
      Eigen::MatrixXd dy;
      nmpc.Residual(x, ref, &y, &dy);
      const Eigen::MatrixXd dy_num = NumericalJacobian(
          [&](const Eigen::VectorXd& xx) {
            Eigen::VectorXd yy;
            Eigen::MatrixXd unused;
            nmpc.Residual(xx, ref, &yy, &unused);
            return yy;
          },
          x);
      EXPECT_TRUE(MatricesNear(dy, dy_num, 1e-6)) << "trial " << trial;
    }
  }
}

TEST(Nmpc, AttitudeResidualSeparatesTiltFromYaw) {
  NmpcController nmpc(ReferenceQuad(), {});
  ReferencePoint ref;  // hover: level, yaw 0
  Eigen::VectorXd x = Eigen::VectorXd::Zero(17), y;
  Eigen::MatrixXd dy;
  const Quaternion yawed = QuaternionFromYaw(0.8);
  x.segment<4>(3) << yawed.w(), yawed.x(), yawed.y(), yawed.z();
  nmpc.Residual(x, ref, &y, &dy);
  // A pure yaw error shows only in the yaw component, as sin(yaw / 2).
  EXPECT_NEAR(y[3], 0.0, 1e-12);
  EXPECT_NEAR(y[4], 0.0, 1e-12);
  EXPECT_NEAR(y[5], 0.0, 1e-12);
  EXPECT_NEAR(std::abs(y[6]), std::sin(0.4), 1e-8);
  // A pure tilt of 0.3 rad about x shows in the tilt components, not in yaw.
  const Quaternion tilted(Eigen::AngleAxisd(0.3, Vector3::UnitX()));
  x.segment<4>(3) << tilted.w(), tilted.x(), tilted.y(), tilted.z();
  nmpc.Residual(x, ref, &y, &dy);
  EXPECT_NEAR(std::abs(y[3]), std::sin(0.15), 1e-8);
  EXPECT_NEAR(y[4], 0.0, 1e-12);
  EXPECT_NEAR(y[5], std::pow(std::sin(0.15), 2), 1e-8);
  EXPECT_NEAR(y[6], 0.0, 1e-12);
}

TEST(Nmpc, HoldsHoverWithTheHoverSplit) {
  NmpcController nmpc(ReferenceQuad(), {});
  const auto ref = HoverAt(1.0);
  RotorVector cmd;
  nmpc.Compute(HoverEstimate(1.0), ref, 0.0, 0.0, &cmd);
  ASSERT_TRUE(nmpc.summary().IsSolutionUsable()) << nmpc.summary().BriefReport();
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(cmd[i], 1.15 * kGravity / 4.0, 1e-6);
}

TEST(Nmpc, ConvergeModeReachesAFixedPointOfTheSqp) {
  NmpcOptions o;
  o.max_sqp_iterations = 50;
  o.sqp_tolerance = 1e-9;
  NmpcController nmpc(ReferenceQuad(), o);
  const auto ref = HoverAt(1.5);  // 0.5 m below the reference, moving sideways, tilted
  StateEstimate est = HoverEstimate(1.0);
  est.v_W = Vector3(0.8, -0.4, 0.0);
  est.q_WB = Quaternion(Eigen::AngleAxisd(0.2, Vector3::UnitY()));
  RotorVector cmd;
  nmpc.Compute(est, ref, 0.0, 0.0, &cmd);
  const NmpcSummary& s = nmpc.summary();
  EXPECT_EQ(s.status, NmpcStatus::kSolved) << s.BriefReport();
  EXPECT_LT(s.step_norm, 1e-9);
  EXPECT_LT(s.dynamics_gap, 1e-8);  // the converged plan is a trajectory of the model
  EXPECT_LT(s.kkt_residual, 1e-8);
  for (int i = 0; i < 4; ++i) {
    EXPECT_GE(cmd[i], 0.0);
    EXPECT_LE(cmd[i], 11.5);
  }
}

TEST(Nmpc, AFailedRotorGetsZeroThrustAndTheTwinIdlesInTheReference) {
  NmpcController nmpc(ReferenceQuad(), {});
  nmpc.SetRotorFailed(0);
  const Eigen::VectorXd t_ref = nmpc.ThrustReference(1.15 * kGravity);
  EXPECT_EQ(t_ref[0], 0.0);
  EXPECT_EQ(t_ref[1], 0.0);  // rotor 1 is rotor 0's diagonal twin (paper 000, eq. 5)
  EXPECT_NEAR(t_ref[2], 0.5 * 1.15 * kGravity, 1e-12);
  EXPECT_NEAR(t_ref[3], 0.5 * 1.15 * kGravity, 1e-12);
  const auto ref = HoverAt(1.0);
  RotorVector cmd;
  for (int k = 0; k < 20; ++k) nmpc.Compute(HoverEstimate(1.0), ref, 0.005 * k, 0.005, &cmd);
  EXPECT_EQ(cmd[0], 0.0);
  EXPECT_TRUE(cmd.allFinite());
  RG_EXPECT_THROW_WITH(nmpc.SetRotorFailed(4), std::invalid_argument, "rotor = 4");
}

TEST(Nmpc, ThePlannedCommandIsThePlansInputOnItsClockAfterTheExpectedDelay) {
  // A rolling vehicle, so that the plan's inputs change from node to node.
  NmpcOptions o;
  o.expected_delay_s = 0.01;
  NmpcController nmpc(ReferenceQuad(), o);
  const auto ref = HoverAt(1.0);
  StateEstimate est = HoverEstimate(1.0);
  est.w_B = Vector3(3.0, -1.0, 0.5);
  RotorVector cmd, planned;
  EXPECT_FALSE(nmpc.PlannedCommand(0.0, &planned)) << "no plan before the first call";
  // dt = 0: no preparation; the plan's node 0 is at the call's time plus the delay.
  nmpc.Compute(est, ref, 1.0, 0.0, &cmd);
  const std::vector<Eigen::VectorXd>& u = nmpc.planned_inputs();
  ASSERT_GT((u[1] - u[0]).norm(), 1e-3) << "a plan whose inputs do not change checks nothing";
  ASSERT_TRUE(nmpc.PlannedCommand(1.0, &planned));
  EXPECT_TRUE(MatricesNear(planned, cmd, 1e-12)) << "at the call's own time: the command it sent";
  // 10 ms later: a fifth of the way from node 0 to node 1 (50 ms apart), held to the bounds.
  const Eigen::VectorXd expected = (0.8 * u[0] + 0.2 * u[1]).cwiseMax(0.0).cwiseMin(nmpc.input_upper_bounds());
  ASSERT_TRUE(nmpc.PlannedCommand(1.01, &planned));
  EXPECT_TRUE(MatricesNear(planned, expected, 1e-12));
  // With the preparation for the next call (dt = 5 ms), the plan is shifted: its node 0 is the
  // input for the next call, the same instant as before.
  nmpc.Compute(est, ref, 1.005, 0.005, &cmd);
  ASSERT_TRUE(nmpc.PlannedCommand(1.01, &planned));
  const Eigen::VectorXd shifted =
      nmpc.planned_inputs()[0].cwiseMax(0.0).cwiseMin(nmpc.input_upper_bounds());
  EXPECT_TRUE(MatricesNear(planned, shifted, 1e-12));
}

TEST(Nmpc, LosingADiagonalPairLeavesTheOtherPairSharingTheWeight) {
  NmpcController nmpc(ReferenceQuad(), {});
  nmpc.SetRotorFailed(0);
  nmpc.SetRotorFailed(1);  // rotor 0's twin: rotors 2 and 3 can still balance roll and pitch
  const Eigen::VectorXd t_ref = nmpc.ThrustReference(10.0);
  EXPECT_EQ(t_ref[0], 0.0);
  EXPECT_EQ(t_ref[1], 0.0);
  EXPECT_NEAR(t_ref[2], 5.0, 1e-12);
  EXPECT_NEAR(t_ref[3], 5.0, 1e-12);
}

TEST(Nmpc, ARateBeyondWhatTheBoundsAllowStillGetsACorrectiveCommand) {
  // Rolling at 16 rad/s: the motors cannot bring it under the 10 rad/s bound within one node, so
  // the QP with rate bounds is infeasible. The NMPC must still counter the roll, not hover.
  NmpcController nmpc(ReferenceQuad(), {});
  const auto ref = HoverAt(1.0);
  StateEstimate est = HoverEstimate(1.0);
  RotorVector cmd;
  nmpc.Compute(est, ref, 0.0, 0.0, &cmd);
  est.w_B = Vector3(16.0, 0.0, 0.0);
  nmpc.Compute(est, ref, 0.005, 0.005, &cmd);
  EXPECT_EQ(nmpc.summary().status, NmpcStatus::kSolved) << nmpc.summary().BriefReport();
  EXPECT_GE(nmpc.summary().rate_bounds_relaxed, 1);
  // Negative roll torque: the rotors at y < 0 (0 and 3, paper 000 eq. 5) push harder.
  EXPECT_GT(cmd[0] + cmd[3], cmd[1] + cmd[2] + 1.0);
}

TEST(Nmpc, NonFiniteStateGivesAFiniteFallbackCommand) {
  NmpcController nmpc(ReferenceQuad(), {});
  const auto ref = HoverAt(1.0);
  StateEstimate est = HoverEstimate(1.0);
  RotorVector cmd;
  nmpc.Compute(est, ref, 0.0, 0.0, &cmd);
  est.p_W.x() = std::nan("");
  nmpc.Compute(est, ref, 0.005, 0.005, &cmd);
  EXPECT_EQ(nmpc.summary().status, NmpcStatus::kInvalidInput);
  EXPECT_TRUE(cmd.allFinite());
}

TEST(Nmpc, AllRotorsFailedStillCommandsFiniteZeros) {
  NmpcController nmpc(ReferenceQuad(), {});
  for (int i = 0; i < 4; ++i) nmpc.SetRotorFailed(i);
  const auto ref = HoverAt(1.0);
  RotorVector cmd;
  nmpc.Compute(HoverEstimate(1.0), ref, 0.0, 0.0, &cmd);
  EXPECT_TRUE(cmd.allFinite());
  EXPECT_EQ(cmd.cwiseAbs().maxCoeff(), 0.0);
}

// NmpcOptions::relinearise_every: of the real-time iteration's preparations (one per call, for the
// next), every third linearises and the two between reuse it; the first call's own SQP iterations
// and a rotor reconfiguration (its weights change the Hessians) linearise. Before the failure the
// commands stay within 0.05 N of a controller's that linearises every time.
TEST(Nmpc, ReusesTheLinearisationForTheConfiguredNumberOfPreparations) {
  NmpcOptions every_third;
  every_third.relinearise_every = 3;
  NmpcController reusing(ReferenceQuad(), every_third), linearising(ReferenceQuad(), {});
  const auto ref = HoverAt(1.5);  // 0.5 m below it, drifting, tilted: the plans move
  StateEstimate est = HoverEstimate(1.0);
  est.v_W = Vector3(0.5, -0.3, 0.0);
  est.q_WB = Quaternion(Eigen::AngleAxisd(0.15, Vector3::UnitX()));
  std::string pattern;
  double largest_difference = 0.0;
  for (int i = 0; i < 12; ++i) {
    if (i == 7) {
      reusing.SetRotorFailed(0);
      linearising.SetRotorFailed(0);
    }
    RotorVector a, b;
    reusing.Compute(est, ref, 0.005 * i, 0.005, &a);
    linearising.Compute(est, ref, 0.005 * i, 0.005, &b);
    const NmpcSummary& s = reusing.summary();
    ASSERT_TRUE(s.IsSolutionUsable()) << "call " << i << ": " << s.BriefReport();
    EXPECT_EQ(linearising.summary().linearisations_reused, 0);
    if (i == 0) {
      EXPECT_EQ(s.linearisations, 3) << "the first plan's own iterations";
    }
    pattern += s.linearisations_reused == 1 ? 'r' : (s.linearisations == (i == 0 ? 3 : 1) ? 'L' : '?');
    // Before the failure (after it, this open loop's fixed state holds the rotors saturated).
    if (i < 7) largest_difference = std::max(largest_difference, (a - b).cwiseAbs().maxCoeff());
    est.p_W += 0.005 * est.v_W;
  }
  // Calls 0-6: the first's SQP linearised, then r r L r r L; call 7 reconfigures: L, then r r L.
  EXPECT_EQ(pattern, "rrLrrLrLrrLr");
  EXPECT_GT(largest_difference, 0.0) << "the reused linearisation changes the plans";
  EXPECT_LT(largest_difference, 0.05) << "of thrusts of 4 to 9 N";
}

TEST(Nmpc, BothQpSolversGiveTheSameCommands) {
  // The two solvers of the same QPs (condensing; Riccati, docs/control.md "Two QP solvers") through
  // what the NMPC asks of them: whole and vector-only preparations (relinearise_every 3), warm
  // starts, a rotor failure (inputs bounded to zero) and an infeasible QP re-solved without rate
  // bounds. The commands agree to rounding.
  NmpcOptions condensing_options, riccati_options;
  condensing_options.relinearise_every = riccati_options.relinearise_every = 3;
  condensing_options.qp_solver = OcpQpMethod::kCondensing;
  riccati_options.qp_solver = OcpQpMethod::kRiccati;
  NmpcController condensing(ReferenceQuad(), condensing_options), riccati(ReferenceQuad(), riccati_options);
  const auto ref = HoverAt(1.5);
  StateEstimate est = HoverEstimate(1.0);
  est.v_W = Vector3(0.5, -0.3, 0.0);
  est.q_WB = Quaternion(Eigen::AngleAxisd(0.15, Vector3::UnitX()));
  double largest_difference = 0.0;
  int relaxed = 0, relaxed_condensing = 0, iterations = 0;
  for (int i = 0; i < 30; ++i) {
    if (i == 12) {
      condensing.SetRotorFailed(0);
      riccati.SetRotorFailed(0);
    }
    StateEstimate now = est;
    if (i == 20) now.w_B = Vector3(16.0, 0.0, 0.0);  // beyond what the rate bounds allow
    RotorVector a, b;
    condensing.Compute(now, ref, 0.005 * i, 0.005, &a);
    riccati.Compute(now, ref, 0.005 * i, 0.005, &b);
    ASSERT_TRUE(riccati.summary().IsSolutionUsable()) << "call " << i << ": " << riccati.summary().BriefReport();
    ASSERT_EQ(condensing.summary().status, riccati.summary().status) << "call " << i;
    largest_difference = std::max(largest_difference, (a - b).cwiseAbs().maxCoeff());
    relaxed += riccati.summary().rate_bounds_relaxed;
    relaxed_condensing += condensing.summary().rate_bounds_relaxed;
    iterations += riccati.summary().qp_iterations;
    est.p_W += 0.005 * est.v_W;
  }
  EXPECT_LT(largest_difference, 1e-7) << "of thrusts of 0 to 9 N";
  EXPECT_EQ(relaxed, relaxed_condensing);
  EXPECT_GE(relaxed, 1);
  EXPECT_GT(iterations, 0) << "bounds must have entered the active set";
}

// Delay compensation: a call's command acts only expected_delay_s after the state it is given, the
// previous command acting meanwhile. The plan starts from the state then, predicted through the
// model: against the simulated vehicle (the same equations, integrated at 1 kHz with each command
// switching at its own instant) the prediction holds to integration error, while the state as
// given is centimetres, degrees and newtons away from it after a failure, spinning.
TEST(Nmpc, ItsPredictionOverTheDelayIsWhereTheVehicleIsWhenTheCommandActs) {
  const vehicle::VehicleParams params = ReferenceQuad();
  NmpcOptions o;
  o.expected_delay_s = 0.0037;
  o.disturbance.enabled = false;  // the model is the vehicle here: nothing to learn
  NmpcController nmpc(params, o);
  nmpc.SetRotorFailed(0);
  const vehicle::MultirotorModel truth(params);
  vehicle::Rk4Integrator rk4(truth);
  vehicle::RotorFaults lost(4);  // the vehicle without rotor 0's thrust, as the NMPC models it
  lost[0].kind = vehicle::FaultKind::kPropellerLoss;
  vehicle::StateVector x = truth.MakeState(Vector3(0, 0, 2), 0.0, truth.HoverThrusts());
  const planning::HoverReference hover = HoverAt(2.0);
  RotorVector acting = truth.HoverThrusts(), command(4);
  // Integrates the vehicle from t to t_end, `acting` held, in steps of at most 1 ms.
  const auto fly = [&](double t, double t_end) {
    while (t < t_end - 1e-12) {
      const double h = std::min(1e-3, t_end - t);
      rk4.Step(acting, lost, vehicle::Disturbance{}, h, &x);
      t += h;
    }
  };
  double worst = 0.0, worst_as_given = 0.0;
  const double period = 0.005;
  for (int k = 0; k < 200; ++k) {  // 1 s: the spin builds up to several rad/s
    const double t = k * period;
    nmpc.Compute(rotorguard::testing::ExactEstimate(x), hover, t, period, &command);
    const Eigen::VectorXd given = x, predicted = nmpc.predicted_state();
    fly(t, t + o.expected_delay_s);  // the previous command acts until the new one does
    Eigen::VectorXd error = predicted - x, as_given = given - x;
    if (predicted.segment<4>(3).dot(x.segment<4>(3)) < 0.0) error.segment<4>(3) = predicted.segment<4>(3) + x.segment<4>(3);
    worst = std::max(worst, error.cwiseAbs().maxCoeff());
    worst_as_given = std::max(worst_as_given, as_given.cwiseAbs().maxCoeff());
    acting = command;
    fly(t + o.expected_delay_s, t + period);
  }
  EXPECT_GT(vehicle::StateView(x).w_B().norm(), 3.0) << "it spins";
  // One RK4 step over 3.7 ms against four over 1 ms: (h / σ)^5 / 120 of the motors' newtons, 1e-6.
  EXPECT_LT(worst, 1e-5);
  EXPECT_GT(worst_as_given, 1e-2);
}

TEST(Nmpc, OptionsValidationNamesTheField) {
  NmpcOptions o;
  o.horizon_steps = 0;
  RG_EXPECT_THROW_WITH(NmpcController(ReferenceQuad(), o), ValidationError, "horizon_steps = 0");
  o = NmpcOptions{};
  o.step_s = std::nan("");
  RG_EXPECT_THROW_WITH(NmpcController(ReferenceQuad(), o), ValidationError, "step_s");
  o = NmpcOptions{};
  o.relinearise_every = 0;
  RG_EXPECT_THROW_WITH(NmpcController(ReferenceQuad(), o), ValidationError, "relinearise_every = 0");
}

}  // namespace
}  // namespace rotorguard::control
