// Micro-benchmarks of the NMPC's parts (Google Benchmark): the RK4 step with and without exact
// sensitivities, an N = 20, nx = 17, nu = 4 OCP QP solved by each of the two solvers (condensing
// with the dense dual active-set solve and its factorisation; Riccati), and one real-time
// iteration in hover and while spinning after a failure with each.
// Run: build/bin/nmpc_benchmark
#include <benchmark/benchmark.h>

#include <memory>

#include "rotorguard/control/nmpc.h"
#include "rotorguard/control/nmpc_model.h"
#include "rotorguard/control/ocp_qp.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/planning/references.h"

namespace {

using namespace rotorguard;

vehicle::VehicleParams ReferenceVehicle() {
  return harness::LoadVehicle(std::string(ROTORGUARD_SOURCE_DIR) + "/configs/vehicles/zhou2025_quad.yaml");
}

Eigen::VectorXd SpinningState() {
  Eigen::VectorXd x(17);
  x << 0, 0, 1, 0.99, 0.05, -0.04, 0.1, 0.5, -0.2, 0.1, 0.3, -0.2, 11.0, 0.1, 0.2, 5.6, 5.6;
  x.segment<4>(3).normalize();
  return x;
}

void BM_Rk4Step(benchmark::State& state) {
  const control::NmpcModel model(ReferenceVehicle());
  control::Rk4Sensitivity rk4(model, 0.05, 1);
  const Eigen::VectorXd x = SpinningState(), u = Eigen::VectorXd::Constant(4, 3.0);
  Eigen::VectorXd next;
  for (auto _ : state) {
    rk4.Step(x, u, &next);
    benchmark::DoNotOptimize(next.data());
  }
}
BENCHMARK(BM_Rk4Step);

void BM_Rk4StepWithSensitivities(benchmark::State& state) {
  const control::NmpcModel model(ReferenceVehicle());
  control::Rk4Sensitivity rk4(model, 0.05, 1);
  const Eigen::VectorXd x = SpinningState(), u = Eigen::VectorXd::Constant(4, 3.0);
  Eigen::VectorXd next;
  Eigen::MatrixXd A, B;
  for (auto _ : state) {
    rk4.Step(x, u, &next, &A, &B);
    benchmark::DoNotOptimize(A.data());
  }
}
BENCHMARK(BM_Rk4StepWithSensitivities);

/// An OCP QP of the NMPC's size: the sensitivities along a spinning trajectory, GN weights.
control::OcpQp NmpcSizedQp() {
  const control::NmpcModel model(ReferenceVehicle());
  control::Rk4Sensitivity rk4(model, 0.05, 1);
  control::OcpQp qp(control::OcpQpDims{20, 17, 4, {10, 11, 12}});
  Eigen::VectorXd x = SpinningState(), next;
  const Eigen::VectorXd u = (Eigen::VectorXd(4) << 0.0, 0.3, 5.6, 5.6).finished();
  Rng rng(1);
  for (int k = 0; k < 20; ++k) {
    rk4.Step(x, u, &next, &qp.A[k], &qp.B[k]);
    x = next;
    qp.u_lower[k] = -u;
    qp.u_upper[k] = Eigen::VectorXd::Constant(4, 11.5) - u;
  }
  Eigen::VectorXd w(17);
  w << 100, 100, 600, 60, 60, 60, 60, 5, 5, 5, 1, 1, 1, 1, 1, 1, 1;
  for (int k = 0; k <= 20; ++k) {
    qp.Q[k] = w.asDiagonal();
    qp.q[k] = Eigen::VectorXd::Random(17);
    qp.x_lower[k].setConstant(-10.0);
    qp.x_upper[k].setConstant(10.0);
  }
  qp.x0 = 0.3 * Eigen::VectorXd::Random(17);
  return qp;
}

// One solve of that QP, warm-started as in flight (the same QP again: its active set is the start).
// Arg: 0 condensing, 1 Riccati (docs/control.md, "Two QP solvers"). prepare_us is condensing and
// factorisation, or the Riccati factorisation with the start's responses; feedback_us the rest.
void BM_OcpQpSolve(benchmark::State& state) {
  const control::OcpQp qp = NmpcSizedQp();
  const auto method = state.range(0) == 0 ? control::OcpQpMethod::kCondensing : control::OcpQpMethod::kRiccati;
  const std::unique_ptr<control::OcpQpSolver> solver = control::MakeOcpQpSolver(method, qp.dims);
  double prepare = 0.0, feedback = 0.0;
  for (auto _ : state) {
    const control::OcpQpSummary& s = solver->Solve(qp);
    prepare += s.prepare_time_s;
    feedback += s.feedback_time_s;
  }
  state.counters["prepare_us"] = 1e6 * prepare / static_cast<double>(state.iterations());
  state.counters["feedback_us"] = 1e6 * feedback / static_cast<double>(state.iterations());
}
BENCHMARK(BM_OcpQpSolve)->Arg(0)->Arg(1)->ArgName("riccati");

// The dense solver's factorisation (Cholesky and J0 = L^-T) of the condensed Hessian: 80 inputs
// in hover, 60 once a failed rotor's 20 are eliminated (the leading block of the same Hessian).
void BM_DenseQpFactorize(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  const control::OcpQp qp = NmpcSizedQp();
  control::CondensingQpSolver condensing(qp.dims);
  condensing.Solve(qp);
  const Eigen::MatrixXd H = condensing.condensed().H.topLeftCorner(n, n);
  control::DenseQpSolver solver(n, 0);
  for (auto _ : state) benchmark::DoNotOptimize(solver.Factorize(H));
}
BENCHMARK(BM_DenseQpFactorize)->Arg(60)->Arg(80);

// One backward Riccati factorisation of the same QP (compile-time sizes): the work an interior-
// point method with Riccati recursion (HPIPM's approach) repeats at each of its iterations.
void BM_RiccatiFactorisation(benchmark::State& state) {
  const control::OcpQp qp = NmpcSizedQp();
  using M17 = Eigen::Matrix<double, 17, 17>;
  using M4x17 = Eigen::Matrix<double, 4, 17>;
  std::vector<M17> A(20), P(21);
  std::vector<Eigen::Matrix<double, 17, 4>> B(20);
  for (int k = 0; k < 20; ++k) {
    A[k] = qp.A[k];
    B[k] = qp.B[k];
  }
  const M17 Q = qp.Q[0];
  const Eigen::Matrix4d R = Eigen::Matrix4d::Identity();
  for (auto _ : state) {
    P[20] = Q;
    for (int k = 19; k >= 0; --k) {
      const M17 PA = P[k + 1] * A[k];
      const Eigen::Matrix<double, 17, 4> PB = P[k + 1] * B[k];
      const M4x17 S = B[k].transpose() * PA;
      const Eigen::Matrix4d Ruu = R + B[k].transpose() * PB;
      const M4x17 K = Ruu.llt().solve(S);
      P[k] = Q + A[k].transpose() * PA - S.transpose() * K;
    }
    benchmark::DoNotOptimize(P[0].data());
  }
}
BENCHMARK(BM_RiccatiFactorisation);

// A call of the controller at 200 Hz: the feedback and the preparation for the next call. Arg 1:
// relinearise_every, the mixed-level iteration's period (1: the paper's RTI, 3: the navigation
// scenarios', 5: what a longer period would add); the time is the mean over the calls, linearising
// and reusing. Arg 2: the QP solver, 0 condensing (the default), 1 Riccati.
void BM_NmpcRealTimeIteration(benchmark::State& state) {
  const bool failed = state.range(0) != 0;
  control::NmpcOptions options;
  options.relinearise_every = static_cast<int>(state.range(1));
  options.qp_solver = state.range(2) == 0 ? control::OcpQpMethod::kCondensing : control::OcpQpMethod::kRiccati;
  control::NmpcController nmpc(ReferenceVehicle(), options);
  if (failed) nmpc.SetRotorFailed(0);
  planning::HoverOptions ho;
  ho.position_m = Vector3(0, 0, 1);
  const planning::HoverReference ref(ho);
  StateEstimate est;
  est.valid = true;
  est.p_W = Vector3(0.05, -0.02, 1.0);
  est.motor_thrust_n = RotorVector::Constant(4, 2.82);
  if (failed) est.w_B = Vector3(0.2, -0.1, 11.0);
  RotorVector cmd;
  double t = 0.0;
  nmpc.Compute(est, ref, t, 0.0, &cmd);
  for (auto _ : state) {
    t += 0.005;
    nmpc.Compute(est, ref, t, 0.005, &cmd);
    benchmark::DoNotOptimize(cmd.data());
  }
}
BENCHMARK(BM_NmpcRealTimeIteration)
    ->ArgsProduct({{0, 1}, {1, 3, 5}, {0, 1}})
    ->ArgNames({"failed", "relinearise_every", "riccati"});

}  // namespace
