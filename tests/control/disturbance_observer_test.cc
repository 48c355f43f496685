#include "rotorguard/control/disturbance_observer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "rotorguard/core/error.h"
#include "rotorguard/vehicle/multirotor.h"
#include "vehicle_fixture.h"

namespace rotorguard::control {
namespace {

using rotorguard::testing::ReferenceQuad;
using vehicle::StateIndex;

/// Level, at rest, the motors at hover thrust.
Eigen::VectorXd HoverState(const NmpcModel& model) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(model.nx());
  x[StateIndex::kPosition + 2] = 2.0;
  x[StateIndex::kQuaternion] = 1.0;
  x.tail(model.nu()).setConstant(model.params().weight_n() / model.nu());
  return x;
}

TEST(DisturbanceObserver, ErrorDecaysAsTheClosedFormDoublePole) {
  // A vehicle whose velocity and rate grow as the model's accelerations plus constants d, d_w,
  // integrated with the observer's own Euler step: the estimation error e = (v^ - v, d^ - d)
  // then follows e_k+1 = M e_k exactly, M = [[1 - k1, dt (1 - k1)], [-k2, 1 - k2 dt]], whose
  // double eigenvalue p = exp(-w dt) makes M^k = p^k I + k p^(k-1) (M - p I).
  const NmpcModel model(ReferenceQuad());
  DisturbanceObserverOptions options;
  DisturbanceObserver observer(model, options);
  const Eigen::Vector3d d(0.3, -0.2, -0.9), d_w(5.0, -3.0, 0.5);
  const double dt = 0.005;
  Eigen::VectorXd x = HoverState(model);
  const int steps = 200;
  for (int k = 0; k <= steps; ++k) {
    observer.Update(x, k * dt);
    Eigen::Vector3d a, alpha;
    model.ModelAccelerations(x, &a, &alpha);
    x.segment<3>(StateIndex::kVelocity) += dt * (a + d);
    x.segment<3>(StateIndex::kBodyRate) += dt * (alpha + d_w);
  }
  for (const auto& [bandwidth, truth, estimate] :
       {std::tuple{options.force_bandwidth_rad_s, d, observer.acceleration_W()},
        std::tuple{options.torque_bandwidth_rad_s, d_w, observer.angular_acceleration_B()}}) {
    const double p = std::exp(-bandwidth * dt), k1 = 1.0 - p * p, k2 = (1.0 - p) * (1.0 - p) / dt;
    Eigen::Matrix2d M;
    M << 1.0 - k1, dt * (1.0 - k1), -k2, 1.0 - k2 * dt;
    const Eigen::Matrix2d N = M - p * Eigen::Matrix2d::Identity();
    EXPECT_LT((N * N).norm(), 1e-12) << "a double eigenvalue";
    // The first update only starts the estimate; `steps` updates follow, from e = (0, -d).
    const Eigen::Matrix2d Mk = std::pow(p, steps) * Eigen::Matrix2d::Identity() + steps * std::pow(p, steps - 1) * N;
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector2d e = Mk * Eigen::Vector2d(0.0, -truth[axis]);
      EXPECT_NEAR(estimate[axis] - truth[axis], e[1], 1e-9) << "bandwidth " << bandwidth << " axis " << axis;
    }
  }
}

