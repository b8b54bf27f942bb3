#pragma once
// VLP-16 wire format (user manual 63-9243, section 9): data packets (UDP 2368) and position packets (UDP 8308),
// the encoder the sim uses to produce them, and the decoder that turns them into timed points.
// The same code serves sim packets and real packets.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/util/log.hpp"

namespace rotolidar {

enum class Vlp16ReturnMode : uint8_t { kStrongest = 0x37, kLast = 0x38, kDual = 0x39 };
/// The modes' words in configs: "strongest", "last", "dual" (core/io/yaml_fields.hpp finds it by
/// argument-dependent lookup).
const std::vector<std::pair<const char*, Vlp16ReturnMode>>& EnumWords(Vlp16ReturnMode*);
inline constexpr uint8_t kVlp16ProductId = 0x22;
inline constexpr double kVlp16FiringPeriodS = 2.304e-6;   ///< between consecutive lasers
inline constexpr double kVlp16SequencePeriodS = 55.296e-6;  ///< one firing sequence of 16 lasers
inline constexpr double kVlp16DistanceUnitM = 0.002;        ///< distance LSB
inline constexpr int kVlp16SequencesPerPacket = 24;         ///< single-return mode

/// One firing sequence of the 16 lasers, as the head measured it: the encoder's input.
/// For dual-return mode each laser carries a second (strongest/second strongest) return.
struct Vlp16FiringSequence {
  Seconds t_s = 0.0;                          ///< firing time of laser 0 on the rig clock
  uint16_t azimuth_centideg = 0;              ///< head azimuth at laser 0, [0, 36000) in 0.01 deg
  std::array<uint16_t, 16> distance_2mm{};    ///< per laser ID; 0 = no return
  std::array<uint8_t, 16> reflectivity{};     ///< per laser ID
  std::array<uint16_t, 16> distance2_2mm{};   ///< dual mode only: the other return
  std::array<uint8_t, 16> reflectivity2{};    ///< dual mode only
};

/// Unit direction of laser `laser_id`'s ray in the lidar frame at head azimuth `azimuth_rad` (manual 9.2 remapped
/// to REP-103: azimuth clockwise from +x seen from above, i.e. the manual's angle from +Y, so
/// x = cos(w)cos(a), y = -cos(w)sin(a), z = sin(w) with w the laser's elevation).
/// Encoder (sim) and decoder (core) both use these two functions: they cannot disagree.
inline Eigen::Vector3d Vlp16RayDirection(double elevation_rad, double azimuth_rad) {
  const double c = std::cos(elevation_rad);
  return {c * std::cos(azimuth_rad), -c * std::sin(azimuth_rad), std::sin(elevation_rad)};
}

/// Origin of a laser's ray in the lidar frame [m]: the manual's per-laser vertical offset along z.
inline Eigen::Vector3d Vlp16RayOrigin(double vertical_offset_m) { return {0.0, 0.0, vertical_offset_m}; }

// ---------------------------------------------------------------------------------------------------------------
// Raw wire fields (no interpretation). Byte layout of a 1206-byte data payload (all integers little-endian):
//   block b at byte 100*b: flag uint16 (0xEEFF = bytes FF EE), azimuth uint16 [0.01 deg],
//     32 x {distance uint16 [2 mm], reflectivity uint8} (channels 0..15 = first firing, 16..31 = second firing)
//   byte 1200: timestamp uint32 [us past the top of the hour]; 1204: return mode; 1205: product id.

inline constexpr uint16_t kVlp16BlockFlag = 0xEEFF;     ///< bytes FF EE read little-endian
inline constexpr uint16_t kVlp16DataPort = 2368;
inline constexpr uint16_t kVlp16PositionPort = 8308;
inline constexpr std::size_t kVlp16PositionPacketBytes = 512;
inline constexpr uint32_t kVlp16MicrosPerHour = 3600000000u;
/// Fixed delay from a packet's last firing to its capture by the host (t_capture_s) that the encoder models.
/// Not a measured value: it only has to be small (< one packet period, 1.327 ms) and constant.
inline constexpr double kVlp16TransmitLatencyS = 100e-6;

struct Vlp16RawBlock {
  uint16_t flag = kVlp16BlockFlag;
  uint16_t azimuth_centideg = 0;                ///< [0, 36000)
  std::array<uint16_t, 32> distance_2mm{};      ///< channel = 16 * firing + laser_id; 0 = no return
  std::array<uint8_t, 32> reflectivity{};
};

struct Vlp16RawPacket {
  std::array<Vlp16RawBlock, 12> blocks{};
  uint32_t timestamp_us = 0;                    ///< past the top of the hour, < 3.6e9
  uint8_t return_mode = static_cast<uint8_t>(Vlp16ReturnMode::kStrongest);
  uint8_t product_id = kVlp16ProductId;
};

/// Parse a data payload. Fails (message names the byte offset and the field) on a size other than 1206, a block
/// flag other than FF EE, an azimuth >= 36000, a timestamp >= 3.6e9 us, an unknown return mode or a product id
/// other than 0x22. `out` is written only on success.
Status ParseVlp16DataPacket(const uint8_t* data, std::size_t size, Vlp16RawPacket* out);
/// The exact 1206 bytes of `packet` (no validation: what you put in is what goes on the wire).
std::vector<uint8_t> SerializeVlp16DataPacket(const Vlp16RawPacket& packet);

// ---------------------------------------------------------------------------------------------------------------
// Position packet (UDP 8308, 512 bytes): bytes 0..197 zero, 198 timestamp uint32 LE [us past hour], 202 PPS status
// (0 none, 1 synchronizing, 2 locked, 3 error), 203..205 zero, 206.. NMEA $GPRMC sentence, zero padded. The manual
// reserves 72 bytes for the sentence; real units write longer sentences into the following unused bytes, so the
// sentence may fill bytes 206..511 (306 bytes at most).
inline constexpr std::size_t kVlp16NmeaOffset = 206;
inline constexpr std::size_t kVlp16NmeaMaxBytes = kVlp16PositionPacketBytes - kVlp16NmeaOffset;

struct Vlp16PositionPacket {
  uint32_t timestamp_us = 0;
  uint8_t pps_status = 0;
  std::string nmea;  ///< up to the first zero byte
};

/// Position packet sent at rig time t_s (t_capture_s = t_s, udp_port 8308). Timestamp as for data packets:
/// floor((t_s - lidar_clock_offset_s) * 1e6) mod 3.6e9. A sentence longer than 306 bytes is truncated.
LidarPacket EncodeVlp16PositionPacket(Seconds t_s, double lidar_clock_offset_s, uint8_t pps_status,
                                      const std::string& nmea_gprmc);
/// Fails on a size other than 512, a timestamp >= 3.6e9 or a PPS status > 3 (message names the offset).
Status ParseVlp16PositionPacket(const uint8_t* data, std::size_t size, Vlp16PositionPacket* out);

/// The sensor's timestamp for rig time t_s: floor((t_s - offset) * 1e6) mod 3.6e9, always in [0, 3.6e9). A 1 ps
/// tolerance is added before the floor so that times meant to be whole microseconds do not lose one to rounding.
uint32_t Vlp16TimestampUs(Seconds t_s, double lidar_clock_offset_s);

/// The NMEA 0183 $GPRMC sentence a GPS receiver sends for the whole UTC second containing utc_unix_s (fraction
/// dropped, as receivers stamp the PPS edge): "$GPRMC,hhmmss,A|V,ddmm.mmmm,N|S,dddmm.mmmm,E|W,000.0,000.0,ddmmyy,,,
/// A|N*hh\r\n" (hh = XOR checksum of the characters between '$' and '*'). `valid` selects status A (fix) or V.
/// utc_unix_s must be >= 0 (dates from 1970 on).
std::string FormatGprmc(double utc_unix_s, bool valid, double latitude_deg, double longitude_deg);
/// UTC [Unix seconds] of an RMC sentence ($GPRMC, $GNRMC, ...): time hhmmss[.ss] (field 1), date ddmmyy (field 9;
/// yy < 80 is 20yy: years 1980..2079). A present checksum must match. Fails naming the field; *utc_unix_s is
/// written only on success.
Status ParseGprmcUtc(const std::string& sentence, double* utc_unix_s);
/// Days from 1970-01-01 to a proleptic Gregorian date (H. Hinnant's days_from_civil; no time zone).
int64_t UnixDaysFromCivil(int year, int month, int day);

// ---------------------------------------------------------------------------------------------------------------
/// Packs firing sequences into data packets, as the sensor does. Not thread-safe.
///
/// Single-return modes (kStrongest, kLast): 24 sequences per packet; sequence i goes to block i/2, firing i%2
/// (channels 16*(i%2) + laser), from distance_2mm/reflectivity. Dual mode: 12 sequences per packet; sequence j goes
/// to firing j%2 of the block pair (2*(j/2), 2*(j/2)+1), both blocks carry the same azimuth; the EVEN block holds
/// the last return (distance_2mm/reflectivity), the ODD block the strongest or second strongest return
/// (distance2_2mm/reflectivity2), as the manual orders them.
/// A block's azimuth is that of its first sequence; the second firing's azimuth is not transmitted (the decoder
/// interpolates it). Only the packet's first sequence time is transmitted: sequences are assumed to be
/// kVlp16SequencePeriodS apart, as the real head fires them.
/// t_capture_s = (last sequence's t_s + 15 * kVlp16FiringPeriodS) + kVlp16TransmitLatencyS.
class Vlp16PacketEncoder {
 public:
  /// Stamps each packet with the sensor clock read at its first firing (rig time t):
  /// t - lidar_clock_offset_s + clock_drift_ppm * 1e-6 * t [s] (the drift of a head whose clock free-runs;
  /// 0 leaves the stamps exactly as the offset alone makes them).
  Vlp16PacketEncoder(Vlp16ReturnMode mode, double lidar_clock_offset_s, double clock_drift_ppm = 0.0);

