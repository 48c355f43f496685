#include "watchdog.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <signal.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace rotorguard::campaign::internal {

namespace {

/// Writes all of `text` to `fd` (the child's end of the pipe); false when the parent is gone.
bool WriteAll(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

std::string HowItEnded(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = sigabbrev_np(sig);
    return fmt::format("the trial's process was killed by signal {} (SIG{}){}", sig, name ? name : "?",
                       sig == SIGKILL ? ", perhaps by the out-of-memory killer" : "");
  }
  if (WIFEXITED(status)) return fmt::format("the trial's process exited with status {}", WEXITSTATUS(status));
  return "the trial's process ended abnormally";
}

}  // namespace

IsolatedRun RunIsolated(const std::function<std::string()>& body, double budget_s) {
  using Clock = std::chrono::steady_clock;
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    throw std::runtime_error(fmt::format("cannot start the trial's process: pipe: {}", ::strerror(errno)));
  }
  const Clock::time_point start = Clock::now();
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int e = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error(fmt::format("cannot start the trial's process: fork: {}", ::strerror(e)));
  }
  if (pid == 0) {
    // A campaign killed outright takes its trials with it rather than leave them running
    // unwatched (the signal comes when the forking thread ends; it outlives its children).
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(4);  // it ended before the line above
    ::close(fds[0]);
    // The body records its own exceptions; one that escapes is a crash like any other.
    const bool written = WriteAll(fds[1], body());
    ::_exit(written ? 0 : 3);
  }
  ::close(fds[1]);
  IsolatedRun run;
  const bool budgeted = std::isfinite(budget_s) && budget_s > 0.0;
  const Clock::time_point deadline =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(budgeted ? budget_s : 0.0));
  char buffer[1 << 16];
  for (;;) {
    int wait_ms = -1;
    if (budgeted) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) {
        run.kind = IsolatedRun::Kind::kTimeout;
        break;
      }
      wait_ms = static_cast<int>(std::min<long long>(left + 1, 60'000));
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, wait_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;  // the deadline is checked above
    const ssize_t n = ::read(fds[0], buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // the child closed its end: it is done
    run.text.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  if (run.kind == IsolatedRun::Kind::kTimeout) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  run.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  if (run.kind == IsolatedRun::Kind::kTimeout) {
    run.text.clear();
  } else if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
    run.kind = IsolatedRun::Kind::kCrashed;
    run.message = HowItEnded(status);
    run.text.clear();
  }
  return run;
}

}  // namespace rotorguard::campaign::internal
