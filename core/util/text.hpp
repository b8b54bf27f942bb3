#pragma once
// Small text helpers shared by the file parsers.
#include <string>
#include <vector>

namespace rotolidar {

/// "path:line: ", the prefix of every parse error that names a line (lines count from 1).
inline std::string FileLinePrefix(const std::string& path, int line) {
  return path + ":" + std::to_string(line) + ": ";
}

/// `s` without leading and trailing spaces, tabs, CR and LF.
inline std::string TrimSpace(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

/// The whitespace-separated tokens of `line` (spaces, tabs, CR, LF, VT, FF), in order.
std::vector<std::string> SplitWhitespace(const std::string& line);

}  // namespace rotolidar
