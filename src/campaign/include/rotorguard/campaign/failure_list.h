#pragma once
/// The failed trials a benchmark's result names: the first few listed with what reproduces each
/// (a seed for --replay), the rest counted, so that a report never drops one silently.
#include <fmt/format.h>

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

namespace rotorguard::campaign {

class FailureList {
 public:
  /// Lists at most `limit` failures.
  explicit FailureList(std::size_t limit) : limit_(limit) {}

  void Add(nlohmann::json failure) {
    if (listed_.size() < limit_) {
      listed_.push_back(std::move(failure));
    } else {
      ++not_listed_;
    }
  }

  /// The listed failures (a result's `failures`) and the count of the others (`failures_not_listed`).
  const nlohmann::json& listed() const { return listed_; }
  int not_listed() const { return not_listed_; }

  /// A Markdown line (without its newline) for the failures of `result` (its `failures_not_listed`)
  /// that are not listed, prefixed by `who`; empty when every failure is listed.
  static std::string NotListedLine(const nlohmann::json& result, const std::string& who) {
    const int more = result.value("failures_not_listed", 0);
    if (more <= 0) return "";
    return fmt::format("{}failed: {} more, not listed", who.empty() ? "" : who + " ", more);
  }

 private:
  std::size_t limit_;
  nlohmann::json listed_ = nlohmann::json::array();
  int not_listed_ = 0;
};

}  // namespace rotorguard::campaign
