#pragma once
/// StackObserver: what the flight stack was given and what it answered, as a recorder sees it
/// (`run --bag`, `sitl --bag`: docs/ros.md). The simulator's side calls it on its own thread; it
/// never sees the truth, only the sensor messages and the cycles' telemetry.
#include "rotorguard/core/types.h"
#include "rotorguard/runtime/onboard_executor.h"
#include "rotorguard/sim/simulator.h"

namespace rotorguard::harness {

class StackObserver {
 public:
  virtual ~StackObserver() = default;
  /// A simulator step's sensor messages, handed to the stack at `t` on the simulator's time.
  virtual void OnSensors(TimeNs t, const sim::SensorOutputs& outputs) = 0;
  /// A control cycle's telemetry as the stack reported it (in the order the cycles came).
  virtual void OnCycle(const runtime::CycleTelemetry& cycle) = 0;
  /// The flight has ended and its outputs are written: finish the recording.
  virtual void Finish() = 0;
};

}  // namespace rotorguard::harness
