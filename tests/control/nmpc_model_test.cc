
#include <gtest/gtest.h>

#include <functional>
#include <numbers>
#include <utility>

#include "rotorguard/control/nmpc_model.h"
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

TEST(NmpcModel, AnalyticJacobiansMatchFiniteDifferences) {
  const NmpcModel model(ReferenceQuad());
  Rng rng(2);
  for (int trial = 0; trial < 20; ++trial) {
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
    const NmpcModel model(vehicle);
    const int rotors = vehicle.num_rotors();
    for (int substeps : {1, 3}) {
      Rk4Sensitivity rk4(model, 0.05, substeps);
      Rng rng(3 + substeps);
      for (int trial = 0; trial < 10; ++trial) {
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
  const NmpcModel model(rotorguard::testing::ReferenceQuad());
  Rng rng(12);
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
