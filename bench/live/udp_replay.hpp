#pragma once
// Plays a whole recording folder onto UDP as the real rig would send it: VLP-16 data and position packets (as the
// sensor does) and the IMU and encoder samples in the rig-sample protocol (core/wire/rig_protocol.hpp, as the
// rig's microcontroller does), merged in time order and paced at N x real time. For `rotolidar replay` and the
// loopback tests of `rotolidar live`. Optional loss on the way: a share of the data packets is not sent, drawn
// from the random stream "replay.drop" of the given seed.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "core/io/recording.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct UdpReplayConfig {
  std::string host = "127.0.0.1";  ///< destination IPv4
  uint16_t data_port = 2368;
  uint16_t position_port = 8308;
  uint16_t rig_port = 0;           ///< rig samples' destination; 0 = do not send them
  std::size_t rig_batch = 1;       ///< samples per rig datagram (1..20)
  double rate = 1.0;               ///< x real time; 0 = as fast as possible
  double drop_fraction = 0.0;      ///< share of data packets not sent, [0, 1)
  uint64_t seed = 1;               ///< run seed of the drop stream
  bool Validate(std::string* error) const;
};

struct UdpReplayStats {
  std::size_t data_sent = 0, position_sent = 0, data_dropped = 0, samples_sent = 0, rig_datagrams = 0;
  double span_s = 0.0;        ///< of the recording's data
  double wall_s = 0.0;
  double max_lateness_s = 0.0;
};

/// Sends everything; returns at the end, at the first send error (message names what) or when *stop is set.
/// `progress` (optional) is called about once per wall second.
Status ReplayOverUdp(const Recording& recording, const UdpReplayConfig& config, UdpReplayStats* stats,
                     const std::atomic<bool>* stop = nullptr,
                     const std::function<void(const UdpReplayStats&)>& progress = nullptr);

}  // namespace rotolidar::bench
