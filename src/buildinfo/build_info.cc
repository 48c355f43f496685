#include "rotorguard/buildinfo/build_info.h"

#include <fstream>
#include <thread>

#include "rotorguard_git_revision.h"  // generated at build time

namespace rotorguard::buildinfo {

namespace {

std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  }
  return "unknown";
}

}  // namespace

std::string Version() { return ROTORGUARD_VERSION; }

std::string GitRevision() { return ROTORGUARD_GIT_REVISION; }

std::string ProgramVersion() { return Version() + " (" + GitRevision() + ")"; }

nlohmann::json HostInfo() {
  return {{"cpu", CpuModel()},
          {"hardware_threads", std::thread::hardware_concurrency()},
          {"compiler", __VERSION__},
          {"version", Version()},
          {"git_revision", GitRevision()}};
}

}  // namespace rotorguard::buildinfo
