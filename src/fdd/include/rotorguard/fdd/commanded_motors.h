#pragma once
/// The motors as the commands drive them: what a fault detector expects the rotors to do. Each
/// command acts `delay_s` after the instant it was computed for (the computation and the ESCs'
/// latency the stack expects), and a motor follows the command acting on it through the first-order
/// lag of paper 000's eq. (6), integrated exactly piece by piece between the instants commands
/// start acting. Nothing is allocated after construction.
///
/// RotorHistory and HealthyThrustFloor bound the other way: how low a healthy motor can be now,
/// whatever its delay and however much faster than the file it is (the motor shortfall rule,
/// docs/fdd.md).
#include <array>
#include <optional>
#include <vector>

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

/// Timed per-rotor values of the last span (the commands sent, or the thrusts measured), in a ring
/// fixed at construction: when full, a new entry drops the oldest, and a query reaching before what
/// is kept has no answer. The motor shortfall rule asks for the lowest command that can have acted
/// over an interval, whatever the delay, and for the thrust measured a window ago.
class RotorHistory {
 public:
  /// Holds up to `capacity` >= 2 entries. Throws std::invalid_argument.
  RotorHistory(int num_rotors, int capacity);
  /// Values for time t; one older than the latest is ignored, one for the same instant replaces it.
  void Push(TimeNs t, const RotorVector& values);
  TimeNs newest_time() const;  ///< the latest entry's time; empty(): undefined
  bool empty() const { return size_ == 0; }
  /// Per rotor, the lowest value in force at some instant of [from, to]: the entries within it and
  /// the one in force at `from` (the latest before it). False, `lowest` untouched, when the history
  /// does not reach back to `from` (no entry at or before it is kept).
  bool LowestOver(TimeNs from, TimeNs to, RotorVector* lowest) const;
  /// The latest entry at or before t (its index for time() and values()), if one is kept.
  std::optional<std::size_t> LatestAtOrBefore(TimeNs t) const;
  TimeNs time(std::size_t index) const { return t_[index]; }
  const RotorVector& values(std::size_t index) const { return values_[index]; }

 private:
  std::vector<TimeNs> t_;
  std::vector<RotorVector> values_;
  std::size_t head_ = 0, size_ = 0;  // the oldest entry, and how many
};

/// The lowest thrust [N] a healthy motor can give `window_s` after it gave `start_n`, while every
/// command acting on it was at least `lowest_command_n`, for any time constant >= `min_time_constant_s`
/// > 0. Eq. (6) is linear with a positive gain, so its solutions are ordered by their inputs and start:
/// the motor is above the one driven by the lowest command throughout, c + (T0 - c) e^(-W/sigma),
/// which falls fastest with the shortest sigma; a motor below that command rises, and stays above
/// where it started.
double HealthyThrustFloor(double start_n, double lowest_command_n, double window_s, double min_time_constant_s);

}  // namespace rotorguard::fdd
