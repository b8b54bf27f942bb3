#pragma once
// Puts a live rig's three UDP streams (VLP-16 data packets, position packets, rig samples) into the one time order
// the estimator and a recording folder expect, as `rotolidar slam` feeds a recording: before each packet, every
// IMU and encoder sample up to its capture time (bench/run/slam_run.cpp, Playback).
//
// Clocks. Rig samples carry rig time. Packets are stamped on arrival with the host's steady clock; their rig-clock
// capture time is the host time minus the smallest host-minus-sensor delay seen lately (the VLP-16's own timestamp
// in each data packet is on the rig clock, calib.yaml lidar_clock_offset_s): the fastest packet of the last
// 10-20 s defines "no network delay", so the host's clock drift against the rig's is followed. A capture time
// is the packet's first firing + one packet period + the sensor's transmit latency (as the twin writes them).
//
// Holding. A packet waits until the rig samples have reached its capture time, so that a sample sent before it is
// fed before it; after hold_s of host time it goes anyway (a silent IMU must not stop the LiDAR). Samples that
// arrive after a later sample of their kind was released (or twice) are dropped and counted: the recording's CSVs
// are strictly increasing in time. Not thread-safe (one owner thread).
#include <cstddef>
#include <deque>
#include <map>
#include <vector>

#include "core/types/messages.hpp"
#include "core/wire/rig_protocol.hpp"

namespace rotolidar::bench {

struct LiveItem {
  enum class Kind { kPacket, kImu, kEncoder };
  Kind kind = Kind::kPacket;
  LidarPacket packet;     ///< kPacket: t_capture_s on the rig clock
  ImuSample imu;          ///< kImu
  EncoderSample encoder;  ///< kEncoder
  Seconds t_s() const;
};

struct LiveMergerConfig {
  double hold_s = 0.25;                 ///< longest a packet waits for the rig samples [s, host clock]
  double lidar_clock_offset_s = 0.0;    ///< calib.yaml: rig time of VLP-16 timestamp 0 [s]
  double delay_window_s = 10.0;         ///< the minimum delay is taken over the last 1-2 windows [s]
  bool Validate(std::string* error) const;
};

struct LiveMergerCounts {
  std::size_t packets = 0, imu = 0, encoder = 0;  ///< released
  std::size_t late_samples = 0;                   ///< dropped: older than (or as old as) one already released
  std::size_t hold_timeouts = 0;                  ///< packets released before the samples reached them
};

class LiveMerger {
 public:
  explicit LiveMerger(const LiveMergerConfig& config);
  /// A packet as received: packet.t_capture_s is the host's steady clock [s].
  void AddPacket(LidarPacket packet);
  void AddSample(const RigSample& sample);
  /// Appends, in feed order, everything that may go at host time now_host_s.
  void Release(double now_host_s, std::vector<LiveItem>* out);
  /// End of input: appends everything still held.
  void ReleaseAll(std::vector<LiveItem>* out);
  const LiveMergerCounts& counts() const { return counts_; }
  /// Rig time of host time host_s (valid once a data packet came; otherwise host_s unchanged).
  double HostToRig(double host_s) const { return have_delay_ ? host_s - delay_s_ : host_s; }

 private:
  void TrackDelay(const LidarPacket& packet);
  void EmitSamplesUpTo(Seconds t_s, std::vector<LiveItem>* out);
  void EmitPacket(std::vector<LiveItem>* out);
  Seconds SamplesReachedS() const;

  LiveMergerConfig config_;
  std::deque<LidarPacket> packets_;              // host-stamped, in host order
  std::multimap<Seconds, RigSample> samples_;    // by rig time
  bool have_delay_ = false;
  double delay_s_ = 0.0;                         // host - rig, the minimum over the window(s)
  double window_start_host_s_ = 0.0, window_min_s_ = 0.0, previous_min_s_ = 0.0;
  Seconds latest_imu_s_ = -1e300, latest_encoder_s_ = -1e300;  // newest received, per kind
  bool seen_imu_ = false, seen_encoder_ = false;
  Seconds released_imu_s_ = -1e300, released_encoder_s_ = -1e300, released_packet_s_ = -1e300;
  LiveMergerCounts counts_;
};

}  // namespace rotolidar::bench
