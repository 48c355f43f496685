#include "rotorguard/io/config_node.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <system_error>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <fmt/format.h>
#include <yaml-cpp/anchor.h>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/emitterstyle.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/exceptions.h>
#include <yaml-cpp/mark.h>
#include <yaml-cpp/parser.h>

#include "rotorguard/core/error.h"

namespace rotorguard::io {
namespace detail {

struct Value;

/// One key of a map with where the key itself was written (unknown-key errors point at the key).
struct MapEntry {
  std::string key;
  int key_line = 0;
  int key_column = 0;
  std::shared_ptr<Value> value;
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

namespace {

using detail::MapEntry;
using detail::Value;
using Kind = detail::Value::Kind;
using ValuePtr = std::shared_ptr<Value>;

/// Aliases are expanded into copies; this bounds the copies so a "billion laughs" document is an
/// error instead of exhausting memory.
constexpr std::size_t kMaxAliasCopiedNodes = 100000;

std::string ComposeWhat(const std::string& file, int line, int column, const std::string& key_path,
                        const std::string& message) {
  std::string out = file;
  if (line > 0) {
    out += fmt::format(":{}", line);
    if (column > 0) out += fmt::format(":{}", column);
  }
  out += ": ";
  if (!key_path.empty()) out += key_path + ": ";
  out += message;
  return out;
}

std::string JoinPath(std::string_view parent, std::string_view child) {
  if (parent.empty()) return std::string(child);
  return fmt::format("{}.{}", parent, child);
}

std::string JoinList(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& item : items) {
    if (!out.empty()) out += ", ";
    out += item;
  }
  return out;
}

std::vector<std::string> SplitPath(std::string_view path) {
  std::vector<std::string> segments;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    segments.emplace_back(path.substr(start, dot == std::string_view::npos ? dot : dot - start));
    if (dot == std::string_view::npos) break;
    start = dot + 1;
  }
  return segments;
}

/// A sequence index segment: decimal digits only.
std::optional<std::size_t> ParseIndex(std::string_view segment) {
  std::size_t index = 0;
  const char* end = segment.data() + segment.size();
  if (segment.empty()) return std::nullopt;
  const auto [ptr, ec] = std::from_chars(segment.data(), end, index);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return index;
}

/// The text of a value for a message: quoted, control characters escaped, long text shortened.
std::string Quote(std::string_view text) {
  constexpr std::size_t kMaxShown = 60;
  std::string out = "'";
  for (std::size_t i = 0; i < text.size() && i < kMaxShown; ++i) {
    const char c = text[i];
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\r') {
      out += "\\r";
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\x{:02x}", static_cast<unsigned>(static_cast<unsigned char>(c)));
    } else {
      out += c;
    }
  }
  if (text.size() > kMaxShown) out += "...";
  out += "'";
  return out;
}

std::string ShortTag(const std::string& tag) {
  constexpr std::string_view kCorePrefix = "tag:yaml.org,2002:";
  if (tag.compare(0, kCorePrefix.size(), kCorePrefix) == 0) {
    return "!!" + tag.substr(kCorePrefix.size());
  }
  return tag;
}

/// What a value is, for "expected X, got Y" messages.
std::string Describe(const Value& value) {
  switch (value.kind) {
    case Kind::kNull:
      return "null (an empty value)";
    case Kind::kMap:
      return "a map";
    case Kind::kSequence:
      return "a sequence";
    case Kind::kScalar:
      break;
  }
  if (value.tag == "?") return "the scalar " + Quote(value.scalar);
  if (value.tag == "!") return "the quoted string " + Quote(value.scalar);
  return fmt::format("the scalar {} tagged '{}'", Quote(value.scalar), ShortTag(value.tag));
}

const std::string& SourceFile(const Value& value, const std::string& file) {
  static const std::string kOverride(kOverrideSource);
  return value.from_override ? kOverride : file;
}

[[noreturn]] void ThrowAt(const Value& value, const std::string& file, const std::string& key_path,
                          const std::string& message) {
  throw ConfigError(SourceFile(value, file), value.line, value.column, key_path, message);
}

// ---- Numbers. Parsed by hand rather than with yaml-cpp's as<double>: that accepts ".nan" and
// ".inf", rejects "nan"/"inf"/"1e999" as a generic bad conversion (so "not finite" could not be
// told from "not a number"), and goes through a locale-dependent stream.

enum class NumberStatus { kOk, kNotANumber, kNotFinite, kOverflow };

struct ParsedNumber {
  NumberStatus status = NumberStatus::kNotANumber;
  double value = 0.0;
};

std::size_t CountDigits(std::string_view text, std::size_t from) {
  std::size_t n = 0;
  while (from + n < text.size() && std::isdigit(static_cast<unsigned char>(text[from + n]))) ++n;
  return n;
}

/// YAML 1.2 core-schema float syntax: [-+]? ( digits [. digits*] | . digits ) ([eE] [-+]? digits)?
/// plus the non-finite spellings, which are recognised (and rejected by callers) case-insensitively
/// with or without the leading dot so the message says "not finite" rather than "not a number".
ParsedNumber ParseYamlFloat(std::string_view text) {
  ParsedNumber result;
  if (text.empty()) return result;
  bool negative = false;
  std::string_view body = text;
  if (body[0] == '+' || body[0] == '-') {
    negative = body[0] == '-';
    body.remove_prefix(1);
  }
  std::string lower(body);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* word : {"nan", ".nan", "inf", ".inf", "infinity", ".infinity"}) {
    if (lower == word) {
      result.status = NumberStatus::kNotFinite;
      return result;
    }
  }

