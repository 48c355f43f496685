#pragma once
/// Facts about this program and the machine it runs on, recorded with every benchmark result and
/// campaign manifest so that a figure can be traced to the build and the host that produced it.
#include <nlohmann/json.hpp>
#include <string>

namespace rotorguard::buildinfo {

/// The release, "MAJOR.MINOR.PATCH" (the CMake project's version).
std::string Version();

/// The source revision this program was built from: git's short hash, "-dirty" appended when the
/// working tree had changes; "unknown" outside a clone.
std::string GitRevision();

/// "VERSION (REVISION)": what campaign manifests record and a resume or a merge checks.
std::string ProgramVersion();

/// Host facts: {"cpu": model name, "hardware_threads", "compiler", "version", "git_revision"}.
nlohmann::json HostInfo();

}  // namespace rotorguard::buildinfo
