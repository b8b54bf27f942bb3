#pragma once
// The VLP-16's position packets (UDP 8308) as the twin emits them, on the sim clock: what a sensor wired to a
// GPS receiver (PPS + NMEA $GPRMC) puts on the wire, so that the recording carries the same time-sync evidence
// as a real one (docs/lidar_model.md "Position packets").
//
// Rate: the manual (63-9243, 9.3.3) gives "about 14 data packets per position packet": 753.5 / 14 = 53.8 Hz in
// single-return mode. Packet k is assembled at t0_s + k / rate_hz; its timestamp is the sensor clock at that time
// (Vlp16TimestampUs with lidar_clock_offset_s, as for data packets), its PPS byte `pps_status`, and its sentence
// the $GPRMC of the last whole UTC second (utc = epoch_unix_s + t; the receiver sends one sentence per PPS edge).
// The packet is captured transmit_latency_s after it was assembled.
//
// Consistency: with PPS locked the sensor's clock IS UTC microseconds past the hour (manual 9.3.1.6), so a locked
// source requires lidar_clock_offset_s = PpsLockedClockOffsetS(epoch_unix_s) (mod 3600 s); Validate says so.
#include <cstdint>
#include <string>
#include <vector>

#include "core/wire/vlp16.hpp"
#include "core/types/messages.hpp"

namespace rotolidar::sim {

struct Vlp16PositionConfig {
  double rate_hz = 753.5 / 14.0;       ///< position packets per second (manual: ~1 per 14 data packets)
  double t0_s = 0.0;                   ///< rig time of the first packet [s]
  double epoch_unix_s = 0.0;           ///< Unix time of rig time 0 [s] (calib.yaml epoch_unix_s)
  double lidar_clock_offset_s = 0.0;   ///< calib.yaml lidar_clock_offset_s [s]
  double clock_drift_ppm = 0.0;        ///< sensor clock = t - lidar_clock_offset_s + this * 1e-6 * t [ppm]
  uint8_t pps_status = 2;              ///< 0 none, 1 synchronizing, 2 locked, 3 error
  bool gps_fix = true;                 ///< $GPRMC status A (fix) or V (no fix)
  double latitude_deg = 0.0;           ///< antenna position the sentences report [deg]; the twin models no
  double longitude_deg = 0.0;          ///< GNSS position, only time, so this is whatever the config says
  double transmit_latency_s = kVlp16TransmitLatencyS;  ///< assembly -> host capture [s]
  /// True when usable; otherwise false with the field named in *error (also for PPS locked with a sensor clock
  /// that does not read UTC).
  bool Validate(std::string* error) const;
};

/// The lidar_clock_offset_s that makes the sensor's hour-relative clock read UTC for a rig started at Unix time
/// epoch_unix_s: -(epoch_unix_s mod 3600 s). The decoder's rig time (hour 0 at the first packet) is then
/// UTC - epoch_unix_s.
double PpsLockedClockOffsetS(double epoch_unix_s);

/// Emits position packets on the sim clock. Call EmitUntil with non-decreasing times. Not thread-safe.
class Vlp16PositionSource {
 public:
  /// ROTOLIDAR_CHECKs config.Validate (validate at the edges).
  explicit Vlp16PositionSource(const Vlp16PositionConfig& config);

  /// Appends every packet assembled at or before t_s (rig time), in time order (udp_port 8308, 512 bytes,
  /// t_capture_s = assembly time + transmit_latency_s). Returns how many it appended.
  std::size_t EmitUntil(Seconds t_s, std::vector<LidarPacket>* out);
  /// Assembly time of the next packet [s].
  Seconds next_time_s() const;
  std::size_t emitted() const { return static_cast<std::size_t>(next_index_); }

 private:
  Vlp16PositionConfig config_;
  int64_t next_index_ = 0;
};

}  // namespace rotolidar::sim
