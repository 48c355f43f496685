#pragma once
/// The documentation's key tables, written from the keys options structs declare
/// (core/config_schema.h): one row per key with its path, its default (the struct's value), the
/// values it accepts and its meaning, so that docs/scenarios.md cannot drift from the loader.
#include <fmt/format.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::io {

/// One key of a table.
struct KeyRow {
  std::string key;              ///< dotted path below the table's section, "weights.time", "known_faults[].rotor"
  std::string value;            ///< the default, as a file would write it ("" for none) ...
  bool value_is_prose = false;  ///< ... or in words (a default that depends on other keys)
  std::string rule;             ///< what it accepts
  std::string meaning;
  /// What a program that writes values needs (the valid-scenario generator, docs/reliability.md):
  /// a number's declared range (min, max, positive, open_max of its KeyInfo) ...
  KeyInfo range;
  /// ... how many numbers it holds (1; 2 a pair; 3 a triple or [x, y, z]; 4; 9 a matrix; -1 a list
  /// of points; 0 not a number) and whether they are integers ...
  int count = 0;
  bool integer = false;
  /// ... or the names an enum (or a bool: true, false) takes.
  std::vector<std::string> choices;

  /// A number or numbers (a vector, an angle, a count): the rule is to state their range.
  bool numeric() const { return count != 0; }
};

/// Collects a struct's rows: `value.Serialize(&writer)`, nested blocks and lists of blocks
/// flattened into dotted paths.
class KeyTableWriter {
 public:
  explicit KeyTableWriter(std::string prefix = "") : prefix_(std::move(prefix)) {}

  template <typename T, typename... Rest>
  void Visit(const char* key, T* value, const KeyInfo& info = {}, Rest&&...) {
    const std::string path = prefix_ + key;
    if constexpr (requires { value->Serialize(this); }) {
      if (info.shorthand != nullptr) {
        Add(path, "", fmt::format("a map, or the value of `{}` alone", info.shorthand), info);
      }
      KeyTableWriter nested(path + ".");
      value->Serialize(&nested);
      rows_.insert(rows_.end(), nested.rows_.begin(), nested.rows_.end());
    } else if constexpr (IsBlockList<T>::value) {
      std::string rule = info.min >= 1.0 ? "a non-empty list of maps" : "a list of maps";
      if (info.required) rule = "**required**, " + rule;
      Add(path, info.required ? "" : "none", info.rule_text ? info.rule_text : rule, info);
      typename T::value_type item{};
      KeyTableWriter nested(path + "[].");
      item.Serialize(&nested);
      rows_.insert(rows_.end(), nested.rows_.begin(), nested.rows_.end());
    } else {
      // A required key has no default to show.
      Add(path, info.required ? "" : (info.default_text ? info.default_text : Text(*value)), RuleOf(*value, info), info,
          CountOf<T>(), info.default_text != nullptr);
      KeyRow& row = rows_.back();
      row.integer = std::is_integral_v<T> && !std::is_same_v<T, bool>;
      if constexpr (NamedEnum<T>) {
        row.choices = NameList<T>();
      } else if constexpr (std::is_same_v<T, bool>) {
        row.choices = {"true", "false"};
      }
    }
  }
  void Visit(const char* key, DegreesOf angle, const KeyInfo& info) {
    Add(prefix_ + key, Number(*angle.radians * 180.0 / 3.14159265358979323846),
        info.rule_text ? info.rule_text : fmt::format("in ({}, {}) deg", Number(info.min), Number(info.max)), info, 1);
    // An open interval at both ends (the loader's rule): its closest closed one in doubles.
    rows_.back().range.min = std::nextafter(info.min, info.max);
    rows_.back().range.max = std::nextafter(info.max, info.min);
  }
  void Visit(const char* key, ConvertedOf number, const KeyInfo& info) {
    Add(prefix_ + key, info.required ? "" : Number(number.to_file(*number.value)), RuleOf(0.0, info), info, 1);
  }
  void Visit(const char* key, TripleOf t, const KeyInfo& info) {
    Add(prefix_ + key, fmt::format("[{}, {}, {}]", Number(*t.x), Number(*t.y), Number(*t.z)),
        info.rule_text ? info.rule_text : WithNote(Each("three numbers", info), info), info, 3);
  }
  void Visit(const char* key, PairOf pair, const KeyInfo& info) {
    Add(prefix_ + key, fmt::format("[{}, {}]", Number(*pair.first), Number(*pair.second)),
        info.rule_text ? info.rule_text : WithNote(Each("two numbers", info), info), info, 2);
  }

  const std::vector<KeyRow>& rows() const { return rows_; }

 private:
  template <typename T>
  struct IsBlockList : std::false_type {};
  template <typename T>
      struct IsBlockList<std::vector<T>> : std::bool_constant < requires(T* t, KeyTableWriter* w) {
    t->Serialize(w);
  } > {};

  /// A row for a key declared with `info`, holding `count` numbers (KeyRow::count).
  void Add(std::string key, std::string value, std::string rule, const KeyInfo& info, int count = 0,
           bool prose = false) {
    KeyRow row;
    row.key = std::move(key);
    row.value = std::move(value);
    row.value_is_prose = prose;
    row.rule = std::move(rule);
    row.meaning = info.meaning;
    row.range = info;
    row.count = count;
    rows_.push_back(std::move(row));
  }