TEST(DisturbanceObserver, FindsAHeavierVehicleAndAnOffsetCentreOfGravityExactly) {
  // The truth: 10 % heavier than the file, its centre of gravity 1 cm along body x, hovering at
  // rest on the thrusts that hold it. The model's accelerations at that state are then exactly
  // what the observer must cancel: a_z = (m_t / m - 1) g, and the file's torque of those thrusts.
  const vehicle::VehicleParams file = ReferenceQuad();
  vehicle::VehicleParams truth_params = file;
  truth_params.mass_kg *= 1.1;
  for (vehicle::Rotor& r : truth_params.rotors) r.p_B -= Vector3(0.01, 0.0, 0.0);
  const vehicle::MultirotorModel truth(truth_params);
  const NmpcModel model(file);
  DisturbanceObserver observer(model, {});
  Eigen::VectorXd x = HoverState(model);
  x.tail(4) = truth.HoverThrusts();
  for (int k = 0; k < 2000; ++k) observer.Update(x, k * 0.005);  // 10 s at rest
  const double thrust = truth.HoverThrusts().sum();
  EXPECT_NEAR(thrust, truth_params.weight_n(), 1e-9);
  const Eigen::Vector3d expected_a(0.0, 0.0, -(thrust / file.mass_kg - kGravity));
  // The file's torque of the true thrusts: sum p_i x T_i e3, with the truth's balancing about its
  // own centre of gravity: c x (thrust e3) = (0, -0.01 thrust, 0) for c = (0.01, 0, 0).
  const Eigen::Vector3d torque(0.0, -0.01 * thrust, 0.0);
  const Eigen::Vector3d expected_alpha = -(file.inertia_kg_m2.inverse() * torque);
  EXPECT_LT((observer.acceleration_W() - expected_a).norm(), 1e-9);
  EXPECT_LT((observer.angular_acceleration_B() - expected_alpha).norm(), 1e-6 * expected_alpha.norm())
      << observer.angular_acceleration_B().transpose() << " vs " << expected_alpha.transpose();
}

TEST(DisturbanceObserver, RewindsToTheEstimateBeforeAGivenTime) {
  // The motors give 10 % more than the weight while the vehicle stays put: the estimate moves
  // from the first update on; after 0.5 s the vehicle falls.
  const NmpcModel model(ReferenceQuad());
  DisturbanceObserver observer(model, {});
  Eigen::VectorXd x = HoverState(model);
  x.tail(4) *= 1.1;
  Eigen::Vector3d first, at_half_second;
  for (int k = 0; k <= 200; ++k) {
    x[StateIndex::kVelocity + 2] = k < 100 ? 0.0 : -0.01 * (k - 100);
    observer.Update(x, k * 0.005);
    if (k == 0) first = observer.acceleration_W();
    if (k == 100) at_half_second = observer.acceleration_W();
  }
  EXPECT_GT((observer.acceleration_W() - at_half_second).norm(), 0.1);
  EXPECT_GT((at_half_second - first).norm(), 0.1);
  observer.RewindTo(100 * 0.005);
  EXPECT_EQ(observer.acceleration_W(), at_half_second);
  observer.RewindTo(-10.0);  // older than the history: its oldest entry
  EXPECT_EQ(observer.acceleration_W(), first);
}

TEST(DisturbanceObserver, LearnsNothingOnTheGround) {
  // Landed with the motors at 90 % of the weight: the ground holds the vehicle, not a disturbance.
  const NmpcModel model(ReferenceQuad());
  DisturbanceObserver observer(model, {});
  Eigen::VectorXd x = HoverState(model);
  x[StateIndex::kPosition + 2] = 0.0;
  x.tail(4) *= 0.9;
  for (int k = 0; k < 400; ++k) observer.Update(x, k * 0.005);
  EXPECT_EQ(observer.acceleration_W(), Eigen::Vector3d::Zero());
}

TEST(DisturbanceObserver, IgnoresNonFiniteStatesAndRestartsAfterAGap) {
  const NmpcModel model(ReferenceQuad());
  DisturbanceObserver observer(model, {});
  Eigen::VectorXd x = HoverState(model);
  observer.Update(x, 0.0);
  Eigen::VectorXd bad = x;
  bad[StateIndex::kVelocity] = std::numeric_limits<double>::quiet_NaN();
  observer.Update(bad, 0.005);
  EXPECT_TRUE(observer.acceleration_W().allFinite());
  observer.Update(x, 0.010);  // running again ...
  observer.Update(x, 0.015);
  // ... when, after a 1 s gap, a velocity of 5 m/s is a new start, not a 5 m/s² disturbance (it
  // would be 4.5 m/s² at the first update across the gap).
  x[StateIndex::kVelocity] = 5.0;
  observer.Update(x, 1.015);
  observer.Update(x, 1.020);
  EXPECT_LT(observer.acceleration_W().norm(), 1e-3);
}

TEST(DisturbanceObserver, OptionsValidationNamesTheField) {
  DisturbanceObserverOptions o;
  o.torque_bandwidth_rad_s = 0.0;
  try {
    o.Validate();
    FAIL() << "no error";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("torque_bandwidth_rad_s"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rotorguard::control
