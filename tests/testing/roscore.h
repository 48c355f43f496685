#pragma once
// A ROS master of a test's own: `roscore` on a free port, its logs in a temporary ROS_HOME, and
// ROS_MASTER_URI and ROS_HOME set for the test's process and the programs it starts; stopped
// (the whole process group) when the fixture goes. C++17, for the ROS tests of both standards.
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>

namespace rotorguard::testing {

/// A TCP port no one listens on now (the kernel's choice).
inline int FreePort() {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t n = sizeof(a);
  if (bind(s, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0 || getsockname(s, reinterpret_cast<sockaddr*>(&a), &n) != 0) {
    close(s);
    throw std::runtime_error("FreePort: no port");
  }
  close(s);
  return ntohs(a.sin_port);
}

/// Whether something accepts TCP connections on the loopback's `port`.
inline bool Listening(int port) {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool ok = connect(s, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
  close(s);
  return ok;
}

class Roscore {
 public:
  Roscore() {
    port_ = FreePort();
    uri_ = "http://localhost:" + std::to_string(port_);
    char dir[] = "/tmp/rotorguard-ros-XXXXXX";
    if (!mkdtemp(dir)) throw std::runtime_error("Roscore: no temporary folder");
    home_ = dir;
    setenv("ROS_MASTER_URI", uri_.c_str(), 1);
    setenv("ROS_HOME", home_.c_str(), 1);
    const std::string log = home_ + "/roscore.log", port = std::to_string(port_);
    posix_spawn_file_actions_t files;
    posix_spawn_file_actions_init(&files);
    posix_spawn_file_actions_addopen(&files, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&files, 1, 2);
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);  // its own group: rosmaster and rosout stop with it
    posix_spawnattr_setpgroup(&attr, 0);
    const char* argv[] = {"roscore", "-p", port.c_str(), nullptr};
    const int e = posix_spawnp(&pid_, "roscore", &files, &attr, const_cast<char* const*>(argv), environ);
    posix_spawn_file_actions_destroy(&files);
    posix_spawnattr_destroy(&attr);
    if (e != 0) throw std::runtime_error("Roscore: cannot start roscore (ros-core-dev: scripts/install-deps.sh)");
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!Listening(port_)) {
      if (std::chrono::steady_clock::now() > until) throw std::runtime_error("Roscore: the master did not come up; see " + log);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  ~Roscore() {
    kill(-pid_, SIGINT);
    for (int i = 0; i < 50 && waitpid(pid_, nullptr, WNOHANG) == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    kill(-pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    std::error_code ec;
    std::filesystem::remove_all(home_, ec);
  }
  Roscore(const Roscore&) = delete;
  Roscore& operator=(const Roscore&) = delete;
  const std::string& uri() const { return uri_; }
  const std::string& home() const { return home_; }

 private:
  int port_ = 0;
  pid_t pid_ = 0;
  std::string uri_, home_;
};

}  // namespace rotorguard::testing
