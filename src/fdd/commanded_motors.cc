#include "rotorguard/fdd/commanded_motors.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"

namespace rotorguard::fdd {

CommandedMotors::CommandedMotors(int num_rotors, double time_constant_s, double delay_s)
    : time_constant_s_(time_constant_s), delay_ns_(FromSeconds(delay_s)) {
  if (num_rotors < 1 || num_rotors > kMaxRotors) {
    ThrowInvalidArgument("CommandedMotors", "num_rotors", num_rotors, fmt::format("a count in [1, {}]", kMaxRotors));
  }
  if (!(time_constant_s > 0.0) || !std::isfinite(time_constant_s)) {
    ThrowInvalidArgument("CommandedMotors", "time_constant_s", time_constant_s, "a time constant > 0 [s]");
  }
  if (!(delay_s >= 0.0) || !std::isfinite(delay_s)) {
    ThrowInvalidArgument("CommandedMotors", "delay_s", delay_s, "a delay >= 0 [s]");
  }
  acting_ = thrust_ = RotorVector::Zero(num_rotors);
  for (Command& c : queue_) c.thrust_n = RotorVector::Zero(num_rotors);
}

void CommandedMotors::OnCommand(TimeNs t, const RotorVector& thrust_n) {
  if (thrust_n.size() != acting_.size() || !thrust_n.allFinite()) return;
  const TimeNs acts = t + delay_ns_;
  if (size_ > 0) {
    Command& last = queue_[static_cast<std::size_t>((head_ + size_ - 1) % kCommands)];
    if (acts < last.acts_ns) return;
    if (acts == last.acts_ns) {  // a command for the same instant replaces it (an overridden cycle's)
      last.thrust_n = thrust_n;
      return;
    }
  }
  if (size_ == kCommands) {  // full: the oldest acts now
    acting_ = queue_[static_cast<std::size_t>(head_)].thrust_n;
    head_ = (head_ + 1) % kCommands;
    --size_;
  }
  Command& c = queue_[static_cast<std::size_t>((head_ + size_) % kCommands)];
  c.acts_ns = acts;
  c.thrust_n = thrust_n;
  ++size_;
}

void CommandedMotors::Start(TimeNs t, const RotorVector& thrust_n) {
  // Until a command acts, the motors hold what they do.
  if (thrust_n.size() == thrust_.size() && thrust_n.allFinite()) acting_ = thrust_ = thrust_n;
  t_ns_ = t;
  started_ = true;
  Activate(t);
}

void CommandedMotors::Activate(TimeNs t) {
  while (size_ > 0 && queue_[static_cast<std::size_t>(head_)].acts_ns <= t) {
    acting_ = queue_[static_cast<std::size_t>(head_)].thrust_n;
    head_ = (head_ + 1) % kCommands;
    --size_;
  }
}

const RotorVector& CommandedMotors::AdvanceTo(TimeNs t) {
  if (!started_) Start(t, thrust_);
  if (t <= t_ns_) return thrust_;
  Activate(t_ns_);
  // Eq. (6), T_dot = (u - T) / σ, exactly over each piece in which one command acts.
  while (t_ns_ < t) {
    const TimeNs next = size_ > 0 ? std::min(t, queue_[static_cast<std::size_t>(head_)].acts_ns) : t;
    const double blend = 1.0 - std::exp(-ToSeconds(next - t_ns_) / time_constant_s_);
    thrust_ += blend * (acting_ - thrust_);
    t_ns_ = next;
    Activate(t_ns_);
  }
  return thrust_;
}

RotorHistory::RotorHistory(int num_rotors, int capacity) {
  if (num_rotors < 1 || num_rotors > kMaxRotors) {
    ThrowInvalidArgument("RotorHistory", "num_rotors", num_rotors, fmt::format("a count in [1, {}]", kMaxRotors));
  }
  if (capacity < 2) ThrowInvalidArgument("RotorHistory", "capacity", capacity, "a capacity >= 2");
  t_.assign(static_cast<std::size_t>(capacity), 0);
  values_.assign(static_cast<std::size_t>(capacity), RotorVector::Zero(num_rotors));
}

TimeNs RotorHistory::newest_time() const { return t_[(head_ + size_ + t_.size() - 1) % t_.size()]; }

void RotorHistory::Push(TimeNs t, const RotorVector& values) {
  if (values.size() != values_.front().size() || !values.allFinite()) return;
  const std::size_t n = t_.size();
  if (size_ > 0) {
    const std::size_t last = (head_ + size_ - 1) % n;
    if (t < t_[last]) return;
    if (t == t_[last]) {
      values_[last] = values;
      return;
    }
  }
  if (size_ == n) {
    head_ = (head_ + 1) % n;
    --size_;
  }
  const std::size_t k = (head_ + size_) % n;
  t_[k] = t;
  values_[k] = values;
  ++size_;
}

std::optional<std::size_t> RotorHistory::LatestAtOrBefore(TimeNs t) const {
  for (std::size_t k = size_; k-- > 0;) {
    const std::size_t j = (head_ + k) % t_.size();
    if (t_[j] <= t) return j;
  }
  return std::nullopt;
}

bool RotorHistory::LowestOver(TimeNs from, TimeNs to, RotorVector* lowest) const {
  const std::size_t n = t_.size();
  if (size_ == 0 || t_[head_] > from) return false;
  // From the newest back: the entries after `to` are not in force in the interval; the first one
  // at or before `from` is the one in force there, and the last needed.
  bool any = false;
  for (std::size_t k = size_; k-- > 0;) {
    const std::size_t j = (head_ + k) % n;
    if (t_[j] > to) continue;
    *lowest = any ? lowest->cwiseMin(values_[j]) : values_[j];
    any = true;
    if (t_[j] <= from) break;
  }
  return any;
}

double HealthyThrustFloor(double start_n, double lowest_command_n, double window_s, double min_time_constant_s) {
  const double settled = lowest_command_n + (start_n - lowest_command_n) * std::exp(-window_s / min_time_constant_s);
  return std::min(start_n, settled);
}

}  // namespace rotorguard::fdd
