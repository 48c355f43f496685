#pragma once
/// Output files that are never seen half-written: content goes to a temporary file in the same
/// folder, which is flushed, synced and renamed over the destination on Commit().
#include <cstdio>
#include <string>

namespace rotorguard::io {

class AtomicFileWriter {
 public:
  /// Opens `<path>.tmp-<pid>` for writing; throws std::runtime_error naming the path on failure.
  explicit AtomicFileWriter(std::string path);
  ~AtomicFileWriter();  ///< removes the temporary file unless committed
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  void Write(const std::string& text);
  void Write(const char* data, std::size_t size);
  /// Flushes, fsyncs and renames onto the destination. Throws std::runtime_error on failure.
  void Commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_, tmp_path_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

/// A new, empty folder under the system's temporary directory, removed with everything in it when
/// the object goes (also on an exception). Its name holds `prefix`, the process id and a counter, so
/// that folders made side by side never collide.
class TemporaryFolder {
 public:
  explicit TemporaryFolder(const std::string& prefix);
  ~TemporaryFolder();
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// Writes a whole file atomically.
void WriteFileAtomically(const std::string& path, const std::string& content);

/// Reads a whole file; throws std::runtime_error naming the path when it cannot.
std::string ReadFile(const std::string& path);

}  // namespace rotorguard::io
