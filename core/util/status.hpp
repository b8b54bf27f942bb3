#pragma once
// The outcome of an operation that can fail on bad input (a file, a field, a packet): a success flag plus a message
// that names the file, line or offset and the field. Library code returns it (or carries it in a result struct)
// and never exits; ignoring one is a compile warning ([[nodiscard]]).
#include <string>
#include <utility>

namespace rotolidar {

struct [[nodiscard]] Status {
  bool ok = true;
  std::string message;
  static Status Ok() { return {}; }
  static Status Error(std::string msg) { return {false, std::move(msg)}; }
  explicit operator bool() const { return ok; }
};

}  // namespace rotolidar
