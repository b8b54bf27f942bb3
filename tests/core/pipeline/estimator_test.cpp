// Estimator (core/pipeline/estimator.hpp) on synthetic, already-deskewed scans (ProcessDeskewedScan): a 64-ring
// lidar ray-cast analytically in a room with pillars, moved along a known path. Checks the pose chain, the map,
// the report fields and the config round trip. The full rotary + IMU chain runs in tests/scenario.
#include "core/pipeline/estimator.hpp"

#include <cmath>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "core/pipeline/estimator_config_yaml.hpp"

namespace rotolidar {
namespace {

struct Box {
  Eigen::Vector3d lo, hi;
};

/// Distance along a unit ray to the first surface: the room's inside walls or a solid box's outside.
double CastRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& room, const std::vector<Box>& solids) {
  double best = 1e9;
  for (int a = 0; a < 3; ++a) {  // room interior: exit distance
    if (std::abs(d[a]) < 1e-12) continue;
    const double t = ((d[a] > 0 ? room.hi[a] : room.lo[a]) - o[a]) / d[a];
    if (t > 0) best = std::min(best, t);
  }
  for (const Box& b : solids) {  // slab test: entry distance
    double t_in = -1e9, t_out = 1e9;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(d[a]) < 1e-12) {
        if (o[a] < b.lo[a] || o[a] > b.hi[a]) t_in = 1e9;
        continue;
      }
      double t0 = (b.lo[a] - o[a]) / d[a], t1 = (b.hi[a] - o[a]) / d[a];
      if (t0 > t1) std::swap(t0, t1);
      t_in = std::max(t_in, t0);
      t_out = std::min(t_out, t1);
    }
    if (t_in <= t_out && t_in > 0) best = std::min(best, t_in);
  }
  return best;
}

/// A KITTI-like 64-ring scan (elevations -24.9..+2 deg, 0.4 deg azimuth steps) from T_world_base, in the base
/// frame; the sensor sits at the base origin.
std::vector<ScanPoint> SyntheticScan(const Pose3& T_world_base, Seconds t_s) {
  const Box room{{-8, -6, -1.5}, {10, 7, 3.0}};
  const std::vector<Box> solids = {{{2, 1, -1.5}, {2.6, 1.6, 3.0}},   {{-4, -3, -1.5}, {-3.5, -2.2, 3.0}},
                                   {{5, -4, -1.5}, {6.5, -3.2, 0.5}}, {{-2, 3.5, -1.5}, {-1.2, 4.4, 1.0}},
                                   {{7, 4, -1.5}, {7.4, 4.4, 3.0}},   {{-6, 1, -1.5}, {-5.2, 1.5, 2.0}}};
  std::vector<ScanPoint> out;
  for (int ring = 0; ring < 64; ++ring) {
    const double el = (-24.9 + ring * 26.9 / 63.0) * M_PI / 180.0;
    for (int k = 0; k < 900; ++k) {
      const double az_deg = k * 0.4;
      const double az = az_deg * M_PI / 180.0;
      const Eigen::Vector3d d_base(std::cos(el) * std::cos(az), -std::cos(el) * std::sin(az), std::sin(el));
      const Eigen::Vector3d d_world = T_world_base.linear() * d_base;
      const double r = CastRay(T_world_base.translation(), d_world, room, solids);
      if (r > 60) continue;
      ScanPoint p;
      p.p_base = (r * d_base).cast<float>();
      p.range_m = float(r);
      p.azimuth_deg = float(az_deg);
      p.ring = uint8_t(ring);
      p.t_s = t_s + 0.1 * k / 900.0;
      out.push_back(p);
    }
  }
  return out;
}

Pose3 TruePose(double t) {  // 0.5 m/s forward with a slow yaw: the KITTI-style motion
  Pose3 T = Pose3::Identity();
  T.linear() = ExpSO3(Eigen::Vector3d(0, 0, 0.15 * t));
  T.translation() = Eigen::Vector3d(0.5 * t, 0.2 * std::sin(0.5 * t), 0.0);
  return T;
}

