// Example 1: the simulator and the flight stack wired by hand, without scenario files.
// A vehicle file gives the parameters; the simulator produces sensor messages; the stack (here with
// the nominal controller) turns them into rotor commands. Prints the position once a second.
#include <cstdio>
#include <memory>

#include "rotorguard/harness/scenario.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/stack/flight_stack.h"

int main() {
  using namespace rotorguard;
  const vehicle::VehicleParams params =
      harness::LoadVehicle(std::string(ROTORGUARD_SOURCE_DIR) + "/configs/vehicles/zhou2025_quad.yaml");
  const vehicle::MultirotorModel truth(params);

  // The simulator starts the vehicle hovering at 1 m; the stack is asked to hold 1.5 m.
  sim::Simulator simulator(truth, sim::World{}, /*faults=*/{}, sim::SimulatorOptions{}, /*seed=*/7,
                           truth.MakeState(Vector3(0, 0, 1.0), 0.0, truth.HoverThrusts()));
  planning::HoverOptions hover;
  hover.position_m = Vector3(0, 0, 1.5);
  stack::FlightStack flight_stack(params, std::make_shared<planning::HoverReference>(hover), {});

  const auto deliver = [&](const sim::SensorOutputs& o) {
    if (o.imu) flight_stack.OnImu(*o.imu);
    if (o.esc) flight_stack.OnEscTelemetry(*o.esc);
    if (o.odometry) flight_stack.OnOdometry(*o.odometry);
  };
  deliver(simulator.outputs());
  RotorCommand command = flight_stack.command();
  for (int k = 0; k < 5000; ++k) {  // 5 s at 1 kHz, the controller at 200 Hz
    if (k % 5 == 0) command = flight_stack.Update(simulator.time_ns());
    deliver(simulator.Step(command));
    if (k % 1000 == 999) {
      const vehicle::StateView s(simulator.state());
      std::printf("t = %.1f s  z = %.3f m\n", simulator.time_s(), s.p_W().z());
    }
  }
  const double z = vehicle::StateView(simulator.state()).p_W().z();
  return std::abs(z - 1.5) < 0.05 && !simulator.crashed() ? 0 : 1;
}
