// The targets of fuzz_targets.h under libFuzzer (clang, `make fuzz`): coverage-guided, with
// AddressSanitizer and UndefinedBehaviorSanitizer. The target is named by the environment variable
// ROTORGUARD_FUZZ_TARGET, as libFuzzer owns the command line (scripts/fuzz.sh sets it): `list`
// prints the targets, and with ROTORGUARD_FUZZ_SEEDS=1 the target's seed files are printed instead
// of fuzzed.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "fuzz_targets.h"

namespace {
const rotorguard::fuzz::Target* g_target = nullptr;
}

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  const char* name = std::getenv("ROTORGUARD_FUZZ_TARGET");
  if (name != nullptr && std::string_view(name) == "list") {
    for (const auto& t : rotorguard::fuzz::Targets())
      std::printf("target: %.*s\n", static_cast<int>(t.name.size()), t.name.data());
    std::exit(0);
  }
  g_target = name == nullptr ? nullptr : rotorguard::fuzz::FindTarget(name);
  if (g_target != nullptr && std::getenv("ROTORGUARD_FUZZ_SEEDS") != nullptr) {
    for (const std::string& seed : rotorguard::fuzz::SeedFiles(*g_target)) std::printf("%s\n", seed.c_str());
    std::exit(0);
  }
  if (g_target == nullptr) {
    std::fprintf(stderr, "set ROTORGUARD_FUZZ_TARGET to one of:");
    for (const auto& t : rotorguard::fuzz::Targets())
      std::fprintf(stderr, " %.*s", static_cast<int>(t.name.size()), t.name.data());
    std::fprintf(stderr, "\n");
    std::exit(2);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rotorguard::fuzz::RunOne(*g_target, std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
