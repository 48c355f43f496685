#include "rotorguard/fdd/commanded_motors.h"

#include <fmt/format.h>

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

}  // namespace rotorguard::fdd
