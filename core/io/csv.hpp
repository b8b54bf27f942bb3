#pragma once
// Strict numeric CSV: a header line naming the columns, then rows of numbers. Errors name file:line:column.
#include <fstream>
#include <string>
#include <vector>

#include "core/util/status.hpp"

namespace rotolidar {

/// Reads a numeric CSV row by row. The header must equal `expected_columns` exactly (order matters).
class CsvReader {
 public:
  /// Opens `path` and checks its header; a '#'-prefixed line before the header is skipped.
  Status Open(const std::string& path, const std::vector<std::string>& expected_columns);
  /// Reads the next row into *values (size = number of columns). Returns false at the end of the file or on an
  /// error; then status() tells which (ok at a clean end).
  bool Next(std::vector<double>* values);
  const Status& status() const { return status_; }
  int line() const { return line_; }

 private:
  std::ifstream in_;
  std::string path_;
  std::vector<std::string> columns_;
  int line_ = 0;
  Status status_;
};

/// Writes a CSV with a header; numbers at full precision (17 significant digits, times with 9 decimals).
class CsvWriter {
 public:
  Status Open(const std::string& path, const std::vector<std::string>& columns);
  /// Writes one row; the first value is written as a time with fixed 9 decimals when `first_is_time`.
  void Row(const std::vector<double>& values, bool first_is_time = true);
  Status Close();

 private:
  std::ofstream out_;
  std::string path_;
  size_t num_columns_ = 0;
};

}  // namespace rotolidar
