#pragma once
// sensor_msgs/PointCloud2 clouds of a VLP-16 -> VLP-16 data packets (1206 bytes, UDP 2368) that the core's
// Vlp16Decoder reads back to the same points, for `rotolidar import` (docs/ros.md, "PointCloud2 LiDAR input").
//
// Input: clouds as the velodyne_pointcloud driver publishes them, in the VLP-16's own frame (the driver's
// "velodyne" frame: x forward, y left, z up, REP-103). Clouds transformed into another frame are not supported:
// each point must lie within 2 deg of its ring's laser elevation and the azimuth must grow with time (checked, see
// CloudPacketizer::Add; smaller rotations or shifts are not detected).
// Per point: laser ID = the ID whose elevation (calib lidar.elevation_deg) has rank `ring` (ring 0 = lowest, the
// driver's convention and Vlp16Decoder's); range = |p - Vlp16RayOrigin(laser)| in 2 mm units; azimuth =
// atan2(-y, x) (clockwise from +x seen from above, Vlp16RayDirection's convention); firing time = header.stamp +
// the point's time field; the point's firing sequence starts 2.304 us * laser earlier.
// Packets: sequences 55.296 us apart fill a packet's 24 slots (Vlp16PacketEncoder, strongest-return mode); rays
// without a point get distance 0. A packet's VLP-16 timestamp is its first slot's time rounded to the microsecond,
// on a sensor clock equal to the rig clock (lidar_clock_offset_s 0). Position packets are not produced.
// Round trip (points decoded from real packets -> cloud -> packets -> decoded): ranges within 1 mm (2 mm
// quantisation), azimuths within 0.01 deg (block azimuths in 0.01 deg, interpolated per laser as the decoder does),
// times within 0.5 us when the cloud's firings lie on the driver's packet grid, else within 1 us (a packet joining
// firings whose grids differ by up to 0.5 us; tested in cloud_import_test.cpp).
#include <cstdint>
#include <optional>
#include <vector>

#include "bench/ros/ros_messages.hpp"
#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench::rosmsg {

/// One point of a cloud as stored (no geometry yet).
struct CloudPoint {
  float x_m = 0.f, y_m = 0.f, z_m = 0.f;  ///< in the cloud's frame (must be the VLP-16's own) [m]
  float intensity = 0.f;                  ///< 0 when the cloud has no intensity field
  uint16_t ring = 0;                      ///< 0 = lowest elevation
  double dt_s = 0.0;                      ///< firing time relative to header.stamp [s]
  uint32_t index = 0;                     ///< row-major position in the message (errors name it)
};

/// Reads the points of `cloud` that hold a return: x, y, z finite and not all exactly 0 (organised clouds mark
/// rays without a return so). Fields: x, y, z (float32 or float64), ring (uint16 or uint8), time (float32 or
/// float64, seconds relative to header.stamp) or else t (uint32, nanoseconds relative to header.stamp), optional
/// intensity (any numeric type); each with count 1, little-endian. Fails with "field 'NAME': ..." (the caller
/// prefixes bag, topic and message) on a missing required field (the message lists the fields the cloud has), a
/// wrong datatype or count, a field outside point_step, big-endian data, row_step < width x point_step, data
/// shorter than row_step x height, or a time that is not finite or over an hour from header.stamp (an absolute
/// time in the field). *points is undefined on failure.
Status ReadCloudPoints(const PointCloud2Msg& cloud, std::vector<CloudPoint>* points);

/// Laser ID of each ring: ring r is the laser whose elevation (lidar.elevation_deg) has rank r (ties by ID), the
/// inverse of Vlp16Decoder's ring numbering.
std::array<int, 16> LaserOfRing(const LidarIntrinsics& lidar);

/// The earliest firing-sequence start of a cloud's points relative to its header.stamp, rounded down to whole ns:
/// min over points of time - 2.304 us x laser (a ring >= 16 counts as laser 0), so that no packet the cloud
/// becomes starts earlier. 0 for a cloud without points.
int64_t EarliestSequenceOffsetNs(const std::vector<CloudPoint>& points, const LidarIntrinsics& lidar);

/// Turns a stream of clouds (in time order) into VLP-16 data packets. Firings that continue the previous one's
/// 55.296 us grid (within 0.5 us, at most 23 empty sequences between) share packets across clouds, as the
/// driver's packets straddle its clouds; a firing off the grid (a new driver packet with a jittered stamp, a gap)
/// ends the packet in progress, its remaining slots empty. Not thread-safe.
class CloudPacketizer {
 public:
  /// `lidar`: the rig's calib (elevations and vertical offsets give the ring -> laser map and the ray origins;
  /// rpm the head speed until a cloud has measured it).
  explicit CloudPacketizer(const LidarIntrinsics& lidar);

  /// Adds one cloud whose header.stamp is `stamp_rig_s` on the rig clock [s]; appends the packets it completes
  /// (firing order; capture times non-decreasing) to *packets. Fails naming the point (index in the message) on a
  /// ring >= 16, a range over 131.07 m (the wire format's 16-bit 2 mm distance), a point more than 2 deg (the
  /// ring spacing) off its laser's elevation (a cloud not in the VLP-16 frame, or rings not numbered from the
  /// lowest), two points of one laser in one firing (dual-return clouds are not supported), a firing earlier than
  /// the packet in progress or the last one, and an azimuth that does not increase with time (a mirrored frame).
  /// The firings already placed stay placed on failure.
  Status Add(Seconds stamp_rig_s, const std::vector<CloudPoint>& points, std::vector<LidarPacket>* packets);

  /// Emits the packet in progress (unfilled slots empty), if any.
  void Flush(std::vector<LidarPacket>* packets);

  /// Head speed in use [0.01 deg/s]: the median over a cloud's consecutive firings, else calib lidar.rpm.
  double rate_centideg_per_s() const { return rate_centideg_per_s_; }

  /// One firing sequence seen in a cloud (internal; public for the helpers in the .cpp).
  struct Firing {
    Seconds t_s = 0.0;                        ///< laser 0's slot time (rig clock)
    std::array<uint16_t, 16> distance_2mm{};  ///< 0 = no point
    std::array<uint8_t, 16> reflectivity{};
    double az_centideg = 0.0;  ///< azimuth of its lowest laser with a point, [0, 36000)
    double lever_s = 0.0;      ///< that point's firing time - t_s
    bool observed = false;     ///< false: an empty slot
  };

 private:
  Status Place(const Firing& f, std::vector<LidarPacket>* packets);
  void EmitPacket(std::vector<LidarPacket>* packets);
  std::array<uint16_t, 12> BlockAzimuths() const;

  LidarIntrinsics lidar_;
  std::array<int, 16> laser_of_ring_{};
  Vlp16PacketEncoder encoder_;
  double rate_centideg_per_s_;
  std::vector<Firing> slots_;  ///< the packet in progress (< 24)
  bool run_ = false;           ///< a grid is in progress (anchor_t_ valid)
  bool anchor_observed_ = false;
  Seconds anchor_t_ = 0.0;       ///< slot 0 time of the packet in progress
  Seconds packet_start_t_ = -1;  ///< slot 0 time of the packet in progress or last emitted (< 0: none)
  Seconds last_capture_t_ = 0.0;
};

}  // namespace rotolidar::bench::rosmsg