  /// Numbers: scalars (bool aside), optional numbers, the vectors and matrix keys use, lists of points.
  template <typename T>
  static constexpr bool IsNumeric() {
    if constexpr (std::is_same_v<T, bool> || NamedEnum<T>) {
      return false;
    } else {
      return std::is_arithmetic_v<T> || std::is_same_v<T, std::optional<double>> ||
             std::is_same_v<T, std::vector<Eigen::Vector3d>> || std::is_same_v<T, Eigen::Vector2d> ||
             std::is_same_v<T, Eigen::Vector3d> || std::is_same_v<T, Eigen::Vector4d> ||
             std::is_same_v<T, Eigen::Matrix3d>;
    }
  }

  /// How many numbers a value of T holds (KeyRow::count).
  template <typename T>
  static constexpr int CountOf() {
    if constexpr (!IsNumeric<T>()) {
      return 0;
    } else if constexpr (std::is_same_v<T, std::vector<Eigen::Vector3d>>) {
      return -1;
    } else if constexpr (std::is_same_v<T, Eigen::Vector2d>) {
      return 2;
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
      return 3;
    } else if constexpr (std::is_same_v<T, Eigen::Vector4d>) {
      return 4;
    } else if constexpr (std::is_same_v<T, Eigen::Matrix3d>) {
      return 9;
    } else {
      return 1;
    }
  }

  /// `rule`, then the key's rule_note after a comma.
  static std::string WithNote(const std::string& rule, const KeyInfo& info) {
    return info.rule_note == nullptr ? rule : rule + ", " + info.rule_note;
  }

  /// A list of numbers and the range each of them must lie in: "[x, y, z], each in [-1, 1]".
  static std::string Each(const std::string& list, const KeyInfo& info) {
    const std::string range = DeclaredRangeText(info);
    return range.empty() ? list : fmt::format("{}, each {}", list, range);
  }

  static std::string Number(double v) {
    if (v == std::numeric_limits<double>::infinity()) return "inf";
    return fmt::format("{}", v);
  }
  static std::string Text(double v) { return Number(v); }
  static std::string Text(const std::optional<double>& v) { return v ? Number(*v) : "unset"; }
  static std::string Text(int v) { return std::to_string(v); }
  static std::string Text(std::uint64_t v) { return std::to_string(v); }
  static std::string Text(bool v) { return v ? "true" : "false"; }
  static std::string Text(const std::string& v) { return v; }
  static std::string Text(const Eigen::Matrix3d& m) {
    std::vector<std::string> rows;
    for (int r = 0; r < 3; ++r) rows.push_back(Text(Eigen::Vector3d(m.row(r).transpose())));
    return fmt::format("[{}]", fmt::join(rows, ", "));
  }
  template <int N>
  static std::string Text(const Eigen::Matrix<double, N, 1>& v) {
    std::vector<std::string> items;
    for (int i = 0; i < v.size(); ++i) items.push_back(Number(v[i]));
    return fmt::format("[{}]", fmt::join(items, ", "));
  }
  static std::string Text(const std::vector<Eigen::Vector3d>& v) { return v.empty() ? "none" : "a list"; }
  template <NamedEnum E>
  static std::string Text(E v) {
    return ToName(v);
  }

  template <typename T>
  static std::string RuleOf(const T&, const KeyInfo& info) {
    if (info.rule_text != nullptr) return info.rule_text;  // as written, "**required**" included
    std::string rule;
    if constexpr (NamedEnum<T>) {
      std::vector<std::string> names;
      for (const std::string& n : NameList<T>()) names.push_back("`" + n + "`");
      rule = fmt::format("one of {}", fmt::join(names, ", "));
    } else if constexpr (std::is_same_v<T, bool>) {
      rule = "true or false";
    } else if constexpr (std::is_same_v<T, std::vector<Eigen::Vector3d>>) {
      rule = Each("a non-empty list of [x, y, z]", info);
    } else if constexpr (std::is_same_v<T, std::string>) {
      rule = "text";
    } else if constexpr (std::is_same_v<T, Eigen::Vector2d>) {
      rule = Each("[x, y]", info);
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
      rule = Each("[x, y, z]", info);
    } else if constexpr (std::is_same_v<T, Eigen::Vector4d>) {
      rule = Each("four numbers", info);
    } else if constexpr (std::is_same_v<T, Eigen::Matrix3d>) {
      rule = Each("3 rows of 3", info);
    } else if constexpr (std::is_same_v<T, std::uint64_t>) {
      rule = "an integer in [0, 2^64 - 1]";  // the loader's own range (a seed: any will do)
    } else {
      rule = DeclaredRangeText(info);
      if (std::is_integral_v<T>) {
        rule = rule.empty() ? "an integer" : "an integer " + rule;
      } else if (rule.empty()) {
        rule = "a number";
      }
    }
    rule = WithNote(rule, info);
    return info.required ? (rule.empty() ? "**required**" : "**required**, " + rule) : rule;
  }

  std::string prefix_;
  std::vector<KeyRow> rows_;
};

/// A Markdown table of `rows`, each key prefixed by `section` ("stack.nmpc."): | key | default | rule | meaning |.
inline std::string KeyTableMarkdown(const std::vector<KeyRow>& rows, const std::string& section) {
  const auto cell = [](const std::string& text) {  // a '|' would end the cell
    std::string escaped;
    for (const char c : text) {
      if (c == '|') escaped.push_back('\\');
      escaped.push_back(c);
    }
    return escaped;
  };
  std::string md = "| key | default | accepts | meaning |\n|---|---|---|---|\n";
  for (const KeyRow& r : rows) {
    const std::string value = r.value.empty() || r.value_is_prose ? r.value : "`" + r.value + "`";
    md += fmt::format("| `{}{}` | {} | {} | {} |\n", section, r.key, cell(value), cell(r.rule), cell(r.meaning));
  }
  return md;
}

}  // namespace rotorguard::io
