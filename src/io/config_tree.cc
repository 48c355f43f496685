#include "config_tree.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <system_error>
#include <utility>

#include <fmt/format.h>

namespace rotorguard::io {
namespace internal {

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

}  // namespace internal

using namespace internal;  // NOLINT: this file implements them

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
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(status)) throw InputFileError(path, "is a directory");
  // A device or a pipe (`vehicle: /dev/zero`) could be read forever.
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
    throw InputFileError(path, "is not a regular file");
  }
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputFileError(path, ReasonFromErrno(errno));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputFileError(path, ReasonFromErrno(errno));
  return text;
}

}  // namespace rotorguard::io
