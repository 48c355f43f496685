#pragma once
/// InputGuard: the node's checks on what arrives on the wire (docs/ros.md, "Bad input"). A
/// message stamped at or before its topic's last one is a duplicate or out of order and does not
/// reach the stack (its estimator assumes time moves forward); a message that does not convert
/// (a NaN, a cloud without per-point times) or is larger than its budget is refused; a topic
/// silent for longer than its limit is noted once per silence. Everything is counted and
/// reported; nothing stops the node.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/core/types.h"

namespace rotorguard::rosbridge {

struct TopicHealth {
  std::uint64_t received = 0;      ///< messages that arrived
  std::uint64_t accepted = 0;      ///< handed to the stack
  std::uint64_t duplicates = 0;    ///< stamped as the topic's last one
  std::uint64_t out_of_order = 0;  ///< stamped before it
  std::uint64_t bad = 0;           ///< did not convert: a NaN, a malformed or time-less cloud
  std::uint64_t oversize = 0;      ///< larger than the budget
  std::uint64_t silences = 0;      ///< gaps longer than the topic's silence limit
  double longest_gap_s = 0.0;      ///< between two arrivals [s]
  std::string last_error;          ///< the last refusal's reason
};

class InputGuard {
 public:
  enum class Verdict { kAccept, kDuplicate, kOutOfOrder };
  /// `silence_limits_s`: per topic watched for silence, the longest gap that is not one [s].
  explicit InputGuard(std::map<std::string, double> silence_limits_s = {});
  /// A message of `topic` stamped `stamp` arrived at `arrival` (a steady clock); accepted when
  /// it is stamped after the topic's last accepted one.
  Verdict Check(const std::string& topic, TimeNs stamp, TimeNs arrival);
  /// A message of `topic` arrived at `arrival` that did not convert or was too large.
  void Bad(const std::string& topic, TimeNs arrival, const std::string& what);
  void Oversize(const std::string& topic, TimeNs arrival, const std::string& what);
  /// The watched topics silent at `now` beyond their limit since their last arrival, each
  /// reported once per silence (a topic that never spoke is not watched yet).
  std::vector<std::string> Silent(TimeNs now);
  const std::map<std::string, TopicHealth>& topics() const { return topics_; }
  /// Every topic's counts (the node's account and its status).
  nlohmann::json ToJson() const;

 private:
  struct Watch {
    TimeNs last_stamp = 0, last_arrival = 0;
    bool any = false, silent = false;
  };
  TopicHealth& Arrived(const std::string& topic, TimeNs arrival);
  std::map<std::string, double> limits_;
  std::map<std::string, TopicHealth> topics_;
  std::map<std::string, Watch> watch_;
};

}  // namespace rotorguard::rosbridge
