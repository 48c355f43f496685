#pragma once
/// The ranges keys declare (KeyInfo, core/config_schema.h), for values set in code: an options
/// struct's Validate() calls CheckDeclaredRanges, so that a user of the API who bypasses the
/// loader meets the bounds the loader enforces and docs/scenarios.md states, declared once.
///
///     void SupervisorOptions::Validate() const {
///       ... rules across keys ...
///       CheckDeclaredRanges("SupervisorOptions", *this);
///     }
#include <fmt/format.h>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/error.h"

namespace rotorguard {

/// Whether `v` lies in the range `info` declares: [min, max], or (0, max] when positive, the upper
/// end excluded when open_max.
inline bool InDeclaredRange(double v, const KeyInfo& info) {
  const bool below_max = info.open_max ? v < info.max : v <= info.max;
  return below_max && (info.positive ? v > 0.0 : v >= info.min);  // false for NaN
}

/// An end of a range as a reader knows it: a multiple of π/2 (an angle's bound) as "π/2", "-2π";
/// else the number ("inf" for infinity).
inline std::string RangeBoundText(double v) {
  constexpr double kHalfPi = std::numbers::pi / 2.0;
  const double k = std::round(v / kHalfPi);
  if (k != 0.0 && std::abs(k) <= 8.0 && v == k * kHalfPi) {
    const std::string sign = k < 0.0 ? "-" : "";
    const int n = static_cast<int>(std::abs(k));
    if (n % 2 != 0) return n == 1 ? sign + "π/2" : fmt::format("{}{}π/2", sign, n);
    return n == 2 ? sign + "π" : fmt::format("{}{}π", sign, n / 2);
  }
  if (v == std::numeric_limits<double>::infinity()) return "inf";
  if (v == -std::numeric_limits<double>::infinity()) return "-inf";
  return fmt::format("{}", v);
}

/// The range `info` declares, in words: "in [0, 1]", "in (0, 50]", "in [0, 1)", "≥ 0", "> 0"; ""
/// for none.
inline std::string DeclaredRangeText(const KeyInfo& info) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const char* close = info.open_max ? ")" : "]";
  if (info.positive) return info.max < kInf ? fmt::format("in (0, {}{}", RangeBoundText(info.max), close) : "> 0";
  if (info.min > -kInf && info.max < kInf) {
    return fmt::format("in [{}, {}{}", RangeBoundText(info.min), RangeBoundText(info.max), close);
  }
  if (info.min > -kInf) return fmt::format("≥ {}", RangeBoundText(info.min));
  if (info.max < kInf) return fmt::format("{} {}", info.open_max ? "<" : "≤", RangeBoundText(info.max));
  return "";
}

namespace detail {

/// A struct that declares its keys to archive A.
template <typename T, typename A>
concept DeclaresKeysTo = requires(T* t, A* a) {
  t->Serialize(a);
};

/// The archive behind CheckDeclaredRanges: each number checked against its key's range; blocks
/// without a Validate() of their own walked, their keys' paths below the struct's ("weights.time").
class DeclaredRangeChecker {
 public:
  DeclaredRangeChecker(const std::string& owner, std::string prefix) : owner_(owner), prefix_(std::move(prefix)) {}

