// The control-rate path allocates nothing once warmed up: malloc is interposed in this test
// executable (allocation_counter.h) and counted while the NMPC, its QP solvers and the fault
// detector run; and in the planner's inner loop, the trajectory optimiser's cost and gradient
// (hundreds of evaluations a solve). Each QP solver alone: qp_contract_test.cc.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "allocation_counter.h"
#include "rotorguard/control/nmpc.h"
#include "rotorguard/fdd/composite_fdd.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/planning/trajectory_optimizer.h"
#include "vehicle_fixture.h"

namespace rotorguard::control {
namespace {

using rotorguard::testing::CountAllocations;

TEST(Allocation, TheCounterSeesAllocations) {
  // The counter itself must work, or the zero counts below would prove nothing.
  EXPECT_GT(CountAllocations([] { Eigen::VectorXd v(100); v.setZero(); }), 0);
  // Over-aligned allocations (operator new of an over-aligned type) take another entry point.
  EXPECT_EQ(CountAllocations([] {
              void* volatile p = std::aligned_alloc(64, 256);  // volatile: the pair is not elided
              std::free(p);
            }),
            1);
}

TEST(Allocation, NmpcRealTimeIterationsAllocateNothing) {
  // Every call linearising (the paper's RTI) and every third (the navigation scenarios'), with
  // either QP solver.
  for (const OcpQpMethod solver : {OcpQpMethod::kCondensing, OcpQpMethod::kRiccati})
    for (int failed : {-1, 0})
      for (int every : {1, 3}) {
        NmpcOptions options;
        options.relinearise_every = every;
        options.qp_solver = solver;
        NmpcController nmpc(rotorguard::testing::ReferenceQuad(), options);
        planning::LemniscateOptions lo;
        lo.center_m = Vector3(0, 0, 1.5);
        const planning::LemniscateReference ref(lo);
        StateEstimate est;
        est.valid = true;
        est.p_W = Vector3(0.1, -0.05, 1.45);
        est.w_B = Vector3(0.1, 0.2, failed >= 0 ? 10.0 : 0.3);
        est.motor_thrust_n = RotorVector::Constant(4, 2.82);
        RotorVector cmd;
        double t = 0.0;
        nmpc.Compute(est, ref, t, 0.0, &cmd);
        if (failed >= 0) nmpc.SetRotorFailed(failed);
        for (int k = 0; k < 5; ++k) nmpc.Compute(est, ref, t += 0.005, 0.005, &cmd);  // warm up
        const long n = CountAllocations([&] {
          for (int k = 0; k < 50; ++k) nmpc.Compute(est, ref, t += 0.005, 0.005, &cmd);
        });
        EXPECT_EQ(n, 0) << ToName(solver) << ", " << (failed >= 0 ? "after a failure" : "nominal")
                        << ", relinearise_every " << every;
        EXPECT_TRUE(nmpc.summary().IsSolutionUsable());
      }
}

TEST(Allocation, FaultDetectionAllocatesNothing) {
  const vehicle::VehicleParams vehicle = rotorguard::testing::ReferenceQuad();
  fdd::CompositeFdd detector(vehicle, {});
  EscTelemetry esc;
  esc.motor_speed_rad_s = RotorVector::Constant(4, std::sqrt(2.82 / vehicle.thrust_coefficient_n_s2));
  ImuSample imu;
  imu.specific_force_B = Vector3(0, 0, kGravity);
  StateEstimate est;
  est.valid = true;
  est.p_W = Vector3(0, 0, 1);
  const auto step = [&](TimeNs t) {
    esc.t_ns = imu.t_ns = est.t_ns = t;
    detector.OnEscTelemetry(esc);
    detector.OnImu(imu);
    detector.SetEstimate(est);
    detector.SetCommand(RotorCommand{t, RotorVector::Constant(4, 2.82)});
  };
  for (int k = 0; k < 10; ++k) step(k * 3'000'000);
  EXPECT_EQ(CountAllocations([&] {
              for (int k = 10; k < 200; ++k) step(k * 3'000'000);
            }),
            0);
}

TEST(Allocation, TrajectoryObjectiveAllocatesNothingOnceWarm) {
  // A 5-piece problem, in free space and with obstacle planes; the second evaluation of a size
  // on a thread reuses the first's buffers.
  planning::TrajectoryOptimizerOptions o;
  const planning::TrajectoryOptimizer optimizer(o);
  planning::PvaState head = planning::PvaState::Zero(), tail = planning::PvaState::Zero();
  tail.col(0) = Vector3(8.0, 2.0, 1.0);
  Eigen::Matrix3Xd waypoints(3, 4);
  waypoints << 1.5, 3.5, 5.0, 6.5, 0.5, 1.0, 2.5, 2.0, 0.5, 1.0, 0.8, 1.2;
  const Eigen::VectorXd x = planning::TrajectoryOptimizer::Variables(waypoints, Eigen::VectorXd::Constant(5, 2.0));
  planning::PlaneSet planes(5);
  planes[1].push_back({3, {Vector3(3.0, 0.2, 1.0), Vector3(0.0, 1.0, 0.0)}});
  planes[1].push_back({4, {Vector3(3.2, 0.3, 1.0), Vector3(0.0, 1.0, 0.0)}});
  const planning::DynamicLimits limits{1.0, 2.0, 6.0};
  for (const planning::PlaneSet& p : {planning::PlaneSet{}, planes}) {
    Eigen::VectorXd gradient(x.size());
    double cost = optimizer.Objective(head, tail, limits, p, x, &gradient);
    EXPECT_EQ(CountAllocations([&] {
                for (int k = 0; k < 20; ++k) cost += optimizer.Objective(head, tail, limits, p, x, &gradient);
              }),
              0);
    EXPECT_TRUE(std::isfinite(cost));
  }
}

}  // namespace
}  // namespace rotorguard::control