  /// Adds one sequence; returns the finished 1206-byte packet (udp_port 2368) after every 24th (dual: 12th).
  std::optional<LidarPacket> Add(const Vlp16FiringSequence& sequence);
  int SequencesPerPacket() const { return mode_ == Vlp16ReturnMode::kDual ? 12 : 24; }
  int pending() const { return pending_; }  ///< sequences waiting in the unfinished packet
  void Reset() { pending_ = 0; }            ///< drop the unfinished packet

 private:
  Vlp16ReturnMode mode_;
  double lidar_clock_offset_s_;
  double clock_drift_ppm_;
  Vlp16RawPacket packet_;
  int pending_ = 0;
};

// ---------------------------------------------------------------------------------------------------------------
enum class Vlp16ReturnFilter { kAll = 0, kStrongest = 1, kLast = 2 };

/// Whether a point of LidarPoint::return_type `return_type` passes `filter`: kAll passes everything, kStrongest
/// kReturnStrongest and kReturnStrongestAndLast, kLast kReturnLast and kReturnStrongestAndLast.
bool Vlp16ReturnSelected(Vlp16ReturnFilter filter, uint8_t return_type);

struct Vlp16DecoderConfig {
  double min_range_m = kVlp16BlindZoneM;         ///< closer returns are dropped [m]
  double max_range_m = kVlp16MaxReportedRangeM;  ///< farther returns are dropped [m]
  Vlp16ReturnFilter return_filter = Vlp16ReturnFilter::kAll;  ///< keeps points with Vlp16ReturnSelected
  double lidar_clock_offset_s = 0.0;  ///< rig time = unwrapped us past the hour * 1e-6 + this [s]
  /// Dual mode: when a firing's two blocks carry the same echo (identical distance and reflectivity: the
  /// strongest return was also the last), false emits it once as kReturnStrongestAndLast (counted in
  /// Vlp16Decoder::merged_dual_duplicates()); true emits both copies (kReturnLast, then kReturnStrongest).
  bool keep_duplicate_dual_returns = false;
  bool Validate(std::string* error) const;
};

/// Turns data packets into timed points in the lidar frame. Keeps state (hour unwrapping, last position packet):
/// feed one stream in order. Not thread-safe.
///
/// Per point: time = packet timestamp + 55.296 us * SeqIdx + 2.304 us * (ch % 16), SeqIdx = 2*block + ch/16
/// (single return) or block - block%2 + ch/16 (dual), then mapped to the rig clock through the unwrapped hour.
/// Unwrapping starts in hour 0 at the first packet and follows the timestamps: a jump back (forward) by more than
/// half an hour counts as entering the next (previous) hour. Azimuth interpolated per firing (driver formula) with
/// d_az = the next distinct block azimuth minus this one mod 36000 (dual: the next block PAIR; the last block
/// (pair) reuses the previous difference; a difference over 10 deg is implausible and replaced by the previous).
/// Position = Vlp16RayOrigin(offset) + Vlp16RayDirection(elevation, azimuth) * range. ring sorts by elevation,
/// laser_id = ch % 16. Distance 0 (no return) and ranges outside [min, max] give no point. return_type: the
/// mode's (single) or even block = last, odd = strongest (dual). Dual mode, same channel in both blocks of a pair
/// with equal non-zero distance and equal reflectivity: one echo reported twice (the manual, 63-9243 9.3.2.1, puts
/// the second strongest return in the odd block when the strongest is also the last; with no second echo both
/// blocks carry the same one, as the sim's caster writes it: 57,378 such pairs in 114,900 points of a 0.2 s
/// dual-return run), so by default that is one point of type kReturnStrongestAndLast, counted in
/// merged_dual_duplicates() (Vlp16DecoderConfig::keep_duplicate_dual_returns).
class Vlp16Decoder {
 public:
  /// ROTOLIDAR_CHECKs that config.Validate() holds (an invalid config is a programmer error here).
  Vlp16Decoder(const LidarIntrinsics& intrinsics, const Vlp16DecoderConfig& config);

