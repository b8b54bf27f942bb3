// The estimator's derived defaults: the keyframe policy follows the rotor angle per scan (calib.yaml's motor speed
// and head rpm), explicit config values win, and the range sigma comes from calib.yaml.
#include <gtest/gtest.h>

#include "core/pipeline/estimator_config.hpp"

namespace rotolidar {
namespace {

RigCalib Rotary(double motor_speed_radps, double rpm) {
  RigCalib c;
  c.motor_speed_radps = motor_speed_radps;
  c.lidar.rpm = rpm;
  return c;
}

TEST(RotaryKeyframePolicy, FollowsTheRotorAnglePerScan) {
  LocalMapConfig map;
  map.max_keyframes = 40;  // a small window, so that the cap shows
  struct Case {
    double speed_radps, rpm;
    int every, initial;
  };
  // a = |w| * 60 / rpm per scan: every = floor(30 deg / a), initial = min(floor(360 deg / a), 40).
  const Case cases[] = {
      {2.6, 600, 2, 24},    // the seed's speed: 14.9 deg per scan
      {-2.6, 600, 2, 24},   // the direction does not matter
      {1.3, 600, 4, 40},    // 7.4 deg: 48 scans per turn, capped by the 40-keyframe window
      {5.2, 600, 1, 12},    // 29.8 deg: every scan
      {2.6, 1200, 4, 40},   // a faster head halves the angle per scan
      {20.0, 600, 1, 3},    // 115 deg per scan: still at least every scan
  };
  for (const Case& c : cases) {
    const KeyframePolicy p = RotaryKeyframePolicy(Rotary(c.speed_radps, c.rpm), map);
    EXPECT_EQ(p.every_scans, c.every) << c.speed_radps << " rad/s at " << c.rpm << " rpm";
    EXPECT_EQ(p.initial_keyframes, c.initial) << c.speed_radps << " rad/s at " << c.rpm << " rpm";
  }
  const KeyframePolicy still = RotaryKeyframePolicy(Rotary(0.0, 600), map);  // a fixed LiDAR (KITTI)
  EXPECT_EQ(still.every_scans, 0);
  EXPECT_EQ(still.initial_keyframes, 0);
}

TEST(ResolveFromCalib, DerivesMarkedValuesAndKeepsExplicitOnes) {
  RigCalib calib = Rotary(1.3, 600);
  calib.lidar.range_sigma_m = 0.03;
  EstimatorConfig config;
  std::string error;
  EXPECT_TRUE(config.Validate(&error)) << error;  // the markers are valid
  const EstimatorConfig derived = ResolveFromCalib(config, calib);
  EXPECT_EQ(derived.keyframe_every_scans, 4);
  EXPECT_EQ(derived.initial_keyframes, 48);  // 7.4 deg per scan: one turn, below the 160-keyframe window
  EXPECT_EQ(derived.features.range_sigma_m, 0.03);
  EXPECT_TRUE(derived.Validate(&error)) << error;
  config.keyframe_every_scans = 3;
  config.initial_keyframes = 0;
  config.features.range_sigma_m = 0.02;
  const EstimatorConfig kept = ResolveFromCalib(config, calib);
  EXPECT_EQ(kept.keyframe_every_scans, 3);
  EXPECT_EQ(kept.initial_keyframes, 0);
  EXPECT_EQ(kept.features.range_sigma_m, 0.02);
  config.keyframe_every_scans = -2;
  EXPECT_FALSE(config.Validate(&error));
  EXPECT_NE(error.find("keyframe_every_scans"), std::string::npos) << error;
}

// The registration's weak-direction gate is the LiDAR-inertial one unless the camera is fused.
TEST(ResolveFromCalib, TheCameraSetsTheWeakDirectionGate) {
  const RigCalib calib = Rotary(2.6, 600);
  EstimatorConfig config;
  config.registration.degeneracy.weak_gate_m = 0.08;
  config.visual.registration_weak_gate_m = 0.02;
  EXPECT_EQ(ResolveFromCalib(config, calib).registration.degeneracy.weak_gate_m, 0.08);
  config.visual.enabled = true;
  EXPECT_EQ(ResolveFromCalib(config, calib).registration.degeneracy.weak_gate_m, 0.02);
  config.visual.registration_weak_gate_m = 0.0;
  std::string error;
  EXPECT_FALSE(config.Validate(&error));
  EXPECT_NE(error.find("visual.registration_weak_gate_m"), std::string::npos) << error;
}

// Without the IMU the guess is the constant-twist extrapolation: the LiDAR-only gate replaces the weak-direction
// gate (the camera's, when it is on, still wins).
TEST(ResolveFromCalib, LidarOnlySetsTheWeakDirectionGate) {
  const RigCalib calib = Rotary(2.6, 600);
  EstimatorConfig config;
  config.registration.degeneracy.weak_gate_m = 0.08;
  config.lidar_only_weak_gate_m = 2.5;
  config.use_imu = false;
  EXPECT_EQ(ResolveFromCalib(config, calib).registration.degeneracy.weak_gate_m, 2.5);
  config.use_imu = true;
  EXPECT_EQ(ResolveFromCalib(config, calib).registration.degeneracy.weak_gate_m, 0.08);
  config.lidar_only_weak_gate_m = 0.0;
  std::string error;
  EXPECT_FALSE(config.Validate(&error));
  EXPECT_NE(error.find("lidar_only_weak_gate_m"), std::string::npos) << error;
}

// Without the IMU a turn's onset leaves the guess degrees off: the LiDAR-only rebuild cap replaces the
// registration's; with the IMU the registration's own stays. Bad values name their field.
TEST(ResolveFromCalib, LidarOnlySetsTheRebuildCap) {
  const RigCalib calib = Rotary(2.6, 600);
  EstimatorConfig config;
  config.registration.max_correspondence_rebuilds = 7;
  config.lidar_only_max_correspondence_rebuilds = 25;
  config.use_imu = false;
  EXPECT_EQ(ResolveFromCalib(config, calib).registration.max_correspondence_rebuilds, 25);
  config.use_imu = true;
  EXPECT_EQ(ResolveFromCalib(config, calib).registration.max_correspondence_rebuilds, 7);
  std::string error;
  config.lidar_only_max_correspondence_rebuilds = 0;
  EXPECT_FALSE(config.Validate(&error));
  EXPECT_NE(error.find("lidar_only_max_correspondence_rebuilds"), std::string::npos) << error;
  config.lidar_only_max_correspondence_rebuilds = 30;
  config.lidar_only_velocity_window_s = -0.1;
  EXPECT_FALSE(config.Validate(&error));
  EXPECT_NE(error.find("lidar_only_velocity_window_s"), std::string::npos) << error;
  config.lidar_only_velocity_window_s = 0.0;  // the last two scans' twist
  EXPECT_TRUE(config.Validate(&error)) << error;
}

}  // namespace
}  // namespace rotolidar
