#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "config_tree.h"
#include "rotorguard/core/key_ranges.h"

// ConfigNode: reading the tree, each accessor's error located at its node.
namespace rotorguard::io {

using namespace internal;  // NOLINT: the layer's own helpers

// ---- ConfigNode.

ConfigNode::ConfigNode(std::shared_ptr<const detail::DocumentState> doc,
                       std::shared_ptr<detail::Value> value, std::string key_path)
    : doc_(std::move(doc)), value_(std::move(value)), key_path_(std::move(key_path)) {}

std::string ConfigNode::Location() const {
  if (value_->from_override) return std::string(kOverrideSource);
  if (value_->line <= 0) return doc_->file;
  return fmt::format("{}:{}:{}", doc_->file, value_->line, value_->column);
}

bool ConfigNode::IsMap() const { return value_->kind == Kind::kMap; }
bool ConfigNode::IsSequence() const { return value_->kind == Kind::kSequence; }
bool ConfigNode::IsScalar() const { return value_->kind == Kind::kScalar; }
bool ConfigNode::IsNull() const { return value_->kind == Kind::kNull; }

void ConfigNode::Fail(const std::string& message) const {
  ThrowAt(*value_, doc_->file, key_path_, message);
}

void ConfigNode::FailAt(const std::string& relative_path, const std::string& message) const {
  const Value* target = value_.get();
  if (!relative_path.empty()) {
    for (const std::string& segment : SplitPath(relative_path)) {
      if (target->kind == Kind::kMap) {
        const auto it = target->index.find(segment);
        if (it == target->index.end()) break;
        target = target->entries[it->second].value.get();
      } else if (target->kind == Kind::kSequence) {
        const std::optional<std::size_t> index = ParseIndex(segment);
        if (!index || *index >= target->items.size()) break;
        target = target->items[*index].get();
      } else {
        break;
      }
    }
  }
  ThrowAt(*target, doc_->file, JoinPath(key_path_, relative_path), message);
}

void ConfigNode::RequireMap() const {
  if (value_->kind != Kind::kMap) Fail(fmt::format("expected a map, got {}", Describe(*value_)));
}

void ConfigNode::RequireSequence(const std::string& expected) const {
  if (value_->kind != Kind::kSequence) {
    Fail(fmt::format("expected {}, got {}", expected, Describe(*value_)));
  }
}

int ConfigNode::LookUp(std::string_view key) const {
  RequireMap();
  std::string name(key);
  const auto it = value_->index.find(name);
  if (value_->asked_set.insert(name).second) value_->asked_keys.push_back(std::move(name));
  return it == value_->index.end() ? -1 : static_cast<int>(it->second);
}

ConfigNode ConfigNode::ChildAt(int entry_index) const {
  const MapEntry& entry = value_->entries[static_cast<std::size_t>(entry_index)];
  return ConfigNode(doc_, entry.value, JoinPath(key_path_, entry.key));
}

bool ConfigNode::Has(std::string_view key) const { return LookUp(key) >= 0; }

ConfigNode ConfigNode::Required(std::string_view key) const {
  const int index = LookUp(key);
  if (index < 0) Fail(fmt::format("missing required key '{}'", key));
  return ChildAt(index);
}

std::optional<ConfigNode> ConfigNode::Optional(std::string_view key) const {
  const int index = LookUp(key);
  if (index < 0) return std::nullopt;
  return ChildAt(index);
}

std::vector<std::string> ConfigNode::Keys() const {
  RequireMap();
  std::vector<std::string> keys;
  keys.reserve(value_->entries.size());
  for (const MapEntry& entry : value_->entries) keys.push_back(entry.key);
  return keys;
}

void ConfigNode::RejectUnknownKeys() const {
  RequireMap();
  for (const MapEntry& entry : value_->entries) {
    if (value_->asked_set.count(entry.key) != 0) continue;
    const std::string message =
        value_->asked_keys.empty()
            ? fmt::format("unknown key '{}'; no keys are expected here", entry.key)
            : fmt::format("unknown key '{}'; expected one of: {}", entry.key,
                          JoinList(value_->asked_keys));
    // The key itself was written in this map, so it shares the map's source, unless an override
    // added it.
    const std::string source = entry.from_override ? std::string(kOverrideSource) : SourceFile(*value_, doc_->file);
    throw ConfigError(source, entry.key_line, entry.key_column,
                      JoinPath(key_path_, entry.key), message);
  }
}

std::size_t ConfigNode::size() const {
  RequireSequence("a sequence");
  return value_->items.size();
}

ConfigNode ConfigNode::At(std::size_t i) const {
  RequireSequence("a sequence");
  if (i >= value_->items.size()) {
    Fail(fmt::format("index {} is out of range; the sequence has {} items", i,
                     value_->items.size()));
  }
  return ConfigNode(doc_, value_->items[i], JoinPath(key_path_, std::to_string(i)));
}

const std::string& ConfigNode::PlainScalar(const std::string& expected) const {
  if (value_->kind != Kind::kScalar || value_->tag != "?") {
    Fail(fmt::format("expected {}, got {}", expected, Describe(*value_)));
  }
  return value_->scalar;
}

double ConfigNode::ParseFinite(const std::string& expected) const {
  const std::string& text = PlainScalar(expected);
  const ParsedNumber parsed = ParseYamlFloat(text);
  switch (parsed.status) {
    case NumberStatus::kOk:
      return parsed.value;
    case NumberStatus::kNotFinite:
      Fail(fmt::format("{} is not finite; expected {}", Quote(text), expected));
    case NumberStatus::kOverflow:
      Fail(fmt::format("{} is not finite (it overflows a double); expected {}", Quote(text),
                       expected));
    case NumberStatus::kNotANumber:
      break;
  }
  Fail(fmt::format("{} is not a number; expected {}", Quote(text), expected));
}

double ConfigNode::AsDouble() const { return ParseFinite("a finite number"); }

double ConfigNode::AsDoubleIn(double lo, double hi) const {
  const std::string expected = fmt::format("a number in [{}, {}]", lo, hi);
  const double value = ParseFinite(expected);
  if (!(value >= lo && value <= hi)) {
    Fail(fmt::format("{} is out of range; expected {}", Quote(value_->scalar), expected));
  }
  return value;
}

double ConfigNode::AsPositive() const {
  const std::string expected = "a positive number (> 0)";
  const double value = ParseFinite(expected);
  if (!(value > 0.0)) {
    Fail(fmt::format("{} is out of range; expected {}", Quote(value_->scalar), expected));
  }
  return value;
}

double ConfigNode::AsNumberIn(const KeyInfo& info) const {
  const std::string expected = "a number " + DeclaredRangeText(info);
  const double value = ParseFinite(expected);
  if (!InDeclaredRange(value, info)) {
    Fail(fmt::format("{} is out of range; expected {}", Quote(value_->scalar), expected));
  }
  return value;
}

double ConfigNode::AsNonNegative() const {
  const std::string expected = "a non-negative number (>= 0)";
  const double value = ParseFinite(expected);
  if (!(value >= 0.0)) {
    Fail(fmt::format("{} is out of range; expected {}", Quote(value_->scalar), expected));
  }
  return value;
}

std::int64_t ConfigNode::ParseInt(const std::string& expected) const {
  const std::string& text = PlainScalar(expected);
  const ParsedInteger parsed = ParseYamlInteger(text);
  constexpr std::uint64_t kMaxPositive =
      static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  if (parsed.ok) {
    if (!parsed.negative && parsed.magnitude <= kMaxPositive) {
      return static_cast<std::int64_t>(parsed.magnitude);
    }
    if (parsed.negative && parsed.magnitude <= kMaxPositive + 1) {
      // -(2^63) has no positive counterpart; negate in unsigned arithmetic.
      return static_cast<std::int64_t>(~parsed.magnitude + 1);
    }
  }
  if (parsed.ok || parsed.overflow) {
    Fail(fmt::format("{} does not fit a 64-bit integer; expected {}", Quote(text), expected));
  }
  Fail(fmt::format("{} is not an integer; expected {}", Quote(text), expected));
}

std::int64_t ConfigNode::AsInt() const { return ParseInt("an integer"); }

std::int64_t ConfigNode::AsIntIn(std::int64_t lo, std::int64_t hi) const {
  const std::string expected = fmt::format("an integer in [{}, {}]", lo, hi);
  const std::int64_t value = ParseInt(expected);
  if (value < lo || value > hi) {
    Fail(fmt::format("{} is out of range; expected {}", Quote(value_->scalar), expected));
  }
  return value;
}

std::uint64_t ConfigNode::AsUint64() const {
  const std::string expected = "a non-negative integer";
  const std::string& text = PlainScalar(expected);
  const ParsedInteger parsed = ParseYamlInteger(text);
  if (parsed.ok && (!parsed.negative || parsed.magnitude == 0)) return parsed.magnitude;
  if (parsed.ok) Fail(fmt::format("{} is negative; expected {}", Quote(text), expected));
  if (parsed.overflow) {
    Fail(fmt::format("{} is out of range; expected {} up to {}", Quote(text), expected,
                     std::numeric_limits<std::uint64_t>::max()));
  }
  Fail(fmt::format("{} is not an integer; expected {}", Quote(text), expected));
}

bool ConfigNode::AsBool() const {
  const std::string expected = "true or false";
  const std::string& text = PlainScalar(expected);
  if (text == "true" || text == "True" || text == "TRUE") return true;
  if (text == "false" || text == "False" || text == "FALSE") return false;
  Fail(fmt::format("{} is not a boolean; expected {}", Quote(text), expected));
}

std::string ConfigNode::AsString() const {
  if (value_->kind != Kind::kScalar) {
    Fail(fmt::format("expected a string, got {}", Describe(*value_)));
  }
  return value_->scalar;
}

std::string ConfigNode::AsEnum(const std::vector<std::string>& allowed) const {
  const std::string expected = fmt::format("one of: {}", JoinList(allowed));
  if (value_->kind != Kind::kScalar) {
    Fail(fmt::format("expected {}, got {}", expected, Describe(*value_)));
  }
  for (const std::string& option : allowed) {
    if (value_->scalar == option) return option;
  }
  Fail(fmt::format("{} is not allowed; expected {}", Quote(value_->scalar), expected));
}

Eigen::Vector3d ConfigNode::AsVector3() const {
  const std::vector<double> values = AsDoubleList(3);
  return Eigen::Vector3d(values[0], values[1], values[2]);
}

std::vector<double> ConfigNode::AsDoubleList(int expected_size) const {
  const std::string expected = expected_size >= 0
                                   ? fmt::format("a list of {} numbers", expected_size)
                                   : std::string("a list of numbers");
  RequireSequence(expected);
  const std::size_t n = value_->items.size();
  if (expected_size >= 0 && n != static_cast<std::size_t>(expected_size)) {
    Fail(fmt::format("expected {}, got {} item{}", expected, n, n == 1 ? "" : "s"));
  }
  std::vector<double> values;
  values.reserve(n);
  for (std::size_t i = 0; i < n; ++i) values.push_back(At(i).AsDouble());
  return values;
}

}  // namespace rotorguard::io
