#include "rotorguard/io/csv.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "rotorguard/io/config_node.h"

namespace rotorguard::io {

int NumericTable::Find(std::string_view name) const {
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (columns[i] == name) return static_cast<int>(i);
  }
  return -1;
}

const std::vector<double>& NumericTable::Column(std::string_view name) const {
  const int i = Find(name);
  if (i < 0) throw std::out_of_range(fmt::format("the table has no column '{}'", name));
  return values[static_cast<std::size_t>(i)];
}

NumericTable ParseNumericCsv(std::string_view text, const std::string& path) {
  NumericTable table;
  const std::size_t header_end = text.find('\n');
  if (text.empty()) throw CorruptFileError(path, 0, "the file is empty; expected a header line of column names");
  if (header_end == std::string_view::npos) {
    throw CorruptFileError(path, text.size(), "the header line has no newline (truncated file?)");
  }
  std::size_t start = 0;
  for (std::size_t i = 0; i <= header_end; ++i) {
    if (i == header_end || text[i] == ',') {
      if (i == start) throw CorruptFileError(path, start, "empty column name in the header");
      table.columns.emplace_back(text.substr(start, i - start));
      start = i + 1;
    }
  }
  const std::size_t n = table.columns.size();
  table.values.resize(n);
  std::size_t pos = header_end + 1;
  int line = 2;
  while (pos < text.size()) {
    for (std::size_t c = 0; c < n; ++c) {
      double v = 0.0;
      const char* first = text.data() + pos;
      const char* last = text.data() + text.size();
      const auto [ptr, ec] = std::from_chars(first, last, v);
      if (ec != std::errc() || !std::isfinite(v)) {
        throw CorruptFileError(path, pos,
                               fmt::format("line {}, column '{}': expected a finite number", line, table.columns[c]));
      }
      pos = static_cast<std::size_t>(ptr - text.data());
      const char expected = c + 1 < n ? ',' : '\n';
      if (pos >= text.size()) {
        throw CorruptFileError(path, pos,
                               fmt::format("line {} ends after {} of {} fields (truncated file?)", line, c + 1, n));
      }
      if (text[pos] != expected) {
        throw CorruptFileError(
            path, pos,
            fmt::format("line {}, column '{}': expected '{}' after the value, found '{}' ({} fields per line)", line,
                        table.columns[c], expected == ',' ? "," : "\\n", text[pos] == '\n' ? "\\n" : std::string(1, text[pos]), n));
      }
      table.values[c].push_back(v);
      ++pos;
    }
    ++line;
  }
  return table;
}

NumericTable ReadNumericCsv(const std::string& path) { return ParseNumericCsv(ReadInputFile(path), path); }

}  // namespace rotorguard::io
