#pragma once
/// Bus: one ROS 1 node's publishers and subscribers over the wire structs (wire.h), without ROS
/// in the interface. Callbacks run on the thread that calls Spin for their topic's queue (one
/// thread per queue: its messages reach it in the order they arrived), never on a hidden one.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rotorguard/ros1/wire.h"

namespace rotorguard::ros1 {

/// How a topic is sent and kept (docs/ros.md gives each topic's).
struct TopicOptions {
  /// Messages kept per connection before the oldest is dropped (publisher and subscriber side).
  std::uint32_t queue_size = 10;
  /// Subscriber: ask the publisher for TCP_NODELAY (no Nagle batching: for high-rate topics whose
  /// latency counts).
  bool tcp_nodelay = false;
  /// Publisher: the last message goes to every later subscriber (status, static TF, the account).
  bool latch = false;
  /// Subscriber: the callbacks' queue. kHeavy is for large messages whose conversion takes
  /// milliseconds (a point cloud): a thread of its own spins it, so that they never hold up the
  /// small, urgent ones (IMU samples) queued behind them.
  enum class Queue { kMain, kHeavy };
  Queue queue = Queue::kMain;
};

/// Counts of what a subscription refused (a message that does not convert: a NaN, a cloud
/// without per-point times).
using BadMessageHandler = std::function<void(std::string_view topic, std::string_view what)>;

class Bus;

template <typename T>
class Publisher {
 public:
  Publisher();
  ~Publisher();
  Publisher(Publisher&&) noexcept;
  Publisher& operator=(Publisher&&) noexcept;
  void Publish(const T& message);
  /// Subscribers connected now.
  std::uint32_t subscribers() const;

 private:
  friend class Bus;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class Bus {
 public:
  struct Options {
    std::string node_name = "rotorguard";
    /// The master (http://host:port); empty: ROS_MASTER_URI.
    std::string master_uri;
    /// Seconds to wait for the master before giving up.
    double master_timeout_s = 10.0;
    /// ROS remappings ("imu" -> "/livox/imu"), as `imu:=/livox/imu` on a ROS command line.
    std::vector<std::pair<std::string, std::string>> remappings;
  };
  /// Starts the process's node (ros::init, once per process: a later Bus shares it, on the same
  /// master). Throws std::runtime_error naming the master when it does not answer.
  explicit Bus(const Options& options);
  ~Bus();
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  template <typename T>
  Publisher<T> Advertise(const std::string& topic, const TopicOptions& options);
  /// `on_message` is called on Spin's thread; a message that does not convert goes to
  /// `on_bad_message` instead (when set).
  template <typename T>
  void Subscribe(const std::string& topic, const TopicOptions& options, std::function<void(const T&)> on_message);
  void OnBadMessage(BadMessageHandler handler);
  /// Publishers connected now to this node's subscription of `topic` (0 when it has none).
  std::uint32_t Publishers(const std::string& topic) const;

  /// Calls the callbacks of the messages that arrived on `queue`, waiting up to `timeout_s` for
  /// one; false once the node is shutting down.
  bool Spin(double timeout_s, TopicOptions::Queue queue = TopicOptions::Queue::kMain);
  /// ROS time now (the /clock when /use_sim_time is set).
  Stamp Now() const;
  /// Whether the node follows /clock.
  bool SimTime() const;
  void SetParam(const std::string& key, bool value);
  std::string master_uri() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rotorguard::ros1
