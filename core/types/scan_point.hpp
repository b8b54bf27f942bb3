#pragma once
// The front end's point: one decoded return, deskewed into the base frame at its scan's start time, with the
// sensor attributes feature extraction needs.
#include <cstdint>

#include <Eigen/Core>

#include "core/types/messages.hpp"
#include "core/types/time.hpp"

namespace rotolidar {

/// One deskewed LiDAR return with the sensor attributes the front end needs (LOAM's ring order, occlusion and
/// beam-parallel tests work in the sensor frame; the geometry works in the base frame).
struct ScanPoint {
  Eigen::Vector3f p_base = Eigen::Vector3f::Zero();  ///< position in the base frame at the scan's start time [m]
  float range_m = 0.f;      ///< distance from the lidar origin at firing time, |p_lidar| [m]
  float azimuth_deg = 0.f;  ///< head azimuth at firing, [0, 360), as LidarPoint::azimuth_deg
  float intensity = 0.f;    ///< reflectivity byte 0..255
  uint8_t ring = 0;         ///< 0..15 sorted by elevation (LidarPoint::ring)
  Seconds t_s = 0.0;        ///< firing time on the rig clock
};

/// One decoded return with its deskewed base-frame position p_base_start [m] (cast to float); range_m = |p_lidar|.
inline ScanPoint ToScanPoint(const LidarPoint& lp, const Eigen::Vector3d& p_base_start) {
  ScanPoint sp;
  sp.p_base = p_base_start.cast<float>();
  sp.range_m = Eigen::Vector3f(lp.x_m, lp.y_m, lp.z_m).norm();
  sp.azimuth_deg = lp.azimuth_deg;
  sp.intensity = lp.intensity;
  sp.ring = lp.ring;
  sp.t_s = lp.t_s;
  return sp;
}

}  // namespace rotolidar
