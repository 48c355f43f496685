#pragma once
/// Config keys declared once, next to the fields they set (Drake's `Serialize(Archive*)`): an
/// options struct lists its keys in a member template
///
///     template <typename Archive>
///     void Serialize(Archive* a) {
///       a->Visit("horizon_steps", &horizon_steps, {.meaning = "N: prediction steps", .min = 1, .max = 200});
///       a->Visit("q_position", &q_position, {.meaning = "Q_p of eq. (10)"});
///     }
///
/// and every archive walks that one list: the strict YAML reader (io/config_archive.h), the JSON
/// reader and writer, and the writer of the documentation's key tables. The modules that declare
/// keys know no archive and no file format: this header is all they include.
///
/// Enums that config files name (controller, fault detection, planner, mission) declare their
/// names once too, as a table found by `NamesOf`, from which parsing, printing and the list of
/// accepted words all come.
#include <array>
#include <cstddef>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rotorguard {

/// What a key means and accepts: its row in the documentation and the loader's range check.
struct KeyInfo {
  /// The documentation's "meaning" column (units in the key's name or here).
  const char* meaning = "";
  /// Numbers must lie in [min, max] (a list of blocks: have at least `min` items; a vector, a
  /// pair, a triple, a matrix or a list of points: each of its numbers) ...
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  /// ... or, when set, in (0, max]: min is then not used.
  bool positive = false;
  /// The upper end excluded: [min, max), or (0, max) when positive.
  bool open_max = false;
  /// The key must be present (the loader reports it missing); else absent keys keep the default.
  bool required = false;
  /// For a block: the key a plain scalar in place of the block sets (`planner: flatness` for
  /// `planner: {method: flatness}`); none when the block must be a map.
  const char* shorthand = nullptr;
  /// The documentation's default and rule, when the value's own would mislead (a default that
  /// depends on another key, a range that does); none: written from the value and the range.
  const char* default_text = nullptr;
  const char* rule_text = nullptr;
  /// Words the documentation adds to the rule written from the value and the range: a rule
  /// Validate() checks beyond the range ("z ≥ 0").
  const char* rule_note = nullptr;
};

/// Ends of ranges that many keys share (docs/scenarios.md), so that a key and the Validate() of its
/// struct state the same bound. They are what a user of a multirotor could still defend, with
/// margin: beyond them a value is a slip of a digit or a unit, and some would make a loop over
/// time or space run for hours (a collision check's step of check_step_m / v_max, a rate's
/// callbacks per simulated second).
inline constexpr double kMaxSpeedMS = 50.0;           ///< [m/s]: racing quadrotors top out near it
/// [m/s], [m/s²], [m/s³]: the slowest a limit of motion may be. Below, it is a slip of a unit, and a
/// curve's phase rate or a profile's duration computed from it leaves the doubles (4.9e-324 m/s
/// made a lemniscate's phase rate 0).
inline constexpr double kMinSpeedMS = 1e-3;
inline constexpr double kMinAccelerationMS2 = 1e-3;
inline constexpr double kMinJerkMS3 = 1e-3;
inline constexpr double kMaxAccelerationMS2 = 100.0;  ///< [m/s²]: about 10 g
inline constexpr double kMaxJerkMS3 = 1000.0;         ///< [m/s³]
inline constexpr double kMaxBodyRateRadS = 100.0;     ///< [rad/s]: about 16 turns a second
inline constexpr double kMaxRateHz = 10000.0;         ///< [Hz]: a loop of the stack or a sensor
/// [Hz]: its slowest, a tick each 100 s; below, a "rate" is a slip of a unit, and its period (1 /
/// rate) leaves the range of the simulation's integer nanoseconds.
inline constexpr double kMinRateHz = 0.01;
inline constexpr double kMaxCoordinateM = 10000.0;    ///< [m]: each coordinate of a place in the world
/// [m]: each coordinate of a point on the vehicle from its centre of gravity (a rotor, a sensor),
/// or a length on it; a line of 16 docked units (64 rotors) a few metres apart spans tens of metres.
inline constexpr double kMaxBodyOffsetM = 50.0;
inline constexpr double kMaxTimeoutS = 3600.0;  ///< [s]: a wait, a hold, a timeout
inline constexpr double kMaxFlightS = 86400.0;  ///< [s]: a day; a flight's time and times within it
inline constexpr double kMaxWeight = 1e9;       ///< a cost's weight, relative to its others
/// A heading or a turn [rad]: any angle is one of [-2π, 2π].
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// A name of an enum's value, as config files write it.
template <typename E>
struct EnumName {
  E value;
  const char* name;
};

/// The names of E's values, in the order shown to users: an ADL-found `NamesOf(const E*)` that
/// returns a span of EnumName<E>, declared next to the enum.
template <typename E>
std::span<const EnumName<E>> EnumNames() {
  return NamesOf(static_cast<const E*>(nullptr));
}

/// Whether E declares its names (NamesOf).
template <typename E>
concept NamedEnum = requires {
  NamesOf(static_cast<const E*>(nullptr));
};

/// The name of `value`; "" for a value without one (never for a table that lists them all).
template <NamedEnum E>
const char* ToName(E value) {
  for (const EnumName<E>& n : EnumNames<E>()) {
    if (n.value == value) return n.name;
  }
  return "";
}

/// The value named `name`, if any.
template <NamedEnum E>
std::optional<E> FromName(std::string_view name) {
  for (const EnumName<E>& n : EnumNames<E>()) {
    if (name == n.name) return n.value;
  }
  return std::nullopt;
}

/// Every name, in order.
template <NamedEnum E>
std::vector<std::string> NameList() {
  std::vector<std::string> names;
  for (const EnumName<E>& n : EnumNames<E>()) names.emplace_back(n.name);
  return names;
}

/// An angle kept in radians but written in degrees in config files (`theta_max_deg`): the reader
/// converts, the documentation shows degrees.
struct DegreesOf {
  double* radians;
};

/// Two numbers written as one key's list [lo, hi] (`altitude_band_m: [0.5, 2.5]`).
struct PairOf {
  double* first;
  double* second;
};

/// A number kept in one unit and written in another (`thrust_coefficient_n_per_rpm2`, kept per
/// (rad/s)²): `from_file` converts what a file says, `to_file` converts back.
struct ConvertedOf {
  double* value;
  double (*from_file)(double);
  double (*to_file)(double);
};

/// Three numbers written as one key's list [x, y, z] (`size_m: [6, 3, 1]`).
struct TripleOf {
  double* x;
  double* y;
  double* z;
};

}  // namespace rotorguard
