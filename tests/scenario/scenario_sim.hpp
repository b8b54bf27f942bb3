#pragma once
// Shared by the scenario tests: simulate a recording into a fresh folder under the system's temporary directory.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "sim/sim_runner.hpp"

namespace rotolidar::bench::test_util {

/// Simulates `config` into <tmp>/<name>/recording (the folder emptied first) and returns <tmp>/<name>; a failed
/// simulation is a test failure (check with ::testing::Test::HasFatalFailure / HasFailure).
inline std::string SimulateFresh(const sim::SimConfig& config, const std::string& name) {
  const std::string dir = (std::filesystem::temp_directory_path() / name).string();
  std::filesystem::remove_all(dir);
  sim::SimSummary summary;
  const Status status = sim::RunSimulation(config, dir + "/recording", &summary);
  EXPECT_TRUE(status.ok) << status.message;
  return dir;
}

}  // namespace rotolidar::bench::test_util
