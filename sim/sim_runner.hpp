#pragma once
// Runs one simulation and writes a recording folder (docs/recording_format.md): the same files a real rig's
// logger writes (calib.yaml, lidar.pcap, imu.csv, encoder.csv, camera.csv + camera/), plus truth/ on its own channel.
#include <functional>
#include <string>

#include "core/util/log.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::sim {

struct SimSummary {
  double sim_duration_s = 0.0;
  double wall_time_s = 0.0;
  size_t lidar_packets = 0;
  size_t lidar_returns = 0;   ///< rays with a non-zero distance
  size_t lidar_rays = 0;
  size_t imu_samples = 0;
  size_t encoder_samples = 0;
  size_t camera_frames = 0;    ///< images written to camera/ (0 when the camera is off)
  size_t scene_triangles = 0;  ///< static plus dynamic-object triangles (EmbreeScene::num_triangles)
  std::string recording_dir;
};

/// Called about every simulated second with the fraction done in [0, 1].
using ProgressFn = std::function<void(double fraction)>;

/// Simulates `config` into `recording_dir` (created; files overwritten). Fails with a message naming the file
/// or field on bad config, scene or I/O errors.
Status RunSimulation(const SimConfig& config, const std::string& recording_dir, SimSummary* summary,
                     const ProgressFn& progress = nullptr);

}  // namespace rotolidar::sim