  const std::size_t int_digits = CountDigits(body, 0);
  std::size_t pos = int_digits;
  std::size_t frac_digits = 0;
  if (pos < body.size() && body[pos] == '.') {
    frac_digits = CountDigits(body, pos + 1);
    pos += 1 + frac_digits;
  }
  if (int_digits + frac_digits == 0) return result;
  std::int64_t exponent = 0;
  if (pos < body.size() && (body[pos] == 'e' || body[pos] == 'E')) {
    ++pos;
    bool negative_exponent = false;
    if (pos < body.size() && (body[pos] == '+' || body[pos] == '-')) {
      negative_exponent = body[pos] == '-';
      ++pos;
    }
    const std::size_t exp_digits = CountDigits(body, pos);
    if (exp_digits == 0) return result;
    for (std::size_t i = 0; i < exp_digits; ++i) {
      // Saturate: only the sign and rough size matter once it is out of double range.
      exponent = std::min<std::int64_t>(exponent * 10 + (body[pos + i] - '0'), 1'000'000'000);
    }
    if (negative_exponent) exponent = -exponent;
    pos += exp_digits;
  }
  if (pos != body.size()) return result;

  double value = 0.0;
  const char* end = body.data() + body.size();
  const auto [ptr, ec] = std::from_chars(body.data(), end, value);
  if (ec == std::errc() && ptr == end) {
    result.status = NumberStatus::kOk;
    result.value = negative ? -value : value;
    return result;
  }
  if (ec != std::errc::result_out_of_range) return result;
  // Out of range is either overflow (rejected: it would be inf) or underflow (the number is
  // finite, just below the smallest double: it reads as zero). Decide by the decimal magnitude.
  std::int64_t magnitude = 0;
  const std::string_view int_part = body.substr(0, int_digits);
  const std::size_t first_int = int_part.find_first_not_of('0');
  if (first_int != std::string_view::npos) {
    magnitude = static_cast<std::int64_t>(int_digits - first_int) - 1;
  } else {
    const std::string_view frac_part = body.substr(int_digits + 1, frac_digits);
    const std::size_t first_frac = frac_part.find_first_not_of('0');
    magnitude = -static_cast<std::int64_t>(first_frac == std::string_view::npos ? 0 : first_frac) - 1;
  }
  if (magnitude + exponent > 0) {
    result.status = NumberStatus::kOverflow;
  } else {
    result.status = NumberStatus::kOk;
    result.value = negative ? -0.0 : 0.0;
  }
  return result;
}

struct ParsedInteger {
  bool ok = false;
  bool overflow = false;
  bool negative = false;
  std::uint64_t magnitude = 0;
};

/// [-+]? ( decimal digits | 0x hex digits ).
ParsedInteger ParseYamlInteger(std::string_view text) {
  ParsedInteger result;
  std::string_view body = text;
  if (!body.empty() && (body[0] == '+' || body[0] == '-')) {
    result.negative = body[0] == '-';
    body.remove_prefix(1);
  }
  int base = 10;
  if (body.size() > 2 && body[0] == '0' && (body[1] == 'x' || body[1] == 'X')) {
    base = 16;
    body.remove_prefix(2);
  }
  if (body.empty()) return result;
  for (const char c : body) {
    const bool digit = base == 16 ? std::isxdigit(static_cast<unsigned char>(c)) != 0
                                  : std::isdigit(static_cast<unsigned char>(c)) != 0;
    if (!digit) return result;
  }
  const char* end = body.data() + body.size();
  const auto [ptr, ec] = std::from_chars(body.data(), end, result.magnitude, base);
  if (ec == std::errc::result_out_of_range) {
    result.overflow = true;
    return result;
  }
  result.ok = ec == std::errc() && ptr == end;
  return result;
}

// ---- Building the tree from parser events.

class TreeBuilder final : public YAML::EventHandler {
 public:
  /// `from_override` values carry no line and report file "--set"; `base_path` is the key path of
  /// the document root (the override's path), so nested errors name the full path.
  TreeBuilder(std::string file, bool from_override, std::string base_path)
      : file_(std::move(file)), from_override_(from_override), base_path_(std::move(base_path)) {}

