# The targets the driver knows (rotorguard_fuzz --list) are those ctest runs: a new target without
# a test would never run in `make test`.
execute_process(COMMAND ${DRIVER} --list OUTPUT_VARIABLE listing RESULT_VARIABLE failed)
if(failed)
  message(FATAL_ERROR "${DRIVER} --list failed")
endif()
string(REGEX MATCHALL "(^|\n)[a-z_]+" names "${listing}")
string(REPLACE "\n" "" names "${names}")
if(NOT "${names}" STREQUAL "${EXPECTED}")
  message(FATAL_ERROR "the driver's targets '${names}' differ from the tests' '${EXPECTED}' (tests/fuzz/CMakeLists.txt)")
endif()
