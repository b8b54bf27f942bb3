#pragma once
// Sensor messages: the only way data enters the estimator, from a real rig or from the sim.
// All times are on the rig clock (core/types/time.hpp), in seconds. All units are SI.
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "core/types/time.hpp"

namespace rotolidar {

/// One IMU sample, in the imu frame. The accelerometer measures specific force (gravity reads +9.81 m/s^2 "up").
struct ImuSample {
  Seconds t_s = 0.0;
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();    ///< angular rate [rad/s]
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();    ///< specific force [m/s^2]
};

/// One motor encoder reading: the rotor angle about the motor axis, as the encoder chip reports it.
/// `count` is the single-turn absolute reading in [0, counts_per_rev); counts_per_rev comes from calib.yaml
/// (4096 for a 12-bit encoder). Angle = 2*pi*(count + 0.5)/counts_per_rev - encoder zero (calib.yaml).
struct EncoderSample {
  Seconds t_s = 0.0;
  uint32_t count = 0;
};

/// Size of one VLP-16 data packet's UDP payload [bytes] (manual section 9).
inline constexpr std::size_t kVlp16PacketBytes = 1206;

/// One VLP-16 UDP payload as it came off the wire (data port 2368 or position port 8308).
/// `t_capture_s` is when the host captured it (pcap record time) on the rig clock; the points' own times come
/// from the timestamp inside the payload (see Vlp16Decoder in core/wire/vlp16.hpp).
struct LidarPacket {
  Seconds t_capture_s = 0.0;
  uint16_t udp_port = 2368;
  std::vector<uint8_t> payload;  ///< 1206 bytes for a data packet, 512 for a position packet
};

/// One decoded LiDAR return, in the lidar frame [m] (REP-103: x forward, y left, z up).
struct LidarPoint {
  float x_m = 0.f, y_m = 0.f, z_m = 0.f;
  float intensity = 0.f;      ///< reflectivity byte 0..255 (0..100 diffuse, 101..255 retroreflective)
  float azimuth_deg = 0.f;    ///< interpolated firing azimuth, [0, 360), clockwise from +Y as the manual counts
  uint8_t ring = 0;           ///< ring index sorted by elevation: 0 = -15 deg ... 15 = +15 deg
  uint8_t laser_id = 0;       ///< the laser's firing order 0..15 (manual Table 9-1)
  uint8_t return_type = 0;    ///< kReturnStrongest, kReturnLast or kReturnStrongestAndLast (below)
  Seconds t_s = 0.0;          ///< firing time of this point on the rig clock
};

/// LidarPoint::return_type. Single-return modes give the mode's type. Dual mode gives a firing's last and its
/// strongest (or second strongest) return as two points, or, where both blocks hold the same echo (identical
/// distance and reflectivity), one point of type kReturnStrongestAndLast (Vlp16DecoderConfig::
/// keep_duplicate_dual_returns keeps the two copies instead).
inline constexpr uint8_t kReturnStrongest = 0;
inline constexpr uint8_t kReturnLast = 1;
inline constexpr uint8_t kReturnStrongestAndLast = 2;

/// One revolution of the LiDAR head (or any span of points): points in the lidar frame, each with its own time.
struct LidarScan {
  Seconds t_start_s = 0.0;  ///< time of the first point
  Seconds t_end_s = 0.0;    ///< time of the last point
  std::vector<LidarPoint> points;
};

/// One camera image. `image` is BGR8 (OpenCV's order), owned by the frame (cv::Mat reference counting).
struct CameraFrame {
  Seconds t_s = 0.0;  ///< mid-exposure time
  cv::Mat image;
};

}  // namespace rotolidar
