#include "rotorguard/runtime/clock.h"

#include "rotorguard/core/error.h"

#include <cerrno>
#include <cmath>
#include <ctime>

namespace rotorguard::runtime {

namespace {
constexpr TimeNs kStopCheckNs = 100'000'000;  // a sleeper looks at the stop flag at least this often
}  // namespace

TimeNs SteadyClock::Monotonic() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * kNanosPerSecond + ts.tv_nsec;
}

SteadyClock::SteadyClock() : origin_(Monotonic()) {}

SteadyClock::SteadyClock(TimeNs origin, double rate) : origin_(origin), rate_(rate) {
  if (!(rate > 0.0 && rate <= 1000.0)) ThrowValidation("SteadyClock", "rate", rate, "in (0, 1000]");
}

TimeNs SteadyClock::Now() const {
  const TimeNs wall = Monotonic() - origin_;
  return rate_ == 1.0 ? wall : static_cast<TimeNs>(std::llround(static_cast<double>(wall) * rate_));
}

bool SteadyClock::SleepUntil(TimeNs t) {
  const TimeNs until =
      origin_ + (rate_ == 1.0 ? t : static_cast<TimeNs>(std::ceil(static_cast<double>(t) / rate_)));
  const timespec ts{static_cast<time_t>(until / kNanosPerSecond), static_cast<long>(until % kNanosPerSecond)};
  // An absolute sleep: a signal's interruption resumes towards the same instant, no drift.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
  return true;
}

void SimulatedTime::Advance(TimeNs t) {
  TimeNs current = now.load(std::memory_order_relaxed);
  while (t > current && !now.compare_exchange_weak(current, t, std::memory_order_acq_rel)) {
  }
  advanced.Ring();
}

void SimulatedTime::Stop() {
  stopped.store(true, std::memory_order_release);
  advanced.Ring();
}

bool SimulatedClock::SleepUntil(TimeNs t) {
  for (;;) {
    const std::uint32_t seen = time_->advanced.Count();
    if (Now() >= t) return true;
    if (time_->stopped.load(std::memory_order_acquire)) return false;
    time_->advanced.Wait(seen, kStopCheckNs);
  }
}

}  // namespace rotorguard::runtime
