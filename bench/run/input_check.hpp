#pragma once
// What a careful user would check before trusting a run: the recording's streams and calibration, inspected once
// before the estimator starts. Each finding is a warning with counts (printed, written into metrics.json and the
// report); with `strict` a warning fails the run. The estimator still copes with each (it falls back to
// LiDAR-only without IMU, bridges gaps, ...), but the result is worse, and the user must know why.
//   imu.missing              imu.csv has no samples: the run is LiDAR-only
//   imu.gaps                 steps between IMU samples over gap_factor / imu.rate_hz (count, longest)
//   encoder.gaps             steps between encoder samples over max_encoder_gap_s (count, longest): the rotor
//                            angle across such a gap is a guess (the unwrap may pick the wrong turn)
//   encoder.resolution       the largest count seen is below counts_per_rev / 4 over more than a few turns of
//                            data: calib.yaml's counts_per_rev (e.g. 16384 for a 14-bit chip) disagrees with
//                            the data (e.g. a 12-bit encoder's 0..4095)
//   calib.pose_missing       T_base_motor / T_rotor_lidar / T_base_imu not in calib.yaml: identity assumed
//   lidar.lost_packets       data packets missing from the timestamp sequence (core/wire/packet_gaps.hpp),
//                            counted after the core's reordering (core/wire/packet_orderer.hpp)
//   lidar.blind              0.5 s or more of data packets without a single return (a covered or failed sensor)
//   encoder.frozen           the count unchanged for 0.25 s or more while calib.yaml says the rotor turns
//   imu.saturated            an axis sits at its extreme value on 3 or more samples (a clipped sensor)
//   lidar.unreadable         (the overload without a Status only) a streamed lidar.pcap failed to read
#include <string>
#include <vector>

#include "core/io/recording.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct InputCheckConfig {
  double gap_factor = 3.0;           ///< an IMU step over gap_factor nominal periods is a gap
  double max_encoder_gap_s = 0.05;   ///< an encoder step over this is a gap [s]
};

struct InputWarning {
  std::string code;     ///< e.g. "imu.gaps" (the list above)
  std::string message;  ///< names the file and what was found, with counts
  std::size_t count = 0;
};

/// Inspects a loaded recording (and its calib.yaml's text for the keys it gives), appending its findings to *out.
/// Reads a streamed lidar.pcap (PacketLoading::kStreamed) once, one packet at a time; fails only where that file
/// cannot be read (a malformed record, no VLP-16 data: LoadRecording's errors for packets in memory).
Status CheckRecording(const Recording& recording, const InputCheckConfig& config, std::vector<InputWarning>* out);
/// The same for a recording whose packets are in memory. Never fails: findings come back as warnings (an
/// unreadable streamed lidar.pcap as "lidar.unreadable").
std::vector<InputWarning> CheckRecording(const Recording& recording, const InputCheckConfig& config = {});

/// "N warnings" summary lines for a terminal, one per warning.
std::string InputWarningsText(const std::vector<InputWarning>& warnings);

}  // namespace rotolidar::bench
