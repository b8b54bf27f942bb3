#pragma once
// Puts a live rig's three UDP streams (VLP-16 data packets, position packets, rig samples) into the one time order
// the estimator and a recording folder expect, as `rotolidar slam` feeds a recording: before each packet, every
// IMU and encoder sample up to its capture time (bench/run/slam_run.cpp, Playback).
//
// Clocks. Rig samples carry rig time. A data packet's capture time is taken from its own VLP-16 timestamp (rig
// clock via calib.yaml lidar_clock_offset_s): its first firing + one packet period + the sensor's transmit
// latency, the rule the twin writes recordings with (core/wire/vlp16.hpp). The host's arrival time is not used
// for it: the host clock is not the rig clock, it drifts, and a replay at N x real time runs the rig clock N times
// faster. So a live recording's data packets carry the same capture times as the recording that was replayed.
// A position packet (its timestamp may lag; it carries no firing) gets the capture time of the last data packet
// plus the host time between their arrivals.
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
  /// The earliest capture time a recording can hold: -calib.yaml epoch_unix_s (pcap record times are Unix times).
  double min_capture_s = 0.0;
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
  /// A packet as received: packet.t_capture_s is the host's steady clock [s] (replaced by the rig-clock capture
  /// time on release).
  void AddPacket(LidarPacket packet);
  void AddSample(const RigSample& sample);
  /// Appends, in feed order, everything that may go at host time now_host_s.
  void Release(double now_host_s, std::vector<LiveItem>* out);
  /// End of input: appends everything still held.
  void ReleaseAll(std::vector<LiveItem>* out);
  const LiveMergerCounts& counts() const { return counts_; }
  /// Rig time of host time host_s, anchored on the last data packet (valid once one came).
  double HostToRig(double host_s) const { return anchor_rig_s_ + (host_s - anchor_host_s_); }

 private:
  /// The rig-clock capture time of a data packet from its timestamp; false for anything else.
  bool DataCaptureTime(const LidarPacket& packet, double* t_s) const;
  void EmitSamplesUpTo(Seconds t_s, std::vector<LiveItem>* out);
  void EmitPacket(std::vector<LiveItem>* out);
  Seconds SamplesReachedS() const;

  LiveMergerConfig config_;
  struct Held {
    LidarPacket packet;  // t_capture_s: host arrival
    double rig_s;        // its capture time on the rig clock (NaN for position packets until released)
  };
  std::deque<Held> packets_;                     // in arrival order
  std::multimap<Seconds, RigSample> samples_;    // by rig time
  bool have_anchor_ = false;                     // a data packet came
  double anchor_rig_s_ = 0.0, anchor_host_s_ = 0.0;
  Seconds latest_imu_s_ = -1e300, latest_encoder_s_ = -1e300;  // newest received, per kind
  bool seen_imu_ = false, seen_encoder_ = false;
  Seconds released_imu_s_ = -1e300, released_encoder_s_ = -1e300, released_packet_s_ = -1e300;
  LiveMergerCounts counts_;
};

}  // namespace rotolidar::bench
