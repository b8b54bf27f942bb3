#pragma once
// Minimal logging and an always-on check for programmer errors (not assert, which vanishes in Release).
// Library code never exits: expected failures are returned as values (result structs, Status in status.hpp).
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/util/status.hpp"

namespace rotolidar {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3, kQuiet = 4 };

void SetLogLevel(LogLevel level);
LogLevel GetLogLevel();
void LogMessage(LogLevel level, const std::string& message);  ///< thread-safe, to stderr

/// Thrown only by ROTOLIDAR_CHECK: a broken invariant inside the library (a bug), never bad input.
struct InternalError : std::logic_error {
  using std::logic_error::logic_error;
};

}  // namespace rotolidar

#define ROTOLIDAR_LOG(level, expr)                                        \
  do {                                                                    \
    if (static_cast<int>(level) >= static_cast<int>(::rotolidar::GetLogLevel())) { \
      std::ostringstream rl_os_;                                          \
      rl_os_ << expr;                                                     \
      ::rotolidar::LogMessage(level, rl_os_.str());                       \
    }                                                                     \
  } while (0)
#define LOG_INFO(expr) ROTOLIDAR_LOG(::rotolidar::LogLevel::kInfo, expr)
#define LOG_WARN(expr) ROTOLIDAR_LOG(::rotolidar::LogLevel::kWarn, expr)
#define LOG_ERROR(expr) ROTOLIDAR_LOG(::rotolidar::LogLevel::kError, expr)
#define LOG_DEBUG(expr) ROTOLIDAR_LOG(::rotolidar::LogLevel::kDebug, expr)

#define ROTOLIDAR_CHECK(cond, msg)                                                              \
  do {                                                                                          \
    if (!(cond)) {                                                                              \
      std::ostringstream rl_os_;                                                                \
      rl_os_ << __FILE__ << ":" << __LINE__ << ": check failed: " #cond ": " << msg;            \
      throw ::rotolidar::InternalError(rl_os_.str());                                           \
    }                                                                                           \
  } while (0)
