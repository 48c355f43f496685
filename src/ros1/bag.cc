#include "rotorguard/ros1/bag.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <cstdio>
#include <stdexcept>

#include "convert.h"

namespace rotorguard::ros1 {

using internal::FromRos;
using internal::RosType;
using internal::ToRos;

struct BagWriter::Impl {
  rosbag::Bag bag;
  std::string active;
  bool open = false;
};

BagWriter::BagWriter(const std::string& path) : impl_(std::make_unique<Impl>()), path_(path) {
  impl_->active = path + ".active";
  try {
    impl_->bag.open(impl_->active, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error("bag: cannot create '" + impl_->active + "': " + e.what());
  }
  impl_->open = true;
}

BagWriter::~BagWriter() {
  // Not closed by the program: it stopped on an error; the bag stays PATH.active.
  if (impl_->open) {
    try {
      impl_->bag.close();
    } catch (...) {
    }
  }
}

template <typename T>
void BagWriter::Write(const std::string& topic, Stamp time, const T& message) {
  impl_->bag.write(topic, internal::ToRosTime(time), ToRos(message));
}

void BagWriter::Close() {
  if (!impl_->open) return;
  impl_->bag.close();
  impl_->open = false;
  if (std::rename(impl_->active.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error("bag: cannot rename '" + impl_->active + "' to '" + path_ + "'");
  }
}

#define ROTORGUARD_WRITTEN(T) template void BagWriter::Write<T>(const std::string&, Stamp, const T&);
ROTORGUARD_WRITTEN(Imu)
ROTORGUARD_WRITTEN(Esc)
ROTORGUARD_WRITTEN(Battery)
ROTORGUARD_WRITTEN(Odometry)
ROTORGUARD_WRITTEN(Cloud)
ROTORGUARD_WRITTEN(Command)
ROTORGUARD_WRITTEN(Health)
ROTORGUARD_WRITTEN(Cycle)
ROTORGUARD_WRITTEN(Transforms)
ROTORGUARD_WRITTEN(Text)
ROTORGUARD_WRITTEN(ClockTick)
#undef ROTORGUARD_WRITTEN

namespace {

enum class Outcome { kOtherType, kRead, kBad };

/// Converts the message to T when it holds T's ROS type.
template <typename T>
Outcome TryRead(const rosbag::MessageInstance& mi, BagMessage* out) {
  using Message = typename RosType<T>::type;
  if (mi.getDataType() != ros::message_traits::DataType<Message>::value()) return Outcome::kOtherType;
  const typename Message::ConstPtr r = mi.instantiate<Message>();
  T m;
  if (!r || !FromRos(*r, &m).empty()) return Outcome::kBad;
  out->message = std::move(m);
  return Outcome::kRead;
}

/// The first of the types Ts the message holds, converted.
template <typename... Ts>
Outcome ReadAny(const rosbag::MessageInstance& mi, BagMessage* out) {
  Outcome o = Outcome::kOtherType;
  ((o = TryRead<Ts>(mi, out), o != Outcome::kOtherType) || ...);
  return o;
}

}  // namespace

BagReadSummary ReadBag(const std::string& path, const std::function<void(const BagMessage&)>& visit,
                       const std::vector<std::string>& topics) {
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error("bag: cannot read '" + path + "': " + e.what());
  }
  BagReadSummary summary;
  rosbag::View view;
  if (topics.empty()) {
    view.addQuery(bag);
  } else {
    view.addQuery(bag, rosbag::TopicQuery(topics));
  }
  for (const rosbag::MessageInstance& mi : view) {
    BagMessage m;
    m.topic = mi.getTopic();
    m.time = internal::FromRosTime(mi.getTime());
    // A cloud is read as a LiDAR frame (PointSet clouds have no time field: counted as bad).
    switch (ReadAny<Imu, Esc, Battery, Odometry, Cloud, Command, Health, Cycle, Text, ClockTick>(mi, &m)) {
      case Outcome::kOtherType:
        ++summary.skipped_types[mi.getDataType()];
        break;
      case Outcome::kBad:
        ++summary.bad[m.topic];
        break;
      case Outcome::kRead:
        ++summary.messages;
        visit(m);
        break;
    }
  }
  bag.close();
  return summary;
}

}  // namespace rotorguard::ros1
