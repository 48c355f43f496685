#pragma once
/// Numeric CSV tables (log.csv): a header of column names, then rows of numbers. The reader is
/// strict because a report or a replay built from a damaged log would mislead: a row with the
/// wrong number of fields, a field that is not a finite number or a last row cut short is a
/// CorruptFileError with the byte offset of the fault.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace rotorguard::io {

struct NumericTable {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> values;  ///< values[c][r]: column-major

  std::size_t rows() const { return values.empty() ? 0 : values.front().size(); }
  /// Index of a column, or -1.
  int Find(std::string_view name) const;
  bool Has(std::string_view name) const { return Find(name) >= 0; }
  /// The column's values; throws std::out_of_range naming the column when there is none.
  const std::vector<double>& Column(std::string_view name) const;
};

/// Parses `text` (the content of `path`, named in errors). Every row must end with a newline and
/// hold one finite number per column. Throws CorruptFileError (config_node.h).
NumericTable ParseNumericCsv(std::string_view text, const std::string& path);

/// Reads and parses a file: InputFileError when it cannot be read, CorruptFileError when damaged.
NumericTable ReadNumericCsv(const std::string& path);

}  // namespace rotorguard::io
