// Compiled only by the layering tests of tests/stack/CMakeLists.txt: code that wants both the
// flight stack and the simulator's truth (the drawn vehicle first, then the simulator). Linked
// with `stack` alone it must not compile.
#include "rotorguard/sim/truth.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/stack/flight_stack.h"

int main() {
  return sizeof(rotorguard::sim::TruthDraw) > 0 && sizeof(rotorguard::sim::Simulator) > 0 &&
                 sizeof(rotorguard::stack::FlightStack) > 0
             ? 0
             : 1;
}
