#pragma once
/// Heap allocations seen in the test executables that link allocation_counter.cc, which defines
/// the process's malloc family (malloc, calloc, realloc and the aligned ones; glibc's own allocator
/// does the work). Counted at the malloc level, not operator new's: Eigen's dynamic matrices call
/// malloc directly. Not under the sanitizers: AddressSanitizer owns malloc, and an instrumented
/// replacement runs before its shadow memory exists.
namespace rotorguard::testing {

/// Called on every allocation while installed, on the allocating thread: it must not allocate
/// (or must guard against its own re-entry).
using AllocationHook = void (*)();
/// Installs `hook` (nullptr: none). StartCountingAllocations installs its own.
void SetAllocationHook(AllocationHook hook);

/// Counts every thread's allocations from now on.
void StartCountingAllocations();
/// The allocations since StartCountingAllocations; stops counting.
long StopCountingAllocations();

/// The allocations made by `f`.
template <typename F>
long CountAllocations(F&& f) {
  StartCountingAllocations();
  f();
  return StopCountingAllocations();
}

}  // namespace rotorguard::testing
