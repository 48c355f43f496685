#pragma once
// The strict YAML layer's own tree and helpers (not public API): the document config_node.h's
// ConfigDocument parses into, shared by the parser (config_document.cc), the reader
// (config_node.cc) and the errors (config_tree.cc).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "rotorguard/io/config_node.h"

namespace rotorguard::io {
namespace detail {

struct Value;

/// One key of a map with where the key itself was written (unknown-key errors point at the key).
struct MapEntry {
  std::string key;
  int key_line = 0;
  int key_column = 0;
  std::shared_ptr<Value> value;
  bool from_override = false;  ///< the key was added by an override (--set), not written in the file
};

/// Our own tree, built from yaml-cpp's parser events rather than from YAML::Node: YAML::Node
/// silently keeps the first of duplicate keys, shares aliased nodes (so an override of one would
/// change the other) and can throw from accessors. Owning the tree keeps every later read
/// exception-free apart from our own ConfigError.
struct Value {
  enum class Kind { kNull, kScalar, kMap, kSequence };

  Kind kind = Kind::kNull;
  std::string scalar;
  /// yaml-cpp's tag: "?" for a plain scalar, "!" for a quoted or block scalar, else an explicit
  /// tag. Numbers and booleans must be plain: a quoted "1.5" is a string in YAML.
  std::string tag = "?";
  /// 1-based; 0 when unknown (values from an override).
  int line = 0;
  int column = 0;
  bool from_override = false;

  std::vector<MapEntry> entries;                         // kMap, document order
  std::unordered_map<std::string, std::size_t> index;    // kMap: key -> entries index
  std::vector<std::shared_ptr<Value>> items;             // kSequence

  /// Keys asked for through Has/Required/Optional, present or not. Present ones count as used;
  /// all of them form the "expected one of" list of RejectUnknownKeys, in first-asked order.
  std::vector<std::string> asked_keys;
  std::unordered_set<std::string> asked_set;
};

struct DocumentState {
  std::string file;
  std::shared_ptr<Value> root;
};

}  // namespace detail

namespace internal {

using detail::MapEntry;
using detail::Value;
using Kind = detail::Value::Kind;
using ValuePtr = std::shared_ptr<Value>;

/// Aliases are expanded into copies; this bounds the copies so a "billion laughs" document is an
/// error instead of exhausting memory.
constexpr std::size_t kMaxAliasCopiedNodes = 100000;

std::string ComposeWhat(const std::string& file, int line, int column, const std::string& key_path,
                        const std::string& message);

std::string JoinPath(std::string_view parent, std::string_view child);

std::string JoinList(const std::vector<std::string>& items);

std::vector<std::string> SplitPath(std::string_view path);

/// A sequence index segment: decimal digits only.
std::optional<std::size_t> ParseIndex(std::string_view segment);

/// The text of a value for a message: quoted, control characters escaped, long text shortened.
std::string Quote(std::string_view text);

std::string ShortTag(const std::string& tag);

/// What a value is, for "expected X, got Y" messages.
std::string Describe(const Value& value);

const std::string& SourceFile(const Value& value, const std::string& file);

[[noreturn]] void ThrowAt(const Value& value, const std::string& file, const std::string& key_path,
                          const std::string& message);

// ---- Numbers. Parsed by hand rather than with yaml-cpp's as<double>: that accepts ".nan" and
// ".inf", rejects "nan"/"inf"/"1e999" as a generic bad conversion (so "not finite" could not be
// told from "not a number"), and goes through a locale-dependent stream.

enum class NumberStatus { kOk, kNotANumber, kNotFinite, kOverflow };

struct ParsedNumber {
  NumberStatus status = NumberStatus::kNotANumber;
  double value = 0.0;
};

std::size_t CountDigits(std::string_view text, std::size_t from);

/// YAML 1.2 core-schema float syntax: [-+]? ( digits [. digits*] | . digits ) ([eE] [-+]? digits)?
/// plus the non-finite spellings, which are recognised (and rejected by callers) case-insensitively
/// with or without the leading dot so the message says "not finite" rather than "not a number".
ParsedNumber ParseYamlFloat(std::string_view text);

struct ParsedInteger {
  bool ok = false;
  bool overflow = false;
  bool negative = false;
  std::uint64_t magnitude = 0;
};

/// [-+]? ( decimal digits | 0x hex digits ).
ParsedInteger ParseYamlInteger(std::string_view text);

/// The system's reason for a file that cannot be opened, in words ("no such file").
std::string ReasonFromErrno(int error);

}  // namespace internal
}  // namespace rotorguard::io
