#include "rotorguard/core/huge_pages.h"

#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace rotorguard::internal {

namespace {
constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;  // x86-64's and AArch64's (4 KB granule)
}  // namespace

void* AllocateHugePageBacked(std::size_t bytes) {
  if (bytes < kHugePageBytes) return ::operator new(bytes);
  // aligned_alloc wants a multiple of the alignment.
  const std::size_t rounded = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  void* p = std::aligned_alloc(kHugePageBytes, rounded);
  if (p == nullptr) throw std::bad_alloc();
#if defined(MADV_HUGEPAGE)
  // A hint: where transparent huge pages are off it fails or is ignored, and the pages stay small.
  (void)madvise(p, rounded, MADV_HUGEPAGE);
#endif
  return p;
}

void FreeHugePageBacked(void* p, std::size_t bytes) noexcept {
  if (bytes < kHugePageBytes) {
    ::operator delete(p);
  } else {
    std::free(p);
  }
}

}  // namespace rotorguard::internal
