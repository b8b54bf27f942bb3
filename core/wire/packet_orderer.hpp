#pragma once
// Puts VLP-16 data packets back into the order of their own timestamps before they are decoded, so that a scan is
// never built from packets out of time order and a trajectory is always time-ordered. What it repairs and counts:
//   reordered   a packet that arrived after a newer one, within the window: put back in place
//   duplicate   a packet whose timestamp was already seen (the same packet twice): dropped
//   late        a packet older than one already released (beyond the window): dropped
//   wild        a timestamp far (> max_jump_s) from the stream that the next packets do not confirm (a corrupted
//               stamp, e.g. one flipped bit): dropped. A jump that confirm_packets packets confirm is a real one
//               (the sensor restarted, or data is missing), and the stream follows it.
// The VLP-16 timestamp counts microseconds past the hour and wraps: keys are unwrapped against the stream.
// Position packets and packets too short to hold a timestamp pass straight through (the decoder reports the
// latter). Not thread-safe.
#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/types/messages.hpp"

namespace rotolidar {

struct PacketOrderConfig {
  double window_s = 0.05;     ///< a packet is released once one this much newer arrived [s]; 0 = no reordering
  double max_jump_s = 1.0;    ///< a timestamp this far from the stream's newest is suspect [s]
  int confirm_packets = 3;    ///< suspect packets that agree with each other before a jump is believed
  bool Validate(std::string* error) const;
};

struct PacketOrderCounts {
  std::size_t reordered = 0, duplicate = 0, late = 0, wild = 0;
  std::size_t total() const { return reordered + duplicate + late + wild; }
};

class PacketOrderer {
 public:
  explicit PacketOrderer(const PacketOrderConfig& config = PacketOrderConfig{});
  /// Takes one packet; appends to *released the packets that may go, in timestamp order.
  void Push(LidarPacket packet, std::vector<LidarPacket>* released);
  /// End of data: releases everything held (suspects that were never confirmed count as wild).
  void Flush(std::vector<LidarPacket>* released);
  const PacketOrderCounts& counts() const { return counts_; }

 private:
  int64_t Unwrap(uint32_t timestamp_us) const;
  void Accept(int64_t key, LidarPacket packet);
  void ReleaseOld(std::vector<LidarPacket>* released);
  void TakeSuspect(int64_t key, LidarPacket packet, std::vector<LidarPacket>* released);

  PacketOrderConfig config_;
  std::map<int64_t, LidarPacket> held_;  // by unwrapped timestamp [us]
  std::vector<std::pair<int64_t, LidarPacket>> suspects_;
  bool have_stream_ = false;
  int64_t newest_us_ = 0;     // newest accepted key
  int64_t released_us_ = 0;   // newest released key
  bool have_released_ = false;
  std::set<int64_t> recent_;       // keys released within max_jump_s of released_us_
  std::size_t stream_packets_ = 0;  // accepted since the stream (re)started
  PacketOrderCounts counts_;
};

}  // namespace rotolidar
