#pragma once
/// The motors as the commands drive them: what a fault detector expects the rotors to do. Each
/// command acts `delay_s` after the instant it was computed for (the computation and the ESCs'
/// latency the stack expects), and a motor follows the command acting on it through the first-order
/// lag of paper 000's eq. (6), integrated exactly piece by piece between the instants commands
/// start acting. Nothing is allocated after construction.
#include <array>

#include "rotorguard/core/types.h"

namespace rotorguard::fdd {

class CommandedMotors {
 public:
  /// `time_constant_s` > 0 (the vehicle file's σ), `delay_s` >= 0. Throws std::invalid_argument.
  CommandedMotors(int num_rotors, double time_constant_s, double delay_s);

  /// A command computed for time t [ns] (thrust per rotor [N]; clamped to [0, max] by the
  /// caller when it should be). Commands must come in time order; an older one is ignored.
  void OnCommand(TimeNs t, const RotorVector& thrust_n);
  /// The modelled thrusts start at `thrust_n` at time t (the motors as measured, or at rest), and
  /// hold there until a command acts.
  void Start(TimeNs t, const RotorVector& thrust_n);
  /// Advances the modelled thrusts to time t (before Start: they start at t at zero). A t before
  /// the model's time leaves it where it is.
  const RotorVector& AdvanceTo(TimeNs t);
  const RotorVector& thrust() const { return thrust_; }
  bool started() const { return started_; }

 private:
  static constexpr int kCommands = 8;  // commands waiting for their instant: a delay of 8 cycles
  struct Command {
    TimeNs acts_ns = 0;
    RotorVector thrust_n;
  };
  /// The commands whose instant has come by t act, in order.
  void Activate(TimeNs t);

  double time_constant_s_;
  TimeNs delay_ns_;
  std::array<Command, kCommands> queue_;
  int head_ = 0, size_ = 0;
  RotorVector acting_, thrust_;
  TimeNs t_ns_ = 0;
  bool started_ = false;
};

}  // namespace rotorguard::fdd
