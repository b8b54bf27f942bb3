#pragma once
// A helper for `bool Validate(std::string* error) const` checks of config structs.
#include <string>

namespace rotolidar {

/// Stores `message` in *error (when error is not null) and returns false, so that a check reads
/// `if (bad) return FailValidation(error, "field: why");`.
inline bool FailValidation(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

}  // namespace rotolidar
