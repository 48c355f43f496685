#pragma once
/// A trial in a child process, under a wall-clock budget: the watchdog of campaigns (campaign.h,
/// CampaignRunOptions::trial_timeout_factor). A thread that loops or crashes cannot be stopped
/// without taking the shard with it; a process can: it is killed when its budget runs out, and a
/// crash (a signal, an abort, the out-of-memory killer) ends only it.
///
/// The child is forked from the worker thread that runs the trial. Only that thread exists in the
/// child; the C library's fork handlers leave its allocator usable, and the child ends with _exit,
/// flushing no buffer it inherited.
#include <functional>
#include <string>

namespace rotorguard::campaign::internal {

struct IsolatedRun {
  enum class Kind {
    kFinished,  ///< the body returned; `text` is what it returned
    kTimeout,   ///< the budget ran out: the child was killed
    kCrashed    ///< the child died otherwise: `message` says how
  };
  Kind kind = Kind::kFinished;
  std::string text;
  std::string message;
  double wall_s = 0.0;  ///< from the fork to the child's end
};

/// Runs `body` in a child process and returns its text, or how the child ended. `budget_s` <= 0
/// or not finite: no budget. Throws std::runtime_error when no child can be started (no pipe, no
/// fork), which the caller records like any trial's error.
IsolatedRun RunIsolated(const std::function<std::string()>& body, double budget_s);

}  // namespace rotorguard::campaign::internal
