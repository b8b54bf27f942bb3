#pragma once
// A static capture of the VLP-16 twin: the caster fires from a fixed pose in a scene for a number of revolutions,
// its sequences are encoded into packets and decoded by core's decoder into revolutions, exactly as a real
// capture would be (bench/eval/plane_residuals.hpp measures both the same way).
#include <cstdint>
#include <string>
#include <vector>

#include "core/types/geometry.hpp"
#include "core/types/messages.hpp"
#include "core/util/status.hpp"
#include "sim/lidar/vlp16_caster.hpp"

namespace rotolidar::bench {

struct TwinCaptureOptions {
  std::string scene = "box_room";                  ///< scene name (scenes/NAME.yaml) or path
  Pose3 T_world_lidar = Pose3::Identity();         ///< the sensor's fixed pose
  int revolutions = 13;                            ///< full revolutions to return (the einride capture has 13)
  uint64_t seed = 1;                               ///< run seed of the caster's random streams
  sim::Vlp16CasterConfig lidar;                    ///< the twin's model (return mode: strongest or last)
};

/// Fires revolutions + 2 revolutions (the first and the last piece are partial and dropped) and returns the full
/// ones. Fails when the scene cannot be loaded or the config is invalid (message names it).
Status CaptureTwinRevolutions(const TwinCaptureOptions& options, std::vector<LidarScan>* scans);

}  // namespace rotolidar::bench
