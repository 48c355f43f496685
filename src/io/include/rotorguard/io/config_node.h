#pragma once
/// Strict schema layer over yaml-cpp. yaml-cpp on its own accepts `.nan`/`.inf`, keeps the first of
/// duplicate keys and ignores misspelt keys; configs read through ConfigDocument/ConfigNode instead
/// reject unknown, duplicate and missing keys, non-finite numbers, unit strings and wrong types, and
/// every error names the file, the 1-based line and column, the key path and what was expected.
///
/// Typical loader:
///   const ConfigDocument doc = ConfigDocument::LoadFile(path);
///   const ConfigNode root = doc.root();
///   params.mass_kg = root.Required("mass_kg").AsPositive();
///   if (auto drag = root.Optional("drag")) params.drag = drag->AsVector3();
///   root.RejectUnknownKeys();
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace rotorguard {
struct KeyInfo;
}  // namespace rotorguard

namespace rotorguard::io {

/// The pseudo file name of values that came from a command-line override (ApplyOverride).
inline constexpr std::string_view kOverrideSource = "--set";

/// An invalid input: where it is and what was expected. what() is
/// "FILE:LINE:COL: KEY_PATH: MESSAGE" (LINE/COL omitted when unknown; KEY_PATH omitted when empty).
class ConfigError : public std::runtime_error {
 public:
  /// `line` and `column` are 1-based; 0 means unknown (a value from an override has neither).
  ConfigError(std::string file, int line, int column, std::string key_path, std::string message);

  const std::string& file() const { return file_; }
  /// 1-based line, 0 when unknown.
  int line() const { return line_; }
  /// 1-based column, 0 when unknown.
  int column() const { return column_; }
  /// Dotted key path ("sensors.imu.rate_hz", "faults.0.kind"); empty for the document itself.
  const std::string& key_path() const { return key_path_; }
  /// The bare message, without location.
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  int column_;
  std::string key_path_;
  std::string message_;
};

/// An input file that cannot be read at all (missing, a directory, permission denied).
/// what() is "PATH: cannot read input file: REASON".
class InputFileError : public std::runtime_error {
 public:
  InputFileError(std::string path, std::string reason);

  const std::string& path() const { return path_; }
  /// "no such file", "is a directory", "permission denied", or the system's description.
  const std::string& reason() const { return reason_; }

 private:
  std::string path_;
  std::string reason_;
};

/// An input file whose content is damaged (truncated, a bad record, a checksum mismatch). what()
/// is "PATH: corrupt at byte OFFSET: MESSAGE"; the CLI exits 3 on it, as on InputFileError.
class CorruptFileError : public std::runtime_error {
 public:
  CorruptFileError(std::string path, std::uint64_t byte_offset, std::string message);

  const std::string& path() const { return path_; }
  /// Offset of the first byte found wrong, from the start of the file.
  std::uint64_t byte_offset() const { return byte_offset_; }
  const std::string& message() const { return message_; }

 private:
  std::string path_;
  std::uint64_t byte_offset_;
  std::string message_;
};

/// Reads a whole input file; throws InputFileError (missing, a directory, unreadable).
std::string ReadInputFile(const std::string& path);

namespace detail {
struct Value;
struct DocumentState;
}  // namespace detail

class ConfigNode;

/// A parsed YAML document plus the bookkeeping of which map keys were read.
///
/// Move-only: nodes handed out by root() share the document's state (and keep it alive), so a copy
/// would silently share overrides and used-key bookkeeping. Not thread-safe.
class ConfigDocument {
 public:
  /// Reads and parses `path`. Throws InputFileError if the file cannot be read and ConfigError if
  /// it is malformed YAML, empty, has duplicate keys, or its top level is not a map.
  static ConfigDocument LoadFile(const std::string& path);
  /// Parses `text`; `name` is the file name that errors report.
  static ConfigDocument LoadString(const std::string& text, const std::string& name);

  ConfigDocument(ConfigDocument&&) noexcept = default;
  ConfigDocument& operator=(ConfigDocument&&) noexcept = default;
  ConfigDocument(const ConfigDocument&) = delete;
  ConfigDocument& operator=(const ConfigDocument&) = delete;
  ~ConfigDocument() = default;

  const std::string& file() const;

  /// Replaces the value at a dotted key path ("faults.0.onset.at_time_s"; integer segments index
  /// sequences) with `value_text` parsed as YAML (an empty text is null). The path must already
  /// exist: otherwise throws ConfigError with file "--set" naming the first missing segment and
  /// listing the keys that exist there. Values that came from an override report their location
  /// as file "--set" (no line) in later errors, with the key path.
  void ApplyOverride(const std::string& key_path, const std::string& value_text);
  /// ApplyOverride for a command-line argument "KEY_PATH=VALUE" (split at the first '=').
  void ApplyOverrideAssignment(const std::string& assignment);

  /// The top-level node; always a map (loading rejects anything else).
  ConfigNode root() const;

 private:
  explicit ConfigDocument(std::shared_ptr<detail::DocumentState> state);