TEST(Estimator, DeskewedScansTrackAKnownPathLidarOnly) {
  RigCalib calib;
  calib.motor_speed_radps = 2.6;
  EstimatorConfig config;
  // A 64-ring full-revolution scan: LOAM's module defaults (4 planar points per cell) suffice and keep this fast.
  config.features = FeatureConfig();
  config.features.range_sigma_m = 0.0;  // noise-free ranges: no noise gate ...
  // ... and no noise growing with the incidence to weigh against (with the default weights, which only drop
  // information here: 2.03 mrad).
  config.registration.plane_incidence_exponent = 0.0;
  config.registration.num_neighbours = 5;
  Estimator estimator(calib, config);
  const Pose3 T0 = TruePose(0.0);
  std::vector<ScanReport> reports;
  for (int k = 0; k < 25; ++k) {
    const double t = 0.1 * k;
    reports.push_back(estimator.ProcessDeskewedScan(t, SyntheticScan(TruePose(t), t)));
  }
  ASSERT_EQ(estimator.trajectory().size(), 25u);
  double max_err_m = 0, max_err_rad = 0;
  for (int k = 0; k < 25; ++k) {
    const Pose3 truth = T0.inverse() * TruePose(0.1 * k);  // world = the base at the first scan
    const Pose3& est = estimator.trajectory()[k].T_ref_body;
    max_err_m = std::max(max_err_m, (est.translation() - truth.translation()).norm());
    max_err_rad = std::max(max_err_rad, LogSO3(est.linear().transpose() * truth.linear()).norm());
  }
  // Noise-free, exactly deskewed scans of planes and box edges: measured max error 6.6 mm / 1.3 mrad over 1.2 m
  // of travel (the 0.2 m map voxels' plane fits near the room's corners bias the planes slightly). 1.2 cm / 2 mrad
  // bounds; a frame or sign error gives decimetres.
  EXPECT_LT(max_err_m, 0.012);
  EXPECT_LT(max_err_rad, 2e-3);
  // Report fields: the first scan defines the map; later ones register and converge.
  EXPECT_FALSE(reports[0].registration.attempted);
  for (int k = 1; k < 25; ++k) {
    EXPECT_TRUE(reports[k].registration.attempted) << k;
    EXPECT_TRUE(reports[k].registration.converged) << k << ": " << reports[k].registration.message;
    EXPECT_GT(reports[k].features.planar, 100u);
    EXPECT_FALSE(reports[k].imu_initialized);
    EXPECT_GE(reports[k].timings.total_ms, reports[k].timings.register_ms);
    EXPECT_GT(reports[k].registration.hessian_eigenvalues.minCoeff(), 0.0);
  }
  // The dense map lags free_space.delay_s (2.5 s) behind the scans: this 2.4 s run is all still waiting.
  EXPECT_EQ(estimator.map().NumPoints(), 0u);
  const FreeSpaceCounts flushed = estimator.FlushMap();
  EXPECT_GT(flushed.judged, 10000u);
  // A static room: only depth edges (a box's rim against the wall behind, its 3x3 bins mostly beyond) can be
  // called seen through. Measured: 50 of 178795; the bound is 1 %.
  EXPECT_LT(flushed.dynamic, flushed.judged / 100) << "of " << flushed.judged;
  std::printf("free space: %zu of %zu judged points dynamic\n", flushed.dynamic, flushed.judged);
  EXPECT_GT(estimator.map().NumPoints(), 10000u);
}

TEST(Estimator, KeyframesEveryScanWhileYoungThenEveryNth) {
  RigCalib calib;
  EstimatorConfig config;
  config.features = FeatureConfig();
  config.features.range_sigma_m = 0.0;
  config.initial_keyframes = 4;
  config.keyframe_every_scans = 3;
  Estimator estimator(calib, config);
  std::vector<bool> keyframe;
  for (int k = 0; k < 12; ++k) {  // 5 cm and 0.9 deg per scan: the local map's own distance / angle rule is silent
    const double t = 0.1 * k;
    keyframe.push_back(estimator.ProcessDeskewedScan(t, SyntheticScan(TruePose(t), t)).keyframe);
  }
  const std::vector<bool> expected = {true, true, true, true, false, false, true, false, false, true, false, false};
  EXPECT_EQ(keyframe, expected);
}

TEST(Estimator, KeepDeskewedCarriesNothingForDeskewedInput) {
  RigCalib calib;
  EstimatorConfig config;
  config.keep_deskewed = true;
  Estimator estimator(calib, config);
  const ScanReport r = estimator.ProcessDeskewedScan(0.0, SyntheticScan(Pose3::Identity(), 0.0));
  // ProcessDeskewedScan skips the deskew stage: no decoded points to carry.
  EXPECT_TRUE(r.deskew_source.empty());
  EXPECT_TRUE(r.deskewed_base.empty());
  EXPECT_EQ(r.timings.deskew_ms, 0.0);
  EXPECT_GT(r.num_points, 30000u);
}

TEST(EstimatorConfig, YamlRoundTripAndStrictKeys) {
  EstimatorConfig c;
  c.lidar_point_sigma_m = 0.07;
  c.features.sectors = 8;
  c.registration.loss = RobustLoss::kCauchy;
  c.window.marginalization = MarginalizationScheme::kDropOldest;
  c.window.estimate_gravity = false;
  c.window.gravity_random_walk_rad_per_sqrt_s = 2e-3;
  c.keep_deskewed = true;
  YAML::Emitter out;
  EmitEstimatorConfig(out, c);
  EstimatorConfig back;
  ASSERT_TRUE(ParseEstimatorConfig("test.yaml", YAML::Load(out.c_str()), &back));
  EXPECT_EQ(back.lidar_point_sigma_m, 0.07);
  EXPECT_EQ(back.features.sectors, 8);
  EXPECT_EQ(back.registration.loss, RobustLoss::kCauchy);
  EXPECT_EQ(back.window.marginalization, MarginalizationScheme::kDropOldest);
  EXPECT_FALSE(back.window.estimate_gravity);
  EXPECT_EQ(back.window.gravity_random_walk_rad_per_sqrt_s, 2e-3);
  EXPECT_TRUE(back.keep_deskewed);
  YAML::Emitter again;
  EmitEstimatorConfig(again, back);
  EXPECT_EQ(std::string(out.c_str()), std::string(again.c_str()));

  EstimatorConfig d;
  const Status unknown = ParseEstimatorConfig("f.yaml", YAML::Load("features: {sectorz: 3}"), &d);
  EXPECT_FALSE(unknown);
  EXPECT_NE(unknown.message.find("sectorz"), std::string::npos) << unknown.message;
  const Status bad_enum = ParseEstimatorConfig("f.yaml", YAML::Load("registration: {loss: l2}"), &d);
  EXPECT_FALSE(bad_enum);
  EXPECT_NE(bad_enum.message.find("huber"), std::string::npos) << bad_enum.message;
  const Status invalid = ParseEstimatorConfig("f.yaml", YAML::Load("lidar_point_sigma_m: -1"), &d);
  EXPECT_FALSE(invalid);
}

}  // namespace
}  // namespace rotolidar
