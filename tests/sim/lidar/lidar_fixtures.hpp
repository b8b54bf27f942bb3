#pragma once
// Small helpers shared by the VLP-16 caster tests (tests/sim/lidar/vlp16_*_test.cpp).
#include <cmath>

#include "core/types/geometry.hpp"
#include "sim/lidar/vlp16_caster.hpp"

namespace rotolidar::sim::lidar_test {

inline constexpr double kDeg = M_PI / 180.0;

inline Vlp16CasterConfig NoiseFree() {
  Vlp16CasterConfig c;
  c.range_noise_sigma_m = 0.0;
  return c;
}

inline Pose3 Static(const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.translation() = t;
  return T;
}

}  // namespace rotolidar::sim::lidar_test
