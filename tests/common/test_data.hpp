#pragma once
// Where `realdata` tests find real sensor data: $ROTOLIDAR_DATA/<folder>. When the folder is absent the test skips
// with one line that names what is missing and how to provide it; under CI (environment CI=true) a missing
// folder is a failure instead, so a CI run can never pass by skipping. Use it at the top of a test body or in a
// fixture's SetUp (it returns from the enclosing void function on skip or failure):
//
//   ROTOLIDAR_REQUIRE_DATA(dir, "kitti00");   // std::string dir = "$ROTOLIDAR_DATA/kitti00"
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace rotolidar::testdata {

/// True when the environment says this is a CI run (CI=true or CI=1, as GitHub/GitLab and our .ci/run set it).
inline bool RunningUnderCi() {
  const char* ci = std::getenv("CI");
  if (ci == nullptr) return false;
  const std::string v(ci);
  return v == "true" || v == "1" || v == "TRUE" || v == "True";
}

/// Resolves $ROTOLIDAR_DATA/<folder> into *dir. Returns "" when it exists as a directory, else the reason
/// (variable unset, or the folder missing) in one line.
inline std::string FindDataFolder(const std::string& folder, std::string* dir) {
  const char* root = std::getenv("ROTOLIDAR_DATA");
  if (root == nullptr || *root == '\0')
    return "ROTOLIDAR_DATA is not set (point it at the real-data folder to run this test)";
  *dir = folder.empty() ? std::string(root) : std::string(root) + "/" + folder;
  std::error_code ec;
  if (!std::filesystem::is_directory(*dir, ec))
    return *dir + " does not exist (ROTOLIDAR_DATA=" + root +
           "; point it at the real-data folder to run this test)";
  return "";
}

}  // namespace rotolidar::testdata

/// Declares `std::string var` = $ROTOLIDAR_DATA/<folder>; skips the test (fails under CI=true) when absent.
#define ROTOLIDAR_REQUIRE_DATA(var, folder)                                                    \
  std::string var;                                                                             \
  if (const std::string rotolidar_missing_ = ::rotolidar::testdata::FindDataFolder(folder, &var); \
      !rotolidar_missing_.empty()) {                                                           \
    if (::rotolidar::testdata::RunningUnderCi())                                               \
      FAIL() << "[realdata] " << rotolidar_missing_ << "; CI=true: real data is required";     \
    GTEST_SKIP() << "[realdata] skipped: " << rotolidar_missing_;                              \
  }
