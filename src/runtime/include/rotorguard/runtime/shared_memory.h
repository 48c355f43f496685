#pragma once
/// SharedMemory: a named POSIX shared-memory segment holding one object that two processes share
/// (the software-in-the-loop transport's queues, docs/runtime.md). The creating process builds
/// the object in place and removes the name when it is destroyed; another process opens it by
/// name. What lives there must work at any address and across processes: fixed-size data and
/// lock-free atomics (SpscQueue of trivially copyable messages qualifies), no pointers.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <new>
#include <string>
#include <type_traits>
#include <utility>

namespace rotorguard::runtime {

/// The raw segment. Throws std::runtime_error naming the segment and the system's reason when it
/// cannot be created, opened or mapped.
class SharedSegment {
 public:
  /// Creates `name` ("/rotorguard-..."), `bytes` long and zeroed; fails if it exists.
  static SharedSegment Create(const std::string& name, std::size_t bytes);
  /// Opens an existing `name`, which must be at least `bytes` long.
  static SharedSegment Open(const std::string& name, std::size_t bytes);
  SharedSegment(SharedSegment&& other) noexcept;
  SharedSegment& operator=(SharedSegment&& other) noexcept;
  SharedSegment(const SharedSegment&) = delete;
  SharedSegment& operator=(const SharedSegment&) = delete;
  /// Unmaps; the creator also removes the name.
  ~SharedSegment();

  void* data() const { return data_; }
  std::size_t size() const { return size_; }
  const std::string& name() const { return name_; }

 private:
  SharedSegment(std::string name, void* data, std::size_t size, bool owner)
      : name_(std::move(name)), data_(data), size_(size), owner_(owner) {}
  void Release();
  std::string name_;
  void* data_ = nullptr;
  std::size_t size_ = 0;
  bool owner_ = false;
};

/// Throws std::runtime_error: `name` holds another layout than the one asked for.
[[noreturn]] void ThrowSharedLayoutMismatch(const std::string& name, std::uint64_t found_magic, std::uint64_t magic,
                                            std::uint64_t found_size, std::uint64_t size);

/// A T in a shared segment, after a header that says which layout it is (a magic number naming
/// the layout's version, and its size), so that a process built from other sources refuses it
/// instead of misreading it. The creator constructs T in place, then writes the header; an opener
/// checks the header and refuses a segment not (yet) holding a T. T is never destroyed (it must
/// not need to be: the last process to unmap it just goes).
template <typename T>
class Shared {
  static_assert(std::is_default_constructible_v<T>, "Shared<T>: T is built in place with T()");
  static_assert(std::is_trivially_destructible_v<T>, "Shared<T>: T holds no resource to release");

  struct Layout {
    std::atomic<std::uint64_t> magic{0};  // written last by the creator
    std::uint64_t layout_size = 0;
    T value;
  };

 public:
  /// `magic`: a constant naming the layout's version, the same in both programs.
  static Shared Create(const std::string& name, std::uint64_t magic) {
    SharedSegment segment = SharedSegment::Create(name, sizeof(Layout));
    auto* layout = new (segment.data()) Layout();
    layout->layout_size = sizeof(Layout);
    layout->magic.store(magic, std::memory_order_release);
    return Shared(std::move(segment), layout);
  }
  /// Throws std::runtime_error when `name` does not hold a T of this layout.
  static Shared Open(const std::string& name, std::uint64_t magic) {
    SharedSegment segment = SharedSegment::Open(name, sizeof(Layout));
    auto* layout = static_cast<Layout*>(segment.data());
    if (layout->magic.load(std::memory_order_acquire) != magic || layout->layout_size != sizeof(Layout)) {
      ThrowSharedLayoutMismatch(name, layout->magic.load(), magic, layout->layout_size, sizeof(Layout));
    }
    return Shared(std::move(segment), layout);
  }

  T& operator*() const { return layout_->value; }
  T* operator->() const { return &layout_->value; }
  const std::string& name() const { return segment_.name(); }

 private:
  Shared(SharedSegment segment, Layout* layout) : segment_(std::move(segment)), layout_(layout) {}
  SharedSegment segment_;
  Layout* layout_;
};

}  // namespace rotorguard::runtime
