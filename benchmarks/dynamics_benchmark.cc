// Micro-benchmarks of the truth model: one derivative evaluation, one RK4 step, one simulator step
// with every sensor. Run: build/bin/dynamics_benchmark
#include <benchmark/benchmark.h>

#include "rotorguard/harness/scenario.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/vehicle/multirotor.h"

namespace {

using namespace rotorguard;

vehicle::VehicleParams ReferenceVehicle() {
  return harness::LoadVehicle(std::string(ROTORGUARD_SOURCE_DIR) + "/configs/vehicles/zhou2025_quad.yaml");
}

void BM_Derivative(benchmark::State& state) {
  const vehicle::MultirotorModel model(ReferenceVehicle());
  vehicle::StateVector x = model.MakeState(Vector3(0, 0, 1), 0.3, model.HoverThrusts());
  x.segment<3>(vehicle::StateIndex::kBodyRate) = Vector3(0.5, -0.2, 11.0);
  const vehicle::RotorFaults faults(4);
  vehicle::StateVector x_dot;
  const RotorVector u = model.HoverThrusts();
  for (auto _ : state) {
    model.Derivative(x, u, faults, vehicle::Disturbance{}, &x_dot);
    benchmark::DoNotOptimize(x_dot.data());
  }
}
BENCHMARK(BM_Derivative);

void BM_Rk4Step(benchmark::State& state) {
  const vehicle::MultirotorModel model(ReferenceVehicle());
  vehicle::Rk4Integrator rk4(model);
  vehicle::StateVector x = model.MakeState(Vector3(0, 0, 1), 0.3, model.HoverThrusts());
  const vehicle::RotorFaults faults(4);
  const RotorVector u = model.HoverThrusts();
  for (auto _ : state) {
    rk4.Step(u, faults, vehicle::Disturbance{}, 1e-3, &x);
    benchmark::DoNotOptimize(x.data());
  }
}
BENCHMARK(BM_Rk4Step);

void BM_SimulatorStep(benchmark::State& state) {
  const vehicle::MultirotorModel model(ReferenceVehicle());
  sim::Simulator sim(model, {}, {}, sim::SimulatorOptions{}, 1,
                     model.MakeState(Vector3(0, 0, 1e6), 0.0, model.HoverThrusts()));
  RotorCommand hover;
  hover.thrust_n = model.HoverThrusts();
  for (auto _ : state) benchmark::DoNotOptimize(&sim.Step(hover));
}
BENCHMARK(BM_SimulatorStep);

}  // namespace
