#pragma once
/// Wall-clock time of a computation: the solve times of the solvers' summaries, the stack's cost per
/// cycle, the benchmarks' speeds. steady_clock is monotonic: a change of the system's clock does not
/// move it.
#include <chrono>

namespace rotorguard {

class Stopwatch {
 public:
  using Clock = std::chrono::steady_clock;

  Stopwatch() : start_(Clock::now()) {}

  /// Time since construction or the last Restart().
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  double milliseconds() const { return 1e3 * seconds(); }

  /// Starts again from now and returns the seconds up to now (consecutive laps add up to the whole).
  double Restart() {
    const Clock::time_point now = Clock::now();
    const double lap = std::chrono::duration<double>(now - start_).count();
    start_ = now;
    return lap;
  }

 private:
  Clock::time_point start_;
};

}  // namespace rotorguard
