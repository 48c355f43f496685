#include "rotorguard/core/error.h"

#include <cstdio>
#include <cstdlib>

namespace rotorguard {

void InvariantFailure(const char* condition, const char* file, int line,
                      const std::string& message) {
  std::fprintf(stderr, "rotorguard internal error: %s failed at %s:%d: %s\n", condition, file,
               line, message.c_str());
  std::abort();
}

}  // namespace rotorguard