  const ValuePtr& root() const { return root_; }
  const YAML::Mark& document_mark() const { return document_mark_; }

  void OnDocumentStart(const YAML::Mark& mark) override { document_mark_ = mark; }
  void OnDocumentEnd() override {}

  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    Finish(NewValue(Kind::kNull, mark), anchor);
  }

  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const auto it = anchors_.find(anchor);
    if (it == anchors_.end()) {
      // yaml-cpp itself rejects undefined aliases, so this one names an anchor still open.
      ThrowAtMark(mark, NextChildPath(),
                  "this alias refers to a node that contains it; recursive aliases are not "
                  "supported");
    }
    ValuePtr copy = DeepCopy(*it->second, mark);
    SetLocation(*copy, mark);
    Finish(copy, YAML::NullAnchor);
  }

  void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                const std::string& value) override {
    ValuePtr node = NewValue(Kind::kScalar, mark);
    node->scalar = value;
    node->tag = tag;
    Finish(node, anchor);
  }

  void OnSequenceStart(const YAML::Mark& mark, const std::string& /*tag*/, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value /*style*/) override {
    Open(NewValue(Kind::kSequence, mark), anchor, mark);
  }
  void OnSequenceEnd() override { Close(); }

  void OnMapStart(const YAML::Mark& mark, const std::string& /*tag*/, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value /*style*/) override {
    Open(NewValue(Kind::kMap, mark), anchor, mark);
  }
  void OnMapEnd() override { Close(); }

 private:
  struct Frame {
    ValuePtr value;
    std::string path;
    YAML::anchor_t anchor = YAML::NullAnchor;
    /// Maps: the last entry's key has been read and its value not yet.
    bool awaiting_value = false;
  };

  ValuePtr NewValue(Kind kind, const YAML::Mark& mark) const {
    auto value = std::make_shared<Value>();
    value->kind = kind;
    value->from_override = from_override_;
    SetLocation(*value, mark);
    return value;
  }

  void SetLocation(Value& value, const YAML::Mark& mark) const {
    if (from_override_ || mark.is_null()) return;
    value.line = mark.line + 1;
    value.column = mark.column + 1;
  }

  [[noreturn]] void ThrowAtMark(const YAML::Mark& mark, const std::string& path,
                                const std::string& message) const {
    const bool located = !from_override_ && !mark.is_null();
    throw ConfigError(from_override_ ? std::string(kOverrideSource) : file_,
                      located ? mark.line + 1 : 0, located ? mark.column + 1 : 0, path, message);
  }

  /// The key path the next completed node will get.
  std::string NextChildPath() const {
    if (frames_.empty()) return base_path_;
    const Frame& top = frames_.back();
    if (top.value->kind == Kind::kSequence) {
      return JoinPath(top.path, std::to_string(top.value->items.size()));
    }
    if (top.awaiting_value) return JoinPath(top.path, top.value->entries.back().key);
    return top.path;
  }

  void Open(ValuePtr value, YAML::anchor_t anchor, const YAML::Mark& mark) {
    if (!frames_.empty() && frames_.back().value->kind == Kind::kMap &&
        !frames_.back().awaiting_value) {
      ThrowAtMark(mark, frames_.back().path,
                  fmt::format("a map key must be a name, not {}", Describe(*value)));
    }
    std::string path = NextChildPath();
    frames_.push_back(Frame{std::move(value), std::move(path), anchor, false});
  }

  void Close() {
    Frame frame = std::move(frames_.back());
    frames_.pop_back();
    Finish(frame.value, frame.anchor);
  }

  void Finish(const ValuePtr& value, YAML::anchor_t anchor) {
    if (anchor != YAML::NullAnchor) anchors_[anchor] = value;
    if (frames_.empty()) {
      root_ = value;
      return;
    }
    Frame& top = frames_.back();
    Value& parent = *top.value;
    if (parent.kind == Kind::kSequence) {
      parent.items.push_back(value);
      return;
    }
    if (top.awaiting_value) {
      MapEntry& entry = parent.entries.back();
      // yaml-cpp marks an empty value at the next token, possibly lines below; the key's line is
      // where the user looks.
      if (value->kind == Kind::kNull && value->line != entry.key_line) {
        value->line = entry.key_line;
        value->column = entry.key_column;
      }
      entry.value = value;
      top.awaiting_value = false;
      return;
    }
    AddKey(top, *value);
  }

  void AddKey(Frame& top, const Value& key) {
    Value& map = *top.value;
    if (key.kind != Kind::kScalar || key.scalar.empty()) {
      throw ConfigError(SourceFile(key, file_), key.line, key.column, top.path,
                        fmt::format("a map key must be a name, not {}", Describe(key)));
    }
    const auto [it, inserted] = map.index.emplace(key.scalar, map.entries.size());
    if (!inserted) {
      const MapEntry& first = map.entries[it->second];
      const std::string message =
          from_override_ ? fmt::format("duplicate key '{}'", key.scalar)
                         : fmt::format("duplicate key '{}' (first at line {})", key.scalar,
                                       first.key_line);
      throw ConfigError(SourceFile(key, file_), key.line, key.column,
                        JoinPath(top.path, key.scalar), message);
    }
    map.entries.push_back(MapEntry{key.scalar, key.line, key.column, nullptr});
    top.awaiting_value = true;
  }

  /// A private copy of an anchored node: overrides and used-key bookkeeping must not leak from
  /// one use of an anchor to another.
  ValuePtr DeepCopy(const Value& source, const YAML::Mark& alias_mark) {
    if (++copied_nodes_ > kMaxAliasCopiedNodes) {
      ThrowAtMark(alias_mark, NextChildPath(),
                  fmt::format("aliases expand to more than {} nodes; expected a smaller document",
                              kMaxAliasCopiedNodes));
    }
    auto copy = std::make_shared<Value>(source);
    for (MapEntry& entry : copy->entries) entry.value = DeepCopy(*entry.value, alias_mark);
    for (ValuePtr& item : copy->items) item = DeepCopy(*item, alias_mark);
    return copy;
  }

  std::string file_;
  bool from_override_;
  std::string base_path_;
  ValuePtr root_;
  YAML::Mark document_mark_;
  std::vector<Frame> frames_;
  std::unordered_map<YAML::anchor_t, ValuePtr> anchors_;
  std::size_t copied_nodes_ = 0;
};