  std::shared_ptr<detail::DocumentState> state_;
};

/// A view of one node with its key path. Cheap to copy. Map reads mark keys as used; views of the
/// same map share that bookkeeping. Every accessor throws ConfigError (never a yaml-cpp exception)
/// located at this node when the node is not what the accessor expects.
class ConfigNode {
 public:
  /// "" for the root, "sensors.imu.rate_hz", "faults.0.kind".
  const std::string& key_path() const { return key_path_; }
  /// "FILE:LINE:COL", or "--set" for a value that came from an override.
  std::string Location() const;

  bool IsMap() const;
  bool IsSequence() const;
  /// True for a non-null scalar (a number, a word, a quoted string).
  bool IsScalar() const;
  /// True for an empty value, `~` or `null`.
  bool IsNull() const;

  // ---- Maps. Each throws if this node is not a map.
  /// True if `key` is present; marks it as used (and as an accepted key for RejectUnknownKeys).
  bool Has(std::string_view key) const;
  /// The value of `key`; error "missing required key 'k'" at this map's location.
  ConfigNode Required(std::string_view key) const;
  /// The value of `key` if present (possibly null), else nullopt.
  std::optional<ConfigNode> Optional(std::string_view key) const;
  /// The keys in document order. Does not mark them as used.
  std::vector<std::string> Keys() const;
  /// Throws ConfigError at the first key never asked for via Has/Required/Optional:
  /// "unknown key 'masss_kg'; expected one of: a, b, c" (the keys asked for, present or not, in the
  /// order first asked). Call after reading a map.
  void RejectUnknownKeys() const;

  // ---- Sequences. Each throws if this node is not a sequence.
  /// The number of items.
  std::size_t size() const;
  /// Item `i` (key path "<parent>.<i>"); throws if out of range.
  ConfigNode At(std::size_t i) const;

  // ---- Scalars. Numbers and booleans must be plain (unquoted) scalars: "1.5" in quotes is a
  // string. Each throws ConfigError at this node saying what was expected.
  /// A finite number: "1.5kg" -> "'1.5kg' is not a number; expected a finite number";
  /// .nan/.inf/nan/inf/1e999 -> "... is not finite". Decimal and exponent forms only (no hex).
  double AsDouble() const;
  /// A finite number in the closed interval [lo, hi]: "expected a number in [lo, hi]".
  double AsDoubleIn(double lo, double hi) const;
  /// A finite number > 0.
  double AsPositive() const;
  /// A finite number in the range `info` declares (InDeclaredRange): "expected a number in (0, 50]".
  double AsNumberIn(const KeyInfo& info) const;
  /// A finite number >= 0.
  double AsNonNegative() const;
  /// An integer literal: decimal or 0x hexadecimal, optional sign (no "1.5", "1e3", "abc").
  std::int64_t AsInt() const;
  /// An integer in the closed interval [lo, hi].
  std::int64_t AsIntIn(std::int64_t lo, std::int64_t hi) const;
  /// A non-negative integer up to 2^64-1 (seeds); decimal or 0x hexadecimal.
  std::uint64_t AsUint64() const;
  /// true/false only (also True/TRUE/False/FALSE); yes/no/on/off are rejected.
  bool AsBool() const;
  /// Any non-null scalar as text (quoted or not).
  std::string AsString() const;
  /// A string from `allowed`: "'x' is not allowed; expected one of: a, b, c".
  std::string AsEnum(const std::vector<std::string>& allowed) const;
  /// A sequence of exactly 3 finite numbers.
  Eigen::Vector3d AsVector3() const;
  /// A sequence of finite numbers; its length must be `expected_size` when that is >= 0.
  std::vector<double> AsDoubleList(int expected_size = -1) const;

  /// Throws ConfigError at this node with `message`.
  [[noreturn]] void Fail(const std::string& message) const;
  /// Throws ConfigError for a rule that a later validation reports by field name. The error is
  /// located at the descendant `relative_path` ("rotors.2.max_thrust_n": dotted, integer segments
  /// index sequences) if it exists, else at its deepest existing ancestor (at worst this node); the
  /// key path is always this node's path joined with `relative_path`.
  [[noreturn]] void FailAt(const std::string& relative_path, const std::string& message) const;

 private:
  friend class ConfigDocument;

  ConfigNode(std::shared_ptr<const detail::DocumentState> doc, std::shared_ptr<detail::Value> value,
             std::string key_path);

  /// Throws unless this is a map / a sequence; `expected` says what the caller wanted.
  void RequireMap() const;
  void RequireSequence(const std::string& expected) const;
  /// The plain scalar text, or a ConfigError "expected <expected>, got ...".
  const std::string& PlainScalar(const std::string& expected) const;
  double ParseFinite(const std::string& expected) const;
  std::int64_t ParseInt(const std::string& expected) const;
  /// Records `key` as asked for; returns its entry index or -1.
  int LookUp(std::string_view key) const;
  ConfigNode ChildAt(int entry_index) const;

  std::shared_ptr<const detail::DocumentState> doc_;
  std::shared_ptr<detail::Value> value_;
  std::string key_path_;
};

}  // namespace rotorguard::io