  /// Appends the packet's points to *appended (in firing order = time order). Position packets (port 8308 or
  /// 512 bytes) are parsed into last_position() and give no points. A malformed packet returns the parse error
  /// and appends nothing.
  Status Decode(const LidarPacket& packet, std::vector<LidarPoint>* appended);

  const std::optional<Vlp16PositionPacket>& last_position() const { return last_position_; }
  /// Unix time [s] of the UTC top of the hour the sensor's timestamps count from, known once a position packet
  /// with PPS locked (status 2) and a parsable RMC sentence has been decoded (manual 9.3.1.6: with PPS the
  /// timestamp is UTC microseconds past the hour): round((utc_rmc - timestamp) / 3600 s) * 3600 s, which
  /// tolerates the sentence being up to half an hour stale. nullopt before. With it a logger can set
  /// calib.yaml's lidar_clock_offset_s = hour start - epoch_unix_s (the rig clock then reads UTC - epoch).
  const std::optional<double>& hour_start_unix_s() const { return hour_start_unix_s_; }
  const Vlp16RawPacket& last_raw() const { return raw_; }  ///< the last data packet parsed
  /// Dual mode: points emitted as kReturnStrongestAndLast since construction, i.e. duplicate returns not emitted
  /// a second time (0 with keep_duplicate_dual_returns). Counted after the range filter.
  std::size_t merged_dual_duplicates() const { return merged_dual_duplicates_; }
  /// Rig time [s] of a timestamp in the current unwrapping state (updates it, as Decode does).
  Seconds UnwrapToRigTime(uint32_t timestamp_us);

