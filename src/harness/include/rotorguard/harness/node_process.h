#pragma once
/// NodeProcess: the stack's process of a two-process flight (`rotorguard node ...`), started by
/// the simulator's side and killed if it is still running when this is destroyed (a failure on
/// the way must not leave it behind).
#include <string>
#include <vector>

namespace rotorguard::harness {

class NodeProcess {
 public:
  NodeProcess() = default;
  /// Starts `argv` (argv[0] searched on PATH). `who` prefixes the errors ("sitl", "sitl --ros").
  /// Throws std::runtime_error naming the program when it cannot be started.
  NodeProcess(const std::vector<std::string>& argv, std::string who);
  ~NodeProcess();
  NodeProcess(NodeProcess&& other) noexcept;
  NodeProcess& operator=(NodeProcess&& other) noexcept;
  NodeProcess(const NodeProcess&) = delete;
  NodeProcess& operator=(const NodeProcess&) = delete;
  /// Throws std::runtime_error "WHO: the node exited (status N) before it could DOING" when the
  /// process has ended.
  void ThrowIfExited(const char* doing);
  /// Waits for the process to end.
  void Wait();
  bool running() const { return pid_ > 0; }

 private:
  int pid_ = 0;
  std::string who_;
};

}  // namespace rotorguard::harness