/// Ignores every event but document starts: used to look for a syntax error only.
class DocumentStarts final : public YAML::EventHandler {
 public:
  const YAML::Mark& last() const { return last_; }

  void OnDocumentStart(const YAML::Mark& mark) override { last_ = mark; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& /*mark*/, YAML::anchor_t /*anchor*/) override {}
  void OnAlias(const YAML::Mark& /*mark*/, YAML::anchor_t /*anchor*/) override {}
  void OnScalar(const YAML::Mark& /*mark*/, const std::string& /*tag*/, YAML::anchor_t /*anchor*/,
                const std::string& /*value*/) override {}
  void OnSequenceStart(const YAML::Mark& /*mark*/, const std::string& /*tag*/,
                       YAML::anchor_t /*anchor*/, YAML::EmitterStyle::value /*style*/) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& /*mark*/, const std::string& /*tag*/,
                  YAML::anchor_t /*anchor*/, YAML::EmitterStyle::value /*style*/) override {}
  void OnMapEnd() override {}

 private:
  YAML::Mark last_;
};

/// Turns yaml-cpp exceptions into ConfigErrors with yaml-cpp's location made 1-based.
class ParseContext {
 public:
  ParseContext(const std::string& file, bool from_override, const std::string& base_path)
      : source_(from_override ? std::string(kOverrideSource) : file),
        from_override_(from_override),
        base_path_(base_path) {}

  ConfigError At(const YAML::Mark& mark, const std::string& message) const {
    const bool located = !from_override_ && !mark.is_null();
    return ConfigError(source_, located ? mark.line + 1 : 0, located ? mark.column + 1 : 0,
                       base_path_, message);
  }

