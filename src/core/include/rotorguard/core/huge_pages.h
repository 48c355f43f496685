#pragma once
/// Storage for large arrays read at random, in 2 MB pages where the kernel grants transparent
/// huge pages on request (Linux's "madvise" mode; "always" gives them unasked). In 4 KB pages
/// each random access to an array larger than the TLB's reach (a few MB) is a page-table walk: the
/// occupancy map's 16 MB of cells, which every LiDAR frame touches tens of thousands of times at
/// scattered addresses. Elsewhere (a build without MADV_HUGEPAGE, or the kernel's huge pages
/// off), or below a huge page, the storage is ordinary; the contents never differ.
#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

namespace rotorguard {

namespace internal {
/// `bytes` of storage, aligned to a huge page and advised into them when at least one; throws
/// std::bad_alloc when none is left.
void* AllocateHugePageBacked(std::size_t bytes);
void FreeHugePageBacked(void* p, std::size_t bytes) noexcept;
}  // namespace internal

/// A standard allocator over AllocateHugePageBacked (stateless: any two compare equal).
template <typename T>
struct HugePageAllocator {
  using value_type = T;
  // The storage is aligned for operator new's default (or a huge page): no over-aligned types.
  static_assert(alignof(T) <= __STDCPP_DEFAULT_NEW_ALIGNMENT__, "HugePageAllocator: over-aligned type");
  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}  // implicit, as std::allocator's
  T* allocate(std::size_t n) {
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(internal::AllocateHugePageBacked(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept { internal::FreeHugePageBacked(p, n * sizeof(T)); }
  template <typename U>
  friend bool operator==(const HugePageAllocator&, const HugePageAllocator<U>&) {
    return true;
  }
};

template <typename T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace rotorguard
