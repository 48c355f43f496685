#pragma once
/// The keys an options struct declares (core/config_schema.h), written back as the YAML the strict
/// reader reads (io/config_archive.h): a run's vehicle.yaml. Numbers in their shortest exact form;
/// a key the file may leave out whose value is nothing (0, an empty list) is left out.
#include <fmt/format.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"

namespace rotorguard::io {

class YamlWriter {
 public:
  /// `flow`: one line of {key: value, ...} (a list's items), else a line per key.
  explicit YamlWriter(bool flow = false) : flow_(flow) {}

  template <typename T, typename... Rest>
  void Visit(const char* key, T* value, const KeyInfo& info = {}, Rest&&...) {
    if constexpr (requires {
                    value->begin();
                    value->front().Serialize(this);
                  }) {  // a list of blocks
      if (value->empty() && !info.required) return;
      std::string text = fmt::format("{}:\n", key);
      for (auto& item : *value) {
        YamlWriter line(/*flow=*/true);
        item.Serialize(&line);
        text += "  - " + line.text() + "\n";
      }
      Add(key, text, /*whole_lines=*/true);
    } else if constexpr (std::is_same_v<T, std::vector<Eigen::Vector3d>>) {  // a list of points
      if (value->empty() && !info.required) return;
      std::string text = fmt::format("{}:\n", key);
      for (const Eigen::Vector3d& p : *value) text += "  - " + Text(p) + "\n";
      Add(key, text, /*whole_lines=*/true);
    } else if constexpr (std::is_same_v<T, Eigen::Matrix3d>) {
      std::string text = fmt::format("{}:\n", key);
      for (int r = 0; r < 3; ++r) text += "  - " + Text(Eigen::Vector3d(value->row(r).transpose())) + "\n";
      Add(key, text, /*whole_lines=*/true);
    } else {
      if constexpr (std::is_arithmetic_v<T>) {
        if (*value == T{} && !info.required) return;
      }
      Add(key, Text(*value), false);
    }
  }
  void Visit(const char* key, ConvertedOf number, const KeyInfo& info) {
    if (*number.value == 0.0 && !info.required) return;
    Add(key, fmt::format("{}", number.to_file(*number.value)), false);
  }

  /// The text: lines `key: value` (ending in a newline), or `{key: value, ...}` for a flow writer.
  std::string text() const { return flow_ ? "{" + text_ + "}" : text_; }

 private:
  void Add(const char* key, const std::string& value, bool whole_lines) {
    if (flow_) {
      text_ += fmt::format("{}{}: {}", text_.empty() ? "" : ", ", key, value);
    } else {
      text_ += whole_lines ? value : fmt::format("{}: {}\n", key, value);
    }
  }
  static std::string Text(double v) { return fmt::format("{}", v); }
  static std::string Text(const std::string& v) { return nlohmann::json(v).dump(); }  // a JSON string is a YAML one
  static std::string Text(const Eigen::Vector3d& v) { return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z()); }
  template <NamedEnum E>
  static std::string Text(E v) {
    return ToName(v);
  }

  bool flow_;
  std::string text_;
};

}  // namespace rotorguard::io