  ConfigError FromYaml(const YAML::Exception& e) const {
    if (const auto* deep = dynamic_cast<const YAML::DeepRecursion*>(&e)) {
      // yaml-cpp's own message for this one is "bad file".
      return At(e.mark, fmt::format("malformed YAML: nesting is deeper than {} levels",
                                    deep->depth()));
    }
    return At(e.mark, fmt::format("malformed YAML: {}", e.msg));
  }

  /// The first syntax error anywhere in `text`, if any.
  std::optional<ConfigError> FindSyntaxError(const std::string& text) const {
    std::istringstream in(text);
    try {
      YAML::Parser parser(in);
      DocumentStarts starts;
      int previous_start = -1;
      // Every real document consumes input, so this bounds the loop even if the check below
      // missed a way for yaml-cpp to stall.
      for (std::size_t documents = 0; documents <= text.size() + 1; ++documents) {
        if (!parser.HandleNextDocument(starts)) return std::nullopt;
        // yaml-cpp 0.7 never consumes a stray ',' outside a flow collection: it reports an
        // endless run of empty documents starting there. Call that a syntax error.
        if (starts.last().pos == previous_start) return Stalled(text, starts.last());
        previous_start = starts.last().pos;
      }
      return Stalled(text, starts.last());
    } catch (const YAML::Exception& e) {
      return FromYaml(e);
    }
  }

 private:
  ConfigError Stalled(const std::string& text, const YAML::Mark& mark) const {
    const auto pos = static_cast<std::size_t>(mark.pos);
    const bool printable = mark.pos >= 0 && pos < text.size() &&
                           std::isprint(static_cast<unsigned char>(text[pos])) != 0;
    return At(mark, printable ? fmt::format("malformed YAML: unexpected {}",
                                            Quote(std::string_view(text).substr(pos, 1)))
                              : std::string("malformed YAML: unexpected content"));
  }

  std::string source_;
  bool from_override_;
  std::string base_path_;
};

/// Parses exactly one YAML document; nullptr when the text holds none (empty or only comments).
/// Every yaml-cpp exception becomes a ConfigError with yaml-cpp's (1-based) location.
ValuePtr ParseSingleDocument(const std::string& text, const std::string& file, bool from_override,
                             const std::string& base_path) {
  const ParseContext context(file, from_override, base_path);
  std::istringstream in(text);
  try {
    YAML::Parser parser(in);
    TreeBuilder builder(file, from_override, base_path);
    if (!parser.HandleNextDocument(builder)) return nullptr;
    TreeBuilder extra(file, from_override, base_path);
    if (parser.HandleNextDocument(extra)) {
      throw context.At(extra.document_mark(),
                       "a second YAML document starts here; expected exactly one document");
    }
    return builder.root();
  } catch (const YAML::Exception& e) {
    throw context.FromYaml(e);
  } catch (const ConfigError&) {
    // yaml-cpp emits events up to the point of a syntax error, and broken syntax often first
    // looks like a bad key ("[1, 2" yields a map inside the sequence). The syntax error is the
    // real cause, so it wins; otherwise our own error stands.
    if (std::optional<ConfigError> syntax = context.FindSyntaxError(text)) throw *syntax;
    throw;
  }
}

std::string ReasonFromErrno(int error) {
  switch (error) {
    case ENOENT:
      return "no such file";
    case EACCES:
    case EPERM:
      return "permission denied";
    case EISDIR:
      return "is a directory";
    case 0:
      return "cannot open";
    default:
      return std::generic_category().message(error);
  }
}

}  // namespace

// ---- Errors.

ConfigError::ConfigError(std::string file, int line, int column, std::string key_path,
                         std::string message)
    : std::runtime_error(ComposeWhat(file, line, column, key_path, message)),
      file_(std::move(file)),
      line_(line > 0 ? line : 0),
      column_(line > 0 && column > 0 ? column : 0),
      key_path_(std::move(key_path)),
      message_(std::move(message)) {}

InputFileError::InputFileError(std::string path, std::string reason)
    : std::runtime_error(fmt::format("{}: cannot read input file: {}", path, reason)),
      path_(std::move(path)),
      reason_(std::move(reason)) {}

CorruptFileError::CorruptFileError(std::string path, std::uint64_t byte_offset, std::string message)
    : std::runtime_error(fmt::format("{}: corrupt at byte {}: {}", path, byte_offset, message)),
      path_(std::move(path)),
      byte_offset_(byte_offset),
      message_(std::move(message)) {}

std::string ReadInputFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputFileError(path, "is a directory");
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputFileError(path, ReasonFromErrno(errno));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputFileError(path, ReasonFromErrno(errno));
  return text;
}

