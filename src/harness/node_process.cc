#include "rotorguard/harness/node_process.h"

#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <stdexcept>
#include <utility>

namespace rotorguard::harness {

NodeProcess::NodeProcess(const std::vector<std::string>& argv, std::string who) : who_(std::move(who)) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  if (const int e = posix_spawnp(&pid, args[0], nullptr, nullptr, args.data(), environ); e != 0) {
    throw std::runtime_error(fmt::format("{}: cannot start the node '{}': {}", who_, argv[0], std::strerror(e)));
  }
  pid_ = pid;
}

NodeProcess::~NodeProcess() {
  if (pid_ > 0) {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
}

NodeProcess::NodeProcess(NodeProcess&& other) noexcept
    : pid_(std::exchange(other.pid_, 0)), who_(std::move(other.who_)) {}

NodeProcess& NodeProcess::operator=(NodeProcess&& other) noexcept {
  if (this != &other) {
    NodeProcess gone(std::move(*this));
    pid_ = std::exchange(other.pid_, 0);
    who_ = std::move(other.who_);
  }
  return *this;
}

void NodeProcess::ThrowIfExited(const char* doing) {
  int status = 0;
  if (pid_ <= 0 || waitpid(pid_, &status, WNOHANG) != pid_) return;
  pid_ = 0;
  throw std::runtime_error(fmt::format("{}: the node exited ({}) before it could {}", who_,
                                       WIFEXITED(status) ? fmt::format("status {}", WEXITSTATUS(status))
                                                         : fmt::format("signal {}", WTERMSIG(status)),
                                       doing));
}

void NodeProcess::Wait() {
  if (pid_ > 0) waitpid(pid_, nullptr, 0);
  pid_ = 0;
}

}  // namespace rotorguard::harness
