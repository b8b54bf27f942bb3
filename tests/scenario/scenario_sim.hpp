#pragma once
// Shared by the scenario tests: simulate a recording into a fresh folder under the system's temporary directory.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

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

/// `typical` realism, the box room, camera off, carried by hand through `waypoints` (not the scene's carrier).
inline sim::SimConfig TypicalBoxRoomWalk(uint64_t seed, double duration_s,
                                         const std::vector<sim::Waypoint2d>& waypoints) {
  sim::SimConfig config = sim::PresetSimConfig(sim::Realism::kTypical);
  config.seed = seed;
  config.scene = "box_room";
  config.duration_s = duration_s;
  config.camera.enabled = false;
  config.carrier_from_scene = false;
  config.carrier.type = sim::CarrierType::kHandheld;
  config.carrier.handheld.waypoints = waypoints;
  return config;
}

}  // namespace rotolidar::bench::test_util
