# rotorguard_precompiled_headers(TARGET KIND)
# Precompiled third-party and standard headers, one set per KIND of target (LIBRARY, TEST).
# The first target of a kind compiles the header set; every later one reuses it, so a build
# compiles two precompiled headers instead of one per target. Sharing needs identical flags
# within a kind (position-independent code, GoogleTest's macros), hence the two kinds; a target
# whose flags differ (one that does not link Eigen and fmt, which the header set includes) opts
# out. A mismatch is reported by -Winvalid-pch, which CMake adds.
#
# Why: most translation units are small (a command, a metric, a file format) and spend more time
# parsing Eigen, nlohmann/json and fmt (and GoogleTest) than compiling their own code. Programs of
# one or two small files gain nothing (loading the header set costs them more than it saves).
# The project's headers are left out, so editing one never rebuilds the shared header.
option(ROTORGUARD_PRECOMPILED_HEADERS "Precompile the third-party headers (faster builds)" ON)

set(ROTORGUARD_PCH_COMMON
  <algorithm> <array> <cmath> <cstdint> <filesystem> <fstream> <functional> <limits> <map>
  <memory> <numbers> <optional> <stdexcept> <string> <string_view> <utility> <vector>
  <Eigen/Dense> <fmt/format.h> <nlohmann/json.hpp>)
set(ROTORGUARD_PCH_LIBRARY ${ROTORGUARD_PCH_COMMON})
set(ROTORGUARD_PCH_TEST ${ROTORGUARD_PCH_COMMON} <gtest/gtest.h>)

function(rotorguard_precompiled_headers target kind)
  if(NOT ROTORGUARD_PRECOMPILED_HEADERS)
    return()
  endif()
  if(NOT DEFINED ROTORGUARD_PCH_${kind})
    message(FATAL_ERROR "rotorguard_precompiled_headers: kind '${kind}' is not one of LIBRARY, TEST")
  endif()
  get_property(donor GLOBAL PROPERTY ROTORGUARD_PCH_DONOR_${kind})
  if(donor)
    target_precompile_headers(${target} REUSE_FROM ${donor})
  else()
    target_precompile_headers(${target} PRIVATE ${ROTORGUARD_PCH_${kind}})
    set_property(GLOBAL PROPERTY ROTORGUARD_PCH_DONOR_${kind} ${target})
  endif()
  # GCC 12 reports out-of-bounds copies inside libstdc++'s std::string when it inlines that code
  # from a precompiled header (the same code read as text is silent); whether it does depends on
  # the length of a literal such as the checkout's path. They stay warnings: a checkout path must
  # not fail a build with warnings as errors.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(${target} PRIVATE -Wno-error=array-bounds -Wno-error=stringop-overflow
                                             -Wno-error=restrict)
  endif()
endfunction()
