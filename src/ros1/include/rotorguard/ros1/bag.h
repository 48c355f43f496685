#pragma once
/// rosbag files in and out, over the wire structs (wire.h): what `run` and `sitl` record and
/// `rotorguard replay` reads (docs/ros.md). A bag is written under `PATH.active` and renamed to
/// PATH when closed, so a run that stops half-way leaves no bag that looks complete.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "rotorguard/ros1/wire.h"

namespace rotorguard::ros1 {

class BagWriter {
 public:
  /// Throws std::runtime_error naming the file when it cannot be created.
  explicit BagWriter(const std::string& path);
  /// Closes the bag (an exception on the way leaves only PATH.active behind).
  ~BagWriter();
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;
  /// `time`: the bag's own time of the message (when it was received or delivered; the message
  /// keeps its own stamp).
  template <typename T>
  void Write(const std::string& topic, Stamp time, const T& message);
  /// Finishes the file and gives it its name.
  void Close();
  const std::string& path() const { return path_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
};

/// A message read from a bag: its topic, the bag's time of it, and the message.
struct BagMessage {
  std::string topic;
  Stamp time = 0;
  std::variant<Imu, Esc, Battery, Odometry, Cloud, Command, Health, Cycle, Text, ClockTick> message;
};

struct BagReadSummary {
  std::uint64_t messages = 0;  ///< handed to the visitor
  /// Messages of a type rotorguard does not read, per type (skipped).
  std::map<std::string, std::uint64_t> skipped_types;
  /// Messages that did not convert (a NaN, a cloud without per-point times), per topic (skipped).
  std::map<std::string, std::uint64_t> bad;
};

/// Reads every message of the bag at `path` (of `topics` alone when given) in the order of its
/// time and hands each one rotorguard reads to `visit`. Throws std::runtime_error naming the file
/// when it is not a readable bag.
BagReadSummary ReadBag(const std::string& path, const std::function<void(const BagMessage&)>& visit,
                       const std::vector<std::string>& topics = {});

}  // namespace rotorguard::ros1
