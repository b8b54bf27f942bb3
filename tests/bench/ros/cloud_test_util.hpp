#pragma once
// Helpers of the PointCloud2 import tests (cloud_import_test.cpp, cloud_errors_test.cpp): driver-layout clouds,
// decoding a packet stream, hand-made firing sequences.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "bench/ros/cloud_to_packets.hpp"
#include "bench/ros/ros_messages.hpp"
#include "core/types/calib.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench::rosmsg::cloudtest {

/// The velodyne_pointcloud driver's point layout (PCL's padded PointXYZIRT): x, y, z at 0, 4, 8, intensity at 16,
/// ring at 20, time at 24; 32 bytes per point. `time_field` "time" (float32 s) or "t" (uint32 ns).
struct CloudLayout {
  std::string time_field = "time";
};

inline PointCloud2Msg MakeCloud(const RosTime& stamp, const std::vector<LidarPoint>& points, Seconds stamp_rig_s,
                         const CloudLayout& layout = {}) {
  PointCloud2Msg c;
  c.header.stamp = stamp;
  c.header.frame_id = "velodyne";
  const uint8_t f32 = static_cast<uint8_t>(PointFieldType::kFloat32);
  const uint8_t time_type =
      static_cast<uint8_t>(layout.time_field == "t" ? PointFieldType::kUint32 : PointFieldType::kFloat32);
  c.fields = {{"x", 0, f32, 1},
              {"y", 4, f32, 1},
              {"z", 8, f32, 1},
              {"intensity", 16, f32, 1},
              {"ring", 20, static_cast<uint8_t>(PointFieldType::kUint16), 1},
              {layout.time_field, 24, time_type, 1}};
  c.height = 1;
  c.width = static_cast<uint32_t>(points.size());
  c.point_step = 32;
  c.row_step = 32 * c.width;
  c.is_dense = 1;
  c.data.assign(c.row_step, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    uint8_t* p = c.data.data() + 32 * i;
    const LidarPoint& q = points[i];
    std::memcpy(p + 0, &q.x_m, 4), std::memcpy(p + 4, &q.y_m, 4), std::memcpy(p + 8, &q.z_m, 4);
    std::memcpy(p + 16, &q.intensity, 4);
    const uint16_t ring = q.ring;
    std::memcpy(p + 20, &ring, 2);
    if (layout.time_field == "t") {
      const uint32_t ns = static_cast<uint32_t>(std::llround((q.t_s - stamp_rig_s) * 1e9));
      std::memcpy(p + 24, &ns, 4);
    } else {
      const float dt = static_cast<float>(q.t_s - stamp_rig_s);
      std::memcpy(p + 24, &dt, 4);
    }
  }
  return c;
}

/// Decodes every packet of `packets` (one decoder: one stream).
inline std::vector<LidarPoint> DecodeAll(const std::vector<LidarPacket>& packets, const RigCalib& calib) {
  Vlp16DecoderConfig config;
  config.lidar_clock_offset_s = calib.lidar_clock_offset_s;
  Vlp16Decoder decoder(calib.lidar, config);
  std::vector<LidarPoint> points;
  for (const LidarPacket& p : packets) EXPECT_TRUE(decoder.Decode(p, &points).ok);
  return points;
}

/// `firings` firing sequences of all 16 lasers from time t0 [s] (55.296 us apart), head at az0_deg turning
/// 3600 deg/s (600 rpm), 10 m ranges: the points a driver would publish (ring, intensity, time).
inline std::vector<LidarPoint> Firings(const RigCalib& calib, double t0, int firings, double az0_deg) {
  std::vector<LidarPoint> out;
  const std::array<int, 16> laser_of_ring = LaserOfRing(calib.lidar);
  for (int s = 0; s < firings; ++s) {
    for (int ring = 0; ring < 16; ++ring) {
      const int laser = laser_of_ring[ring];
      const double t = t0 + s * kVlp16SequencePeriodS + laser * kVlp16FiringPeriodS;
      const double az = (az0_deg + 3600.0 * (t - t0)) * M_PI / 180.0;
      const Eigen::Vector3d p = Vlp16RayOrigin(calib.lidar.vertical_offset_m[laser]) +
                                10.0 * Vlp16RayDirection(calib.lidar.elevation_deg[laser] * M_PI / 180.0, az);
      LidarPoint q;
      q.x_m = static_cast<float>(p.x()), q.y_m = static_cast<float>(p.y()), q.z_m = static_cast<float>(p.z());
      q.ring = static_cast<uint8_t>(ring), q.laser_id = static_cast<uint8_t>(laser);
      q.intensity = static_cast<float>(10 + ring);
      q.t_s = t;
      out.push_back(q);
    }
  }
  return out;
}

}  // namespace rotolidar::bench::rosmsg::cloudtest
