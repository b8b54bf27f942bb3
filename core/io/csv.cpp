#include "core/io/csv.hpp"
#include "core/util/log.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace rotolidar {
namespace {

std::vector<std::string> SplitComma(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

std::string Trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return s.substr(i);
}

}  // namespace

Status CsvReader::Open(const std::string& path, const std::vector<std::string>& expected_columns) {
  path_ = path;
  columns_ = expected_columns;
  in_.open(path);
  if (!in_) return status_ = Status::Error(path + ": cannot open file");
  std::string header;
  do {
    if (!std::getline(in_, header)) return status_ = Status::Error(path + ": empty file, expected a header line");
    ++line_;
  } while (!header.empty() && header[0] == '#');
  std::vector<std::string> cells = SplitComma(Trim(header));
  for (auto& c : cells) c = Trim(c);
  if (cells != expected_columns) {
    std::string want;
    for (const auto& c : expected_columns) want += (want.empty() ? "" : ",") + c;
    return status_ = Status::Error(path + ":" + std::to_string(line_) + ": header must be '" + want + "', got '" +
                                   Trim(header) + "'");
  }
  return status_ = Status::Ok();
}

bool CsvReader::Next(std::vector<double>* values) {
  if (!status_) return false;
  std::string line;
  while (std::getline(in_, line)) {
    ++line_;
    line = Trim(line);
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> cells = SplitComma(line);
    const std::string where = path_ + ":" + std::to_string(line_) + ": ";
    if (cells.size() != columns_.size()) {
      status_ = Status::Error(where + "expected " + std::to_string(columns_.size()) + " columns, got " +
                              std::to_string(cells.size()));
      return false;
    }
    values->resize(cells.size());
    for (size_t i = 0; i < cells.size(); ++i) {
      const std::string cell = Trim(cells[i]);
      char* end = nullptr;
      errno = 0;
      (*values)[i] = std::strtod(cell.c_str(), &end);
      if (cell.empty() || *end != '\0' || errno == ERANGE || !std::isfinite((*values)[i])) {
        status_ = Status::Error(where + "column " + std::to_string(i + 1) + " ('" + columns_[i] +
                                "'): not a finite number: '" + cell + "'");
        return false;
      }
    }
    return true;
  }
  return false;
}

Status CsvWriter::Open(const std::string& path, const std::vector<std::string>& columns) {
  path_ = path;
  num_columns_ = columns.size();
  out_.open(path);
  if (!out_) return Status::Error(path + ": cannot open for writing");
  for (size_t i = 0; i < columns.size(); ++i) out_ << (i ? "," : "") << columns[i];
  out_ << "\n";
  return Status::Ok();
}

void CsvWriter::Row(const std::vector<double>& values, bool first_is_time) {
  ROTOLIDAR_CHECK(values.size() == num_columns_, path_ << ": row has " << values.size() << " values");
  char buf[64];
  for (size_t i = 0; i < values.size(); ++i) {
    if (i == 0 && first_is_time)
      std::snprintf(buf, sizeof(buf), "%.9f", values[i]);
    else
      std::snprintf(buf, sizeof(buf), "%.17g", values[i]);
    out_ << (i ? "," : "") << buf;
  }
  out_ << "\n";
}

Status CsvWriter::Close() {
  out_.close();
  return out_ ? Status::Ok() : Status::Error(path_ + ": write failed");
}

}  // namespace rotolidar
