#pragma once
// Runs one simulation and writes a recording folder (docs/recording_format.md): the same files a real rig's
// logger writes (calib.yaml, lidar.pcap, imu.csv, encoder.csv, camera.csv + camera/), plus truth/ on its own channel.
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "core/util/status.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::sim {

struct SimSummary {
  double sim_duration_s = 0.0;
  double wall_time_s = 0.0;
  // Counts of what reached the recording: with faults on (faults.yaml), lost packets and dropped IMU samples are
  // not counted and duplicated packets are. Returns and rays are the caster's, before faults.
  size_t lidar_packets = 0;   ///< VLP-16 data packets in lidar.pcap
  size_t lidar_returns = 0;   ///< rays with a non-zero distance
  size_t lidar_rays = 0;
  size_t imu_samples = 0;     ///< rows of imu.csv
  size_t encoder_samples = 0;
  size_t camera_frames = 0;    ///< images written to camera/ (0 when the camera is off)
  size_t scene_triangles = 0;  ///< static plus dynamic-object triangles (EmbreeScene::num_triangles)
  bool stopped = false;        ///< `stop` was set: the recording is whole but ends at sim_duration_s
  std::string recording_dir;
};

/// Called about every simulated second with the fraction done in [0, 1].
using ProgressFn = std::function<void(double fraction)>;

/// What a simulation writes into a recording folder: the recording's files and folders (core/io/recording.hpp)
/// plus sim_config.yaml and rig_model.xml.
std::vector<std::string> RecordingOutputNames();

/// Readies `dir` for a new recording so that it never mixes two runs: Ok when it does not exist or is empty;
/// an error naming it when it holds anything, unless `force`, which removes the previous run's recording outputs
/// (RecordingOutputNames; other files stay). Fails naming the path when it is a file or cannot be cleared.
Status PrepareRecordingDir(const std::string& dir, bool force);

/// Simulates `config` into `recording_dir` (created; files overwritten). Fails with a message naming the file
/// or field on bad config, scene or I/O errors; an unknown scene lists the available ones; a carrier path
/// that leaves the scene's bounds or crosses its static geometry fails before anything is simulated
/// (sim/scene_carrier.hpp). `stop` (optional, e.g. set by a signal handler) is polled every physics step: when
/// set, the simulation ends there and closes its files (a valid, shorter recording; SimSummary::stopped).
Status RunSimulation(const SimConfig& config, const std::string& recording_dir, SimSummary* summary,
                     const ProgressFn& progress = nullptr, const std::atomic<bool>* stop = nullptr);

}  // namespace rotolidar::sim
