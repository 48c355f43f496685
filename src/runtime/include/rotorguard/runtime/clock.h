#pragma once
/// The clocks the onboard runtime's loops follow (docs/runtime.md, "Clocks and scheduling"). On a
/// vehicle: the steady clock (CLOCK_MONOTONIC; a change of the system's date does not move it).
/// In software in the loop: the simulator's time, which the simulator advances and every loop of
/// the stack, in its own process, follows, so that a flight runs at real time or faster or slower
/// and both sides agree on every stamp.
#include <atomic>

#include "rotorguard/core/types.h"
#include "rotorguard/runtime/doorbell.h"

namespace rotorguard::runtime {

class Clock {
 public:
  virtual ~Clock() = default;
  /// Now on this clock [ns].
  virtual TimeNs Now() const = 0;
  /// Sleeps until Now() >= t; returns at once when t has passed. False when the clock stopped
  /// (the simulation ended) before t.
  virtual bool SleepUntil(TimeNs t) = 0;
};

/// CLOCK_MONOTONIC, counted from its construction (or from `origin`, a CLOCK_MONOTONIC time in ns),
/// running at `rate` times real time: rate 1 on a vehicle; in software in the loop the simulator
/// and the stack follow one such clock (the same origin and rate, in two processes as in one), and
/// a flight runs at real time (1), faster or slower.
class SteadyClock final : public Clock {
 public:
  SteadyClock();
  explicit SteadyClock(TimeNs origin, double rate = 1.0);
  TimeNs Now() const override;
  bool SleepUntil(TimeNs t) override;
  TimeNs origin() const { return origin_; }
  double rate() const { return rate_; }
  /// CLOCK_MONOTONIC now [ns]: an origin for clocks that must agree.
  static TimeNs Monotonic();

 private:
  TimeNs origin_;
  double rate_ = 1.0;
};

/// The simulated time one simulator publishes and the stack's loops follow; it may live in memory
/// shared between processes (it holds only lock-free atomics).
struct SimulatedTime {
  SimulatedTime() = default;
  /// Starts at `start`: -1 keeps a loop waiting for time 0 until the simulator has reached it.
  explicit SimulatedTime(TimeNs start) : now(start) {}
  std::atomic<TimeNs> now{0};
  std::atomic<bool> stopped{false};
  Doorbell advanced;  // rung on every advance and at the stop
  /// The simulator: time moves to t (never back).
  void Advance(TimeNs t);
  /// The simulator: the simulation ended; sleepers wake and are told.
  void Stop();
};

class SimulatedClock final : public Clock {
 public:
  explicit SimulatedClock(SimulatedTime* time) : time_(time) {}
  TimeNs Now() const override { return time_->now.load(std::memory_order_acquire); }
  bool SleepUntil(TimeNs t) override;

 private:
  SimulatedTime* time_;
};

}  // namespace rotorguard::runtime
