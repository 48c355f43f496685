#include "rotorguard/ros1/bus.h"

#include <ros/callback_queue.h>
#include <ros/master.h>
#include <ros/ros.h>

#include <atomic>
#include <chrono>
#include <map>
#include <stdexcept>
#include <thread>
#include <vector>

#include "convert.h"

namespace rotorguard::ros1 {

using internal::FromRos;
using internal::RosType;
using internal::ToRos;

template <typename T>
struct Publisher<T>::Impl {
  ros::Publisher publisher;
};
template <typename T>
Publisher<T>::Publisher() = default;
template <typename T>
Publisher<T>::~Publisher() = default;
template <typename T>
Publisher<T>::Publisher(Publisher&&) noexcept = default;
template <typename T>
Publisher<T>& Publisher<T>::operator=(Publisher&&) noexcept = default;
template <typename T>
void Publisher<T>::Publish(const T& message) {
  if (impl_) impl_->publisher.publish(ToRos(message));
}
template <typename T>
std::uint32_t Publisher<T>::subscribers() const {
  return impl_ ? impl_->publisher.getNumSubscribers() : 0;
}

struct Bus::Impl {
  std::unique_ptr<ros::NodeHandle> node;
  ros::CallbackQueue heavy;  // TopicOptions::Queue::kHeavy's
  std::vector<ros::Subscriber> subscribers;
  BadMessageHandler on_bad;
};

namespace {
std::atomic<bool> g_initialised{false};
}  // namespace

Bus::Bus(const Options& options) : impl_(std::make_unique<Impl>()) {
  // ROS 1 has one node per process, started once: a later Bus (the next flight of a benchmark)
  // shares it, on the same master, with publishers and subscriptions of its own.
  if (!g_initialised.exchange(true)) {
    std::map<std::string, std::string> remappings(options.remappings.begin(), options.remappings.end());
    if (!options.master_uri.empty()) remappings["__master"] = options.master_uri;
    // No SIGINT handler of ROS's own: the program's (rotorguard's commands stop cleanly on their own).
    ros::init(remappings, options.node_name, ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
  } else if (!options.master_uri.empty() && options.master_uri != ros::master::getURI()) {
    throw std::runtime_error("ros: this process's node talks to " + ros::master::getURI() + ", not " + options.master_uri +
                             " (one ROS node per process)");
  }
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.master_timeout_s);
  while (!ros::master::check()) {
    if (std::chrono::steady_clock::now() > until) {
      throw std::runtime_error("ros: no ROS master at " + ros::master::getURI() + " (start one with `roscore -p PORT` and set ROS_MASTER_URI, or pass --ros-master)");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  impl_->node = std::make_unique<ros::NodeHandle>();
}

Bus::~Bus() {
  // The subscriptions and the handle go; the process's node stays for a later Bus (ROS 1 cannot
  // start a node twice) and ends with the process.
  impl_->subscribers.clear();
  impl_->node.reset();
}

template <typename T>
Publisher<T> Bus::Advertise(const std::string& topic, const TopicOptions& options) {
  Publisher<T> p;
  p.impl_ = std::make_unique<typename Publisher<T>::Impl>();
  p.impl_->publisher = impl_->node->advertise<typename RosType<T>::type>(topic, options.queue_size, options.latch);
  return p;
}

template <typename T>
void Bus::Subscribe(const std::string& topic, const TopicOptions& options, std::function<void(const T&)> on_message) {
  using Message = typename RosType<T>::type;
  ros::TransportHints hints;
  if (options.tcp_nodelay) hints = hints.tcpNoDelay();
  Impl* impl = impl_.get();
  ros::SubscribeOptions o;
  o.template init<Message>(topic, options.queue_size,
                           [impl, topic, on_message = std::move(on_message)](const typename Message::ConstPtr& r) {
                             T m;
                             if (const std::string e = FromRos(*r, &m); !e.empty()) {
                               if (impl->on_bad) impl->on_bad(topic, e);
                               return;
                             }
                             on_message(m);
                           });
  o.transport_hints = hints;
  if (options.queue == TopicOptions::Queue::kHeavy) o.callback_queue = &impl_->heavy;
  impl_->subscribers.push_back(impl_->node->subscribe(o));
}

void Bus::OnBadMessage(BadMessageHandler handler) { impl_->on_bad = std::move(handler); }

std::uint32_t Bus::Publishers(const std::string& topic) const {
  std::uint32_t n = 0;
  const std::string resolved = ros::names::resolve(topic);
  for (const ros::Subscriber& s : impl_->subscribers) {
    if (s.getTopic() == resolved) n += s.getNumPublishers();
  }
  return n;
}

bool Bus::Spin(double timeout_s, TopicOptions::Queue queue) {
  if (!ros::ok()) return false;
  ros::CallbackQueue* q = queue == TopicOptions::Queue::kHeavy ? &impl_->heavy : ros::getGlobalCallbackQueue();
  q->callAvailable(ros::WallDuration(timeout_s));
  return ros::ok();
}

Stamp Bus::Now() const { return internal::FromRosTime(ros::Time::now()); }
bool Bus::SimTime() const { return ros::Time::isSimTime(); }
void Bus::SetParam(const std::string& key, bool value) { ros::param::set(key, value); }
std::string Bus::master_uri() const { return ros::master::getURI(); }

// The topics' types: every wire struct that is published, and those that are read.
#define ROTORGUARD_PUBLISHED(T)                  \
  template class Publisher<T>;                   \
  template Publisher<T> Bus::Advertise<T>(const std::string&, const TopicOptions&);
#define ROTORGUARD_READ(T) \
  template void Bus::Subscribe<T>(const std::string&, const TopicOptions&, std::function<void(const T&)>);
ROTORGUARD_PUBLISHED(Imu)
ROTORGUARD_PUBLISHED(Esc)
ROTORGUARD_PUBLISHED(Battery)
ROTORGUARD_PUBLISHED(Odometry)
ROTORGUARD_PUBLISHED(Cloud)
ROTORGUARD_PUBLISHED(PointSet)
ROTORGUARD_PUBLISHED(Command)
ROTORGUARD_PUBLISHED(Health)
ROTORGUARD_PUBLISHED(Cycle)
ROTORGUARD_PUBLISHED(Transforms)
ROTORGUARD_PUBLISHED(Path)
ROTORGUARD_PUBLISHED(Text)
ROTORGUARD_PUBLISHED(ClockTick)
ROTORGUARD_PUBLISHED(Markers)
ROTORGUARD_READ(Imu)
ROTORGUARD_READ(Esc)
ROTORGUARD_READ(Battery)
ROTORGUARD_READ(Odometry)
ROTORGUARD_READ(Cloud)
ROTORGUARD_READ(Command)
ROTORGUARD_READ(Health)
ROTORGUARD_READ(Cycle)
ROTORGUARD_READ(Text)
ROTORGUARD_READ(ClockTick)
#undef ROTORGUARD_PUBLISHED
#undef ROTORGUARD_READ

}  // namespace rotorguard::ros1
