#include "rotorguard/rosbridge/input_guard.h"

#include <algorithm>

namespace rotorguard::rosbridge {

InputGuard::InputGuard(std::map<std::string, double> silence_limits_s) : limits_(std::move(silence_limits_s)) {}

TopicHealth& InputGuard::Arrived(const std::string& topic, TimeNs arrival) {
  TopicHealth& h = topics_[topic];
  Watch& w = watch_[topic];
  ++h.received;
  if (w.any) h.longest_gap_s = std::max(h.longest_gap_s, ToSeconds(arrival - w.last_arrival));
  w.last_arrival = arrival;
  w.any = true;
  w.silent = false;
  return h;
}

InputGuard::Verdict InputGuard::Check(const std::string& topic, TimeNs stamp, TimeNs arrival) {
  TopicHealth& h = Arrived(topic, arrival);
  Watch& w = watch_[topic];
  if (h.accepted > 0 && stamp == w.last_stamp) {
    ++h.duplicates;
    h.last_error = "a duplicate stamp";
    return Verdict::kDuplicate;
  }
  if (h.accepted > 0 && stamp < w.last_stamp) {
    ++h.out_of_order;
    h.last_error = "a stamp before the topic's last one";
    return Verdict::kOutOfOrder;
  }
  w.last_stamp = stamp;
  ++h.accepted;
  return Verdict::kAccept;
}

void InputGuard::Bad(const std::string& topic, TimeNs arrival, const std::string& what) {
  TopicHealth& h = Arrived(topic, arrival);
  ++h.bad;
  h.last_error = what;
}

void InputGuard::Oversize(const std::string& topic, TimeNs arrival, const std::string& what) {
  TopicHealth& h = Arrived(topic, arrival);
  ++h.oversize;
  h.last_error = what;
}

std::vector<std::string> InputGuard::Silent(TimeNs now) {
  std::vector<std::string> silent;
  for (const auto& [topic, limit_s] : limits_) {
    Watch& w = watch_[topic];
    if (!w.any || w.silent || ToSeconds(now - w.last_arrival) <= limit_s) continue;
    w.silent = true;
    ++topics_[topic].silences;
    silent.push_back(topic);
  }
  return silent;
}

nlohmann::json InputGuard::ToJson() const {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [topic, h] : topics_) {
    j[topic] = {{"received", h.received},     {"accepted", h.accepted}, {"duplicates", h.duplicates},
                {"out_of_order", h.out_of_order}, {"bad", h.bad},         {"oversize", h.oversize},
                {"silences", h.silences},     {"longest_gap_s", h.longest_gap_s}, {"last_error", h.last_error}};
  }
  return j;
}

}  // namespace rotorguard::rosbridge
