#include "allocation_counter.h"

#include <atomic>
#include <cerrno>
#include <cstddef>

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* pointer, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
}

namespace {
std::atomic<rotorguard::testing::AllocationHook> g_hook{nullptr};
std::atomic<long> g_allocations{0};
void Seen() {
  if (const rotorguard::testing::AllocationHook hook = g_hook.load(std::memory_order_relaxed)) hook();
}
void CountAny() { g_allocations.fetch_add(1, std::memory_order_relaxed); }
}  // namespace

extern "C" {
void* malloc(std::size_t size) {
  Seen();
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  Seen();
  return __libc_calloc(count, size);
}
void* realloc(void* pointer, std::size_t size) {
  Seen();
  return __libc_realloc(pointer, size);
}
// The aligned ones too: operator new of an over-aligned type (a fixed-size Eigen matrix) comes here.
void* memalign(std::size_t alignment, std::size_t size) {
  Seen();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  Seen();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** pointer, std::size_t alignment, std::size_t size) {
  Seen();
  *pointer = __libc_memalign(alignment, size);
  return *pointer != nullptr ? 0 : ENOMEM;
}
}

namespace rotorguard::testing {

void SetAllocationHook(AllocationHook hook) { g_hook.store(hook); }

void StartCountingAllocations() {
  g_allocations = 0;
  SetAllocationHook(&CountAny);
}

long StopCountingAllocations() {
  SetAllocationHook(nullptr);
  return g_allocations;
}

}  // namespace rotorguard::testing
