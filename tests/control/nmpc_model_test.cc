
#include "rotorguard/control/nmpc_model.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <numbers>
#include <utility>

#include "rotorguard/core/rng.h"
#include "rotorguard/vehicle/multirotor.h"
#include "test_util.h"
#include "vehicle_fixture.h"

namespace rotorguard::control {
namespace {

using rotorguard::testing::MatricesNear;
using rotorguard::testing::NumericalJacobian;
using rotorguard::testing::ReferenceQuad;

/// A non-trivial state: tilted, moving, spinning, motors loaded unevenly.
Eigen::VectorXd SomeState(Rng& rng, int rotors = 4) {
  Eigen::VectorXd x(13 + rotors);
  x.segment<3>(0) << rng.Normal(), rng.Normal(), 1.0 + rng.Uniform();
  Eigen::Vector4d q(1.0, 0.3 * rng.Normal(), 0.3 * rng.Normal(), rng.Normal());
  x.segment<4>(3) = q.normalized();
  x.segment<3>(7) << 2.0 * rng.Normal(), 2.0 * rng.Normal(), rng.Normal();
  x.segment<3>(10) << rng.Normal(), rng.Normal(), 11.0 * rng.Uniform();
  for (int i = 0; i < rotors; ++i) x[13 + i] = rng.Uniform(0.5, 8.0);
  return x;
}

Eigen::VectorXd SomeInput(Rng& rng, int rotors = 4) {
  Eigen::VectorXd u(rotors);
  for (int i = 0; i < rotors; ++i) u[i] = rng.Uniform(0.0, 11.5);
  return u;
}

/// Central-difference Jacobians of out = f(x, u) with respect to x and to u.
std::pair<Eigen::MatrixXd, Eigen::MatrixXd> JacobiansByDifferences(
    const std::function<void(const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd*)>& f,
    const Eigen::VectorXd& x, const Eigen::VectorXd& u) {
  const auto at = [&f](const Eigen::VectorXd& xx, const Eigen::VectorXd& uu) {
    Eigen::VectorXd out;
    f(xx, uu, &out);
    return out;
  };
  return {NumericalJacobian([&](const Eigen::VectorXd& xx) { return at(xx, u); }, x),
          NumericalJacobian([&](const Eigen::VectorXd& uu) { return at(x, uu); }, u)};
}

/// The reference quadrotor's body with six rotors on a circle, spins alternating: the model's
/// generic (run-time sized) paths.
vehicle::VehicleParams Hexarotor() {
  vehicle::VehicleParams p = ReferenceQuad();
  p.name = "reference_hexa";
  const vehicle::Rotor r0 = p.rotors[0];
  p.rotors.clear();
  for (int i = 0; i < 6; ++i) {
    vehicle::Rotor r = r0;
    const double angle = std::numbers::pi / 6.0 + i * std::numbers::pi / 3.0;
    r.p_B = Vector3(0.1 * std::cos(angle), 0.1 * std::sin(angle), 0.0);
    r.direction = i % 2 == 0 ? vehicle::SpinDirection::kCounterClockwise : vehicle::SpinDirection::kClockwise;
    p.rotors.push_back(r);
  }
  return p;
}

TEST(NmpcModel, EqualsTheSimulatorModelForHealthyRotorsWithinBounds) {
  const NmpcModel model(ReferenceQuad());
  const vehicle::MultirotorModel truth(ReferenceQuad());
  Rng rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd x = SomeState(rng), u = SomeInput(rng);
    Eigen::VectorXd f;
    model.Dynamics(x, u, &f);
    vehicle::StateVector xs = x, fs;
    RotorVector us = u;
    truth.Derivative(xs, us, vehicle::RotorFaults(4), vehicle::Disturbance{}, &fs);
    EXPECT_TRUE(MatricesNear(f, Eigen::VectorXd(fs), 1e-10)) << "trial " << trial;
  }
}

/// A correction with every rotor partly effective and constant accelerations in every axis.
ModelCorrection SomeCorrection(Rng& rng, int rotors = 4) {
  ModelCorrection c;
  c.effectiveness.resize(rotors);
  for (int i = 0; i < rotors; ++i) c.effectiveness[i] = rng.Uniform(0.2, 1.0);
  c.acceleration_W << rng.Normal(), rng.Normal(), rng.Normal();
  c.angular_acceleration_B << 10.0 * rng.Normal(), 10.0 * rng.Normal(), rng.Normal();
  return c;
}

TEST(NmpcModel, WithACorrectionEqualsTheSimulatorModelWithTheSameLossesForceAndTorque) {
  // The simulator's loss of effectiveness eta (thrust and torque scale by 1 - eta) is the
  // model's effectiveness 1 - eta; its force and torque disturbances are m a_c and I alpha_c.
  const vehicle::VehicleParams params = ReferenceQuad();
  NmpcModel model(params);
  const vehicle::MultirotorModel truth(params);
  Rng rng(21);
  for (int trial = 0; trial < 20; ++trial) {
    const ModelCorrection c = SomeCorrection(rng);
    model.SetCorrection(c);
    vehicle::RotorFaults faults(4);
    for (int i = 0; i < 4; ++i) faults[i] = {vehicle::FaultKind::kLossOfEffectiveness, 1.0 - c.effectiveness[i]};
    vehicle::Disturbance d;
    d.force_W = params.mass_kg * c.acceleration_W;
    d.torque_B = params.inertia_kg_m2 * c.angular_acceleration_B;
    const Eigen::VectorXd x = SomeState(rng), u = SomeInput(rng);
    Eigen::VectorXd f;
    model.Dynamics(x, u, &f);
    vehicle::StateVector xs = x, fs;
    RotorVector us = u;
    truth.Derivative(xs, us, faults, d, &fs);
    EXPECT_TRUE(MatricesNear(f, Eigen::VectorXd(fs), 1e-10)) << "trial " << trial;
  }
}

TEST(NmpcModel, RejectsABadCorrection) {
  NmpcModel model(ReferenceQuad());
  ModelCorrection c;
  c.effectiveness = Eigen::VectorXd::Constant(3, 1.0);
  EXPECT_THROW(model.SetCorrection(c), std::invalid_argument);
  c.effectiveness = Eigen::Vector4d(1.0, 1.0, 1.2, 1.0);
  EXPECT_THROW(model.SetCorrection(c), std::invalid_argument);
  c.effectiveness = Eigen::Vector4d(1.0, 0.5, 1.0, 1.0);  // valid, with a bad acceleration
  c.acceleration_W.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(model.SetCorrection(c), std::invalid_argument);
  EXPECT_EQ(model.effectiveness(), Eigen::VectorXd::Ones(4));  // nothing half-applied
}

TEST(NmpcModel, AnalyticJacobiansMatchFiniteDifferences) {
  NmpcModel model(ReferenceQuad());
  Rng rng(2);
  for (int trial = 0; trial < 20; ++trial) {
    if (trial >= 10) model.SetCorrection(SomeCorrection(rng));  // the effectiveness scales columns
    const Eigen::VectorXd x = SomeState(rng), u = SomeInput(rng);
    Eigen::VectorXd f;
    Eigen::MatrixXd fx, fu;
    model.DynamicsWithJacobians(x, u, &f, &fx, &fu);
    const auto [fx_num, fu_num] = JacobiansByDifferences([&](const Eigen::VectorXd& xx, const Eigen::VectorXd& uu,
                                                             Eigen::VectorXd* out) { model.Dynamics(xx, uu, out); },
                                                         x, u);
    // Central differences with h = 1e-6 on entries of size ~1e2: errors ~1e-7 relative.
    EXPECT_TRUE(MatricesNear(fx, fx_num, 1e-5 * (1.0 + fx.cwiseAbs().maxCoeff()))) << "trial " << trial;
    EXPECT_TRUE(MatricesNear(fu, fu_num, 1e-6 * (1.0 + fu.cwiseAbs().maxCoeff()))) << "trial " << trial;
  }
}

TEST(Rk4Sensitivity, DiscreteSensitivitiesMatchFiniteDifferences) {
  // The quadrotor (compile-time sized products) and a hexarotor (the generic ones).
  for (const vehicle::VehicleParams& vehicle : {ReferenceQuad(), Hexarotor()}) {
    NmpcModel model(vehicle);
    const int rotors = vehicle.num_rotors();
    for (int substeps : {1, 3}) {
      Rk4Sensitivity rk4(model, 0.05, substeps);
      Rng rng(3 + substeps);
      for (int trial = 0; trial < 10; ++trial) {
        if (trial == 5) model.SetCorrection(SomeCorrection(rng, rotors));
        const Eigen::VectorXd x = SomeState(rng, rotors), u = SomeInput(rng, rotors);
        Eigen::VectorXd next;
        Eigen::MatrixXd A, B;
        rk4.Step(x, u, &next, &A, &B);
        Eigen::VectorXd plain;
        rk4.Step(x, u, &plain);
        EXPECT_TRUE(MatricesNear(next, plain, 1e-14));  // sensitivities do not change the step
        const auto [A_num, B_num] = JacobiansByDifferences(
            [&](const Eigen::VectorXd& xx, const Eigen::VectorXd& uu, Eigen::VectorXd* out) { rk4.Step(xx, uu, out); },
            x, u);
        EXPECT_TRUE(MatricesNear(A, A_num, 1e-6 * (1.0 + A.cwiseAbs().maxCoeff()))) << substeps << "/" << trial;
        EXPECT_TRUE(MatricesNear(B, B_num, 1e-6 * (1.0 + B.cwiseAbs().maxCoeff()))) << substeps << "/" << trial;
      }
    }
  }
}

TEST(Rk4Sensitivity, ConvergesAtFourthOrderAgainstTheSimulatorIntegrator) {
  // The NMPC's discretisation of a 50 ms step, against the simulator's RK4 at 0.05 ms.
  const NmpcModel model(ReferenceQuad());
  const vehicle::MultirotorModel truth(ReferenceQuad());
  Rng rng(9);
  const Eigen::VectorXd x = SomeState(rng), u = SomeInput(rng);
  vehicle::StateVector xs = x;
  vehicle::Rk4Integrator fine(truth);
  for (int k = 0; k < 1000; ++k) fine.Step(RotorVector(u), vehicle::RotorFaults(4), {}, 5e-5, &xs);
  double previous = 0.0;
  for (int substeps : {1, 2, 4}) {
    Rk4Sensitivity rk4(model, 0.05, substeps);
    Eigen::VectorXd next;
    rk4.Step(x, u, &next);
    next.segment<4>(3).normalize();  // the simulator renormalises its quaternion
    const double error = (next - Eigen::VectorXd(xs)).norm();
    if (previous > 0.0) {
      EXPECT_GT(previous / error, 10.0) << substeps << " substeps: " << error;
    }
    previous = error;
  }
}

}  // namespace
}  // namespace rotorguard::control

namespace rotorguard::control {
namespace {

TEST(NmpcModel, StructuredJacobianProductEqualsTheDenseProduct) {
  NmpcModel model(rotorguard::testing::ReferenceQuad());
  Rng rng(12);
  model.SetCorrection(SomeCorrection(rng));  // unequal thrust columns
  const Eigen::VectorXd x = SomeState(rng), u = SomeInput(rng);
  Eigen::VectorXd f;
  Eigen::MatrixXd fx, fu, out;
  model.DynamicsWithJacobians(x, u, &f, &fx, &fu);
  for (int cols : {18, 9}) {  // the RK4's compile-time-sized [d/dx d/du] path, and the generic one
    const Eigen::MatrixXd M = Eigen::MatrixXd::Random(17, cols);
    model.MultiplyStateJacobian(fx, M, &out);
    EXPECT_TRUE(rotorguard::testing::MatricesNear(out, fx * M, 1e-12 * (fx * M).cwiseAbs().maxCoeff())) << cols;
  }
}

}  // namespace
}  // namespace rotorguard::control
