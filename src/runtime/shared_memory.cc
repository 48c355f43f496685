#include "rotorguard/runtime/shared_memory.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace rotorguard::runtime {

namespace {

[[noreturn]] void Fail(const std::string& what, const std::string& name, int err) {
  throw std::runtime_error(fmt::format("shared memory {}: cannot {}: {}", name, what, std::strerror(err)));
}

void CheckName(const std::string& name) {
  if (name.size() < 2 || name.front() != '/' || name.find('/', 1) != std::string::npos || name.size() > 250) {
    throw std::invalid_argument(fmt::format(
        "shared memory name '{}' is invalid; expected '/' then 1-249 characters without another '/'", name));
  }
}

}  // namespace

SharedSegment SharedSegment::Create(const std::string& name, std::size_t bytes) {
  CheckName(name);
  const int fd = shm_open(name.c_str(), O_CREAT | O_EXCL | O_RDWR, 0600);
  if (fd < 0) Fail("create it", name, errno);
  if (ftruncate(fd, static_cast<off_t>(bytes)) != 0) {
    const int err = errno;
    close(fd);
    shm_unlink(name.c_str());
    Fail(fmt::format("size it to {} bytes", bytes), name, err);
  }
  void* data = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  const int err = errno;
  close(fd);
  if (data == MAP_FAILED) {
    shm_unlink(name.c_str());
    Fail("map it", name, err);
  }
  return SharedSegment(name, data, bytes, true);  // ftruncate zero-fills
}

SharedSegment SharedSegment::Open(const std::string& name, std::size_t bytes) {
  CheckName(name);
  const int fd = shm_open(name.c_str(), O_RDWR, 0);
  if (fd < 0) Fail("open it", name, errno);
  struct stat st {};
  if (fstat(fd, &st) != 0 || static_cast<std::size_t>(st.st_size) < bytes) {
    close(fd);
    throw std::runtime_error(fmt::format("shared memory {}: {} bytes, expected at least {}", name,
                                         static_cast<long long>(st.st_size), bytes));
  }
  void* data = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  const int err = errno;
  close(fd);
  if (data == MAP_FAILED) Fail("map it", name, err);
  return SharedSegment(name, data, bytes, false);
}

SharedSegment::SharedSegment(SharedSegment&& other) noexcept
    : name_(std::move(other.name_)), data_(other.data_), size_(other.size_), owner_(other.owner_) {
  other.data_ = nullptr;
  other.owner_ = false;
}

SharedSegment& SharedSegment::operator=(SharedSegment&& other) noexcept {
  if (this != &other) {
    Release();
    name_ = std::move(other.name_);
    data_ = other.data_;
    size_ = other.size_;
    owner_ = other.owner_;
    other.data_ = nullptr;
    other.owner_ = false;
  }
  return *this;
}

SharedSegment::~SharedSegment() { Release(); }

void SharedSegment::Release() {
  if (data_ != nullptr) munmap(data_, size_);
  if (owner_) shm_unlink(name_.c_str());
  data_ = nullptr;
  owner_ = false;
}

void ThrowSharedLayoutMismatch(const std::string& name, std::uint64_t found_magic, std::uint64_t magic,
                               std::uint64_t found_size, std::uint64_t size) {
  throw std::runtime_error(fmt::format(
      "shared memory {}: layout {:#x} of {} bytes, expected {:#x} of {} bytes (another build of rotorguard, or not "
      "yet built)",
      name, found_magic, found_size, magic, size));
}

}  // namespace rotorguard::runtime
