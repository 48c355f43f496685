#include <fmt/format.h>
#include <yaml-cpp/anchor.h>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/emitterstyle.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/exceptions.h>
#include <yaml-cpp/mark.h>
#include <yaml-cpp/parser.h>

#include <algorithm>
#include <sstream>
#include <string_view>
#include <utility>

#include "config_tree.h"
#include "rotorguard/core/error.h"

// ConfigDocument: parsing a file into our own tree, and overrides.
namespace rotorguard::io {

using namespace internal;  // NOLINT: the layer's own helpers

namespace {

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

/// The offset of the first byte of `text` that is not part of well-formed UTF-8 (RFC 3629: no
/// overlong forms, no surrogates, nothing above U+10FFFF), or npos.
std::size_t FirstInvalidUtf8(std::string_view text) {
  const auto byte = [&text](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  std::size_t i = 0;
  while (i < text.size()) {
    const unsigned char c = byte(i);
    if (c < 0x80) {
      ++i;
      continue;
    }
    int length = 0;
    unsigned char lo = 0x80, hi = 0xBF;  // the range of the second byte
    if (c >= 0xC2 && c <= 0xDF) {
      length = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
      length = 3;
      if (c == 0xE0) lo = 0xA0;  // overlong
      if (c == 0xED) hi = 0x9F;  // surrogates
    } else if (c >= 0xF0 && c <= 0xF4) {
      length = 4;
      if (c == 0xF0) lo = 0x90;  // overlong
      if (c == 0xF4) hi = 0x8F;  // above U+10FFFF
    } else {
      return i;
    }
    if (i + length > text.size() || byte(i + 1) < lo || byte(i + 1) > hi) return i;
    for (int k = 2; k < length; ++k) {
      if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return i;
    }
    i += length;
  }
  return std::string_view::npos;
}

/// Parses exactly one YAML document; nullptr when the text holds none (empty or only comments).
/// Every yaml-cpp exception becomes a ConfigError with yaml-cpp's (1-based) location.
ValuePtr ParseSingleDocument(const std::string& text, const std::string& file, bool from_override,
                             const std::string& base_path) {
  const ParseContext context(file, from_override, base_path);
  // YAML is UTF-8 here; a stray byte would pass the parser and break every JSON output that names
  // the value (found by fuzzing: a scenario name with byte 0x84 stopped `run` at summary.json).
  if (const std::size_t bad = FirstInvalidUtf8(text); bad != std::string_view::npos) {
    const std::size_t newline = text.rfind('\n', bad);  // the byte itself is not one
    const int line =
        1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(bad), '\n'));
    const int column = 1 + static_cast<int>(newline == std::string::npos ? bad : bad - newline - 1);
    throw ConfigError(
        file, from_override ? 0 : line, from_override ? 0 : column, base_path,
        fmt::format("byte 0x{:02X} is not valid UTF-8; expected UTF-8 text", static_cast<unsigned char>(text[bad])));
  }
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

}  // namespace

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
      auto it = current.index.find(segment);
      if (it == current.index.end()) {
        // A key the file does not write: added (and the rest of the path as maps), so that any
        // declared key can be set; the schema rejects one that is not declared, naming --set and
        // the keys it expects. Nothing can fail after this point: the override applies whole.
        auto added = std::make_shared<Value>();
        added->kind = Kind::kMap;
        added->from_override = true;
        current.index.emplace(segment, current.entries.size());
        current.entries.push_back(MapEntry{segment, 0, 0, std::move(added), /*from_override=*/true});
        it = current.index.find(segment);
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

}  // namespace rotorguard::io
