#pragma once
/// Heap allocations counted in the test executables that link allocation_counter.cc, which
/// interposes malloc, calloc and realloc (glibc's own allocator does the work). Not under the
/// sanitizers: AddressSanitizer owns malloc, and an instrumented replacement runs before its shadow
/// memory exists.
namespace rotorguard::testing {

void StartCountingAllocations();
/// The allocations since StartCountingAllocations.
long StopCountingAllocations();

/// The allocations made by `f`.
template <typename F>
long CountAllocations(F&& f) {
  StartCountingAllocations();
  f();
  return StopCountingAllocations();
}

}  // namespace rotorguard::testing
