#pragma once
/// The strict YAML reader of the keys an options struct declares (core/config_schema.h): a struct's
/// `Serialize(ConfigReader*)` reads each key it lists from a map node, through ConfigNode, so that
/// every error names the file, line, column and key path. Absent keys keep the struct's values
/// (its defaults); keys the struct does not declare are errors; each block read is validated
/// (its `Validate()`, or the check its declaration names) and a violation is reported at the key.
///
///     stack::FlightStackOptions o;
///     io::ReadConfig(doc.root().Required("stack"), &o);
#include <fmt/format.h>

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/error.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::io {

/// Runs `validate` and reports its failure at `node`: a ValidationError at the key its field()
/// names below node (or its nearest existing parent), any other invalid argument at node itself.
template <typename F>
void ValidateAt(const ConfigNode& node, F&& validate) {
  try {
    validate();
  } catch (const ValidationError& e) {
    node.FailAt(e.field(), e.what());
  } catch (const std::invalid_argument& e) {
    node.Fail(e.what());
  }
}

class ConfigReader;

/// A struct that declares its keys.
template <typename T>
concept DeclaresKeys = requires(T* t, ConfigReader* a) {
  t->Serialize(a);
};

/// Reads the keys `value` declares from the map `node` and rejects the others; no validation.
template <DeclaresKeys T>
void ReadKeys(const ConfigNode& node, T* value);

/// ReadKeys, then `value`'s own Validate() when it has one, its failure reported at its key.
template <DeclaresKeys T>
void ReadConfig(const ConfigNode& node, T* value) {
  ReadKeys(node, value);
  if constexpr (requires { value->Validate(); }) ValidateAt(node, [&] { value->Validate(); });
}

/// The key names a struct declares, in order ("{rotor, at_time_s, loss}" in messages).
class KeyNameCollector {
 public:
  template <typename T, typename... Rest>
  void Visit(const char* key, T&&, const KeyInfo& = {}, Rest&&...) {
    names_.emplace_back(key);
  }
  const std::vector<std::string>& names() const { return names_; }

 private:
  std::vector<std::string> names_;
};

template <DeclaresKeys T>
std::string KeyListOf() {
  T sample{};
  KeyNameCollector names;
  sample.Serialize(&names);
  return fmt::format("{{{}}}", fmt::join(names.names(), ", "));
}

class ConfigReader {
 public:
  explicit ConfigReader(const ConfigNode& map) : node_(map) {}
  /// The map being read (a Serialize that needs a cross-key check reads it).
  const ConfigNode& node() const { return node_; }

  /// One key: a number, an integer, a boolean, a word, a vector, an enum's name, an optional
  /// number (null: unset), a list of points, a block (a struct that declares its keys, validated once read) or a
  /// list of blocks.
  template <typename T>
  void Visit(const char* key, T* value, const KeyInfo& info = {}) {
    if (const std::optional<ConfigNode> n = Find(key, info)) {
      if constexpr (DeclaresKeys<T>) {
        ReadBlock(*n, value, info);
        if constexpr (requires { value->Validate(); }) ValidateAt(*n, [&] { value->Validate(); });
      } else {
        Read(*n, value, info);
      }
    }
  }
  /// A block whose validity depends on more than its own keys: `validate` runs once it is read.
  template <DeclaresKeys T, typename F>
  void Visit(const char* key, T* value, const KeyInfo& info, F&& validate) {
    if (const std::optional<ConfigNode> n = Find(key, info)) {
      ReadBlock(*n, value, info);
      ValidateAt(*n, validate);
    }
  }
  /// An angle written in degrees, in the open interval (info.min, info.max).
  void Visit(const char* key, DegreesOf angle, const KeyInfo& info) {
    if (const std::optional<ConfigNode> n = Find(key, info)) {
      const double deg = n->AsDouble();
      if (!(deg > info.min && deg < info.max)) {
        n->Fail(
            fmt::format("{} = {:g} is invalid; expected an angle in ({:g}, {:g}) deg", key, deg, info.min, info.max));
      }
      *angle.radians = deg * 3.14159265358979323846 / 180.0;
    }
  }
  /// A number in a file's unit, kept in another.
  void Visit(const char* key, ConvertedOf number, const KeyInfo& info) {
    if (const std::optional<ConfigNode> n = Find(key, info)) {
      double x = 0.0;
      Read(*n, &x, info);
      *number.value = number.from_file(x);
    }
  }
  /// Three numbers as one list, each in the key's range.
  void Visit(const char* key, TripleOf triple, const KeyInfo& info) {
    if (const std::optional<ConfigNode> n = Find(key, info)) {
      const std::vector<double> v = Numbers(*n, 3, info);
      *triple.x = v[0];
      *triple.y = v[1];
      *triple.z = v[2];
    }
  }
  /// Two numbers as one list, each in the key's range.
  void Visit(const char* key, PairOf pair, const KeyInfo& info) {
    if (const std::optional<ConfigNode> n = Find(key, info)) {
      const std::vector<double> v = Numbers(*n, 2, info);
      *pair.first = v[0];
      *pair.second = v[1];
    }
  }

 private:
  std::optional<ConfigNode> Find(const char* key, const KeyInfo& info) const {
    if (info.required) return node_.Required(key);
    return node_.Optional(key);
  }

  template <typename T>
  static void ReadBlock(const ConfigNode& n, T* value, const KeyInfo& info) {
    if (info.shorthand != nullptr && n.IsScalar()) {
      // `planner: flatness` stands for `planner: {method: flatness}`: the scalar read as that key.
      ShorthandReader shorthand(n, info.shorthand);
      value->Serialize(&shorthand);
      return;
    }
    ReadKeys(n, value);
  }

  /// Reads only the shorthand key of a block, from the block's scalar.
  class ShorthandReader {
   public:
    ShorthandReader(const ConfigNode& scalar, const char* key) : scalar_(scalar), key_(key) {}
    template <typename T, typename... Rest>
    void Visit(const char* key, T&& value, const KeyInfo& info = {}, Rest&&...) {
      if constexpr (requires { ConfigReader::Read(scalar_, value, info); }) {
        if (std::string_view(key) == key_) ConfigReader::Read(scalar_, value, info);
      }
    }

   private:
    ConfigNode scalar_;
    std::string_view key_;
  };

  /// A number in the key's range; the error names the value and the range.
  static double Number(const ConfigNode& n, const KeyInfo& info) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    if (info.max == kInf) {  // the unbounded ranges' own words ("a positive number (> 0)")
      if (info.positive) return n.AsPositive();
      if (info.min == 0.0) return n.AsNonNegative();
      if (info.min == -kInf) return n.AsDouble();
    }
    return n.AsNumberIn(info);
  }
  /// A list of `size` numbers (any length when negative), each in the key's range: an error names
  /// the item ("center_m.2") and its line.
  static std::vector<double> Numbers(const ConfigNode& n, int size, const KeyInfo& info) {
    std::vector<double> v = n.AsDoubleList(size);  // the list's shape, and finite numbers
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = Number(n.At(i), info);
    return v;
  }

  static void Read(const ConfigNode& n, double* v, const KeyInfo& info) { *v = Number(n, info); }
  /// null unsets it (what io::JsonWriter writes for an unset one, so that options read back as written).
  static void Read(const ConfigNode& n, std::optional<double>* v, const KeyInfo& info) {
    if (n.IsNull()) {
      v->reset();
      return;
    }
    double x = 0.0;
    Read(n, &x, info);
    *v = x;
  }
  static void Read(const ConfigNode& n, int* v, const KeyInfo& info) {
    const auto lo = static_cast<std::int64_t>(std::max<double>(info.min, std::numeric_limits<int>::min()));
    const auto hi = static_cast<std::int64_t>(std::min<double>(info.max, std::numeric_limits<int>::max()));
    *v = static_cast<int>(n.AsIntIn(lo, hi));
  }
  static void Read(const ConfigNode& n, std::uint64_t* v, const KeyInfo&) { *v = n.AsUint64(); }
  static void Read(const ConfigNode& n, bool* v, const KeyInfo&) { *v = n.AsBool(); }
  static void Read(const ConfigNode& n, std::string* v, const KeyInfo&) { *v = n.AsString(); }
  template <int N>
  static void Read(const ConfigNode& n, Eigen::Matrix<double, N, 1>* v, const KeyInfo& info) {
    const std::vector<double> x = Numbers(n, N, info);
    for (int i = 0; i < N; ++i) (*v)[i] = x[static_cast<std::size_t>(i)];
  }
  static void Read(const ConfigNode& n, Eigen::Matrix3d* m, const KeyInfo& info) {
    if (!n.IsSequence() || n.size() != 3) n.Fail("expected a 3x3 matrix written as three rows of three numbers");
    for (std::size_t r = 0; r < 3; ++r) {
      const std::vector<double> row = Numbers(n.At(r), 3, info);
      for (int c = 0; c < 3; ++c) (*m)(static_cast<int>(r), c) = row[static_cast<std::size_t>(c)];
    }
  }
  static void Read(const ConfigNode& n, std::vector<Eigen::Vector3d>* v, const KeyInfo& info) {
    if (!n.IsSequence() || n.size() == 0) n.Fail("expected a non-empty list of [x, y, z] points");
    v->clear();
    for (std::size_t k = 0; k < n.size(); ++k) {
      const std::vector<double> x = Numbers(n.At(k), 3, info);
      v->emplace_back(x[0], x[1], x[2]);
    }
  }
  template <NamedEnum E>
  static void Read(const ConfigNode& n, E* v, const KeyInfo&) {
    *v = *FromName<E>(n.AsEnum(NameList<E>()));
  }
  template <DeclaresKeys T>
  static void Read(const ConfigNode& n, std::vector<T>* v, const KeyInfo& info) {
    if (!n.IsSequence()) n.Fail("expected a list of " + KeyListOf<T>());
    if (info.min >= 1.0 && n.size() == 0) n.Fail("expected a non-empty list of " + KeyListOf<T>());
    v->clear();
    for (std::size_t i = 0; i < n.size(); ++i) {
      T item{};
      ReadConfig(n.At(i), &item);
      v->push_back(item);
    }
  }

  ConfigNode node_;
};

template <DeclaresKeys T>
void ReadKeys(const ConfigNode& node, T* value) {
  ConfigReader reader(node);
  value->Serialize(&reader);
  node.RejectUnknownKeys();
}

}  // namespace rotorguard::io