  template <typename T, typename... Rest>
  void Visit(const char* key, T* value, const KeyInfo& info = {}, Rest&&...) {
    const std::string field = prefix_ + key;
    if constexpr (std::is_same_v<T, double>) {
      Check(field, *value, info);
    } else if constexpr (std::is_same_v<T, std::optional<double>>) {
      if (value->has_value()) Check(field, **value, info);
    } else if constexpr (std::is_same_v<T, int>) {
      if (!(*value >= info.min && *value <= info.max)) ThrowValidation(owner_, field, *value, Rule("an integer", info));
    } else if constexpr (std::is_same_v<T, Eigen::Vector2d> || std::is_same_v<T, Eigen::Vector3d> ||
                         std::is_same_v<T, Eigen::Vector4d>) {
      for (int i = 0; i < value->size(); ++i) Check(fmt::format("{}.{}", field, i), (*value)[i], info);
    } else if constexpr (std::is_same_v<T, Eigen::Matrix3d>) {
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) Check(fmt::format("{}.{}.{}", field, r, c), (*value)(r, c), info);
      }
    } else if constexpr (std::is_same_v<T, std::vector<Eigen::Vector3d>>) {
      for (std::size_t k = 0; k < value->size(); ++k) {
        for (int i = 0; i < 3; ++i) Check(fmt::format("{}.{}.{}", field, k, i), (*value)[k][i], info);
      }
    } else if constexpr (DeclaresKeysTo<T, DeclaredRangeChecker>) {
      if constexpr (!requires { value->Validate(); }) {  // a block that validates itself is its own business
        DeclaredRangeChecker nested(owner_, field + ".");
        value->Serialize(&nested);
      }
    } else if constexpr (IsBlockList<T>::value) {
      if constexpr (!requires(const typename T::value_type& item) { item.Validate(); }) {
        for (std::size_t i = 0; i < value->size(); ++i) {
          DeclaredRangeChecker nested(owner_, fmt::format("{}.{}.", field, i));
          (*value)[i].Serialize(&nested);
        }
      }
    }
    // Words, booleans, enums and seeds have no range.
  }
  /// An angle kept in radians, declared in degrees in the open interval (min, max).
  void Visit(const char* key, DegreesOf angle, const KeyInfo& info) {
    const double deg = *angle.radians * 180.0 / std::numbers::pi;
    if (!(deg > info.min && deg < info.max)) {
      ThrowValidation(owner_, prefix_ + key, deg, fmt::format("an angle in ({}, {}) deg", info.min, info.max));
    }
  }
  /// A number kept in one unit, declared in the file's.
  void Visit(const char* key, ConvertedOf number, const KeyInfo& info) {
    Check(prefix_ + key, number.to_file(*number.value), info);
  }
  void Visit(const char* key, TripleOf t, const KeyInfo& info) {
    const std::string field = prefix_ + key;
    Check(field + ".0", *t.x, info);
    Check(field + ".1", *t.y, info);
    Check(field + ".2", *t.z, info);
  }
  void Visit(const char* key, PairOf pair, const KeyInfo& info) {
    const std::string field = prefix_ + key;
    Check(field + ".0", *pair.first, info);
    Check(field + ".1", *pair.second, info);
  }

 private:
  template <typename T>
  struct IsBlockList : std::false_type {};
  template <typename T>
  struct IsBlockList<std::vector<T>> : std::bool_constant<DeclaresKeysTo<T, DeclaredRangeChecker>> {};

  void Check(const std::string& field, double v, const KeyInfo& info) const {
    if (!InDeclaredRange(v, info)) ThrowValidation(owner_, field, v, Rule("a number", info));
  }
  /// "a number in [0, 1]"; "a number" alone for a key without a range (which then only NaN breaks).
  static std::string Rule(const char* what, const KeyInfo& info) {
    const std::string range = DeclaredRangeText(info);
    return range.empty() ? what : fmt::format("{} {}", what, range);
  }

  const std::string& owner_;
  std::string prefix_;
};

}  // namespace detail

/// Checks every number `value` declares (its Serialize) against the range its key declares, as the
/// loader does; throws ValidationError "<owner>::<key> = <value> is invalid; expected a number in
/// [lo, hi]", the field being the key's path below `value` ("size_m.2", "weights.time"). Blocks
/// with a Validate() of their own are left to it. NaN is out of every range. `prefix` goes before
/// each field: the path of `value` in the owner's ("weights.").
template <typename T>
void CheckDeclaredRanges(const std::string& owner, const T& value, const std::string& prefix = "") {
  detail::DeclaredRangeChecker checker(owner, prefix);
  // Serialize is one member for every archive, reading or writing; this archive only reads.
  const_cast<T&>(value).Serialize(&checker);
}

}  // namespace rotorguard
