#pragma once
/// How long a control cycle's computation holds its command back from the ESCs: the truth's drawn
/// delay within its jitter, or the stack's measured wall-clock time for the cycle
/// (sim.computation_delay: measured). The ideal world draws none: its commands act at their
/// cycle's instant.
#include <cstdint>

#include "rotorguard/core/rng.h"
#include "rotorguard/core/types.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/sim/truth.h"

namespace rotorguard::harness {

class ComputationDelayModel {
 public:
  /// The delays of a flight whose truth is `draw`, jittered by a stream of `seed`.
  ComputationDelayModel(ComputationDelay kind, const sim::TruthDraw& draw, std::uint64_t seed);
  /// The delay of a cycle that took `cycle_s` of wall-clock time [ns].
  TimeNs Next(double cycle_s);

 private:
  ComputationDelay kind_;
  double delay_s_, jitter_;
  Rng rng_;
};

}  // namespace rotorguard::harness