// ---- ConfigDocument.

ConfigDocument::ConfigDocument(std::shared_ptr<detail::DocumentState> state)
    : state_(std::move(state)) {}

ConfigDocument ConfigDocument::LoadFile(const std::string& path) {
  return LoadString(ReadInputFile(path), path);
}

ConfigDocument ConfigDocument::LoadString(const std::string& text, const std::string& name) {
  ValuePtr root = ParseSingleDocument(text, name, /*from_override=*/false, /*base_path=*/"");
  if (root == nullptr || root->kind == Kind::kNull) {
    throw ConfigError(name, 1, 0, "", "file is empty; expected a YAML map");
  }
  if (root->kind != Kind::kMap) {
    throw ConfigError(name, root->line, root->column, "",
                      fmt::format("the top level is {}; expected a YAML map", Describe(*root)));
  }
  auto state = std::make_shared<detail::DocumentState>();
  state->file = name;
  state->root = std::move(root);
  return ConfigDocument(std::move(state));
}

const std::string& ConfigDocument::file() const {
  RG_INVARIANT(state_ != nullptr, "use of a moved-from ConfigDocument");
  return state_->file;
}

void ConfigDocument::ApplyOverride(const std::string& key_path, const std::string& value_text) {
  RG_INVARIANT(state_ != nullptr, "use of a moved-from ConfigDocument");
  const std::string source(kOverrideSource);
  if (key_path.empty()) {
    throw ConfigError(source, 0, 0, "", "empty key path; expected KEY.PATH=VALUE");
  }
  const std::vector<std::string> segments = SplitPath(key_path);
  for (const std::string& segment : segments) {
    if (segment.empty()) {
      throw ConfigError(source, 0, 0, key_path,
                        "malformed key path (empty segment); expected dotted names such as "
                        "'sensors.imu.rate_hz'");
    }
  }
  // Parse first: a malformed value must not leave a half-applied override behind.
  ValuePtr value = ParseSingleDocument(value_text, source, /*from_override=*/true, key_path);
  if (value == nullptr) {
    value = std::make_shared<Value>();
    value->from_override = true;
  }

  ValuePtr* slot = &state_->root;
  std::string walked;
  for (const std::string& segment : segments) {
    Value& current = **slot;
    const std::string where =
        walked.empty() ? std::string("at the top level") : fmt::format("under '{}'", walked);
    if (current.kind == Kind::kMap) {
      const auto it = current.index.find(segment);
      if (it == current.index.end()) {
        std::vector<std::string> keys;
        for (const MapEntry& entry : current.entries) keys.push_back(entry.key);
        throw ConfigError(source, 0, 0, key_path,
                          fmt::format("no key '{}' {}; existing keys: {}", segment, where,
                                      keys.empty() ? std::string("(none)") : JoinList(keys)));
      }
      slot = &current.entries[it->second].value;
    } else if (current.kind == Kind::kSequence) {
      const std::optional<std::size_t> index = ParseIndex(segment);
      if (!index || *index >= current.items.size()) {
        const std::string existing =
            current.items.empty()
                ? std::string("the sequence is empty")
                : fmt::format("existing indices: 0 to {}", current.items.size() - 1);
        throw ConfigError(source, 0, 0, key_path,
                          fmt::format("no item '{}' in the sequence {}; {}", segment, where,
                                      existing));
      }
      slot = &current.items[*index];
    } else {
      throw ConfigError(source, 0, 0, key_path,
                        fmt::format("no key '{}' {}: that is {}, not a map or sequence", segment,
                                    where, Describe(current)));
    }
    walked = JoinPath(walked, segment);
  }
  *slot = std::move(value);
}

void ConfigDocument::ApplyOverrideAssignment(const std::string& assignment) {
  const std::size_t equals = assignment.find('=');
  if (equals == std::string::npos || equals == 0) {
    throw ConfigError(std::string(kOverrideSource), 0, 0, "",
                      fmt::format("{} is not an override; expected KEY.PATH=VALUE",
                                  Quote(assignment)));
  }
  ApplyOverride(assignment.substr(0, equals), assignment.substr(equals + 1));
}

ConfigNode ConfigDocument::root() const {
  RG_INVARIANT(state_ != nullptr, "use of a moved-from ConfigDocument");
  return ConfigNode(state_, state_->root, "");
}

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
    // The key itself was written in this map, so it shares the map's source.
    throw ConfigError(SourceFile(*value_, doc_->file), entry.key_line, entry.key_column,
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