 private:
  /// Points of one firing (16 lasers) of block `block`, firing `firing` (0/1), in laser order.
  void DecodeFiring(int block, int firing, double d_az, double packet_t_s, std::vector<LidarPoint>* appended);
  std::array<double, 12> AzimuthSteps() const;  ///< d_az [0.01 deg] per block of raw_
  void TakePosition(const Vlp16PositionPacket& position);

  LidarIntrinsics intrinsics_;
  Vlp16DecoderConfig config_;
  std::array<uint8_t, 16> ring_of_laser_{};
  std::array<double, 16> cos_elevation_{};  ///< per laser ID
  std::array<double, 16> sin_elevation_{};
  // Per-laser azimuth increment rotations (cos, sin of d_az * laser * 2.304 / 110.592) for the d_az last seen.
  mutable double cached_d_az_ = -1.0;
  mutable std::array<double, 16> cos_increment_{};
  mutable std::array<double, 16> sin_increment_{};
  Vlp16RawPacket raw_;
  std::optional<Vlp16PositionPacket> last_position_;
  std::optional<double> hour_start_unix_s_;
  std::size_t merged_dual_duplicates_ = 0;
  bool have_time_ = false;
  int64_t hour_ = 0;
  int64_t last_unwrapped_us_ = 0;
};

}  // namespace rotolidar
