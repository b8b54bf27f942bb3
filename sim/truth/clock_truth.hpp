#pragma once
// The true sensor clocks of a simulated run, in <recording>/truth/clocks.yaml (read only by bench/). calib.yaml
// holds what the rig's owner believes (the nominal LiDAR clock offset); this file holds what the twin ran, so a
// clock error is measurable. Every clock in one convention (sim/sensors/sensor_clock.hpp):
//   stamp = t + offset_s + drift_ppm * 1e-6 * t   (t: rig time [s]; the LiDAR's stamp is its sensor time)
// The LiDAR's offset_s is minus calib.yaml's lidar_clock_offset_s (that one maps sensor time to rig time), and
// its drift is 0 when pps_synced. lidar_capture is the host receive delay of the pcap records.
#include <string>

#include "core/util/status.hpp"
#include "sim/sensors/sensor_clock.hpp"

namespace rotolidar::sim {

struct ClockTruth {
  SensorClock lidar;               ///< the VLP-16's packet clock (effective drift: 0 when pps_synced)
  bool lidar_pps_synced = true;    ///< whether the PPS disciplined the VLP-16's clock
  SensorClock imu;
  SensorClock encoder;
  SensorClock camera;
  CaptureJitterConfig lidar_capture;  ///< host receive latency and jitter of the pcap capture times
};

/// Writes <recording_dir>/truth/clocks.yaml (the folder must exist); errors name the file.
Status WriteClockTruth(const std::string& recording_dir, const ClockTruth& clocks);
/// Reads it back; errors name file:line and the field. Recordings without the file fail (callers that accept
/// older recordings check for it first).
Status ReadClockTruth(const std::string& recording_dir, ClockTruth* clocks);

}  // namespace rotolidar::sim
