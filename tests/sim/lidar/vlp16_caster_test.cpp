// Simulated VLP-16: schedule, noise-free ranges against analytic geometry, azimuths the decoder's interpolation
// reproduces, seeded determinism, grazing/range cut-offs, the reflectivity model, the beam footprint (mixed edge
// points, dual returns), glass transmission, pose interpolation, and the position packet source.
#include <algorithm>
#include <cmath>
#include <iostream>

#include <gtest/gtest.h>

#include "sim/lidar/position_source.hpp"
#include "sim/lidar/vlp16_caster.hpp"
#include "tests/sim/lidar/lidar_fixtures.hpp"
#include "tests/sim/world/world_fixtures.hpp"

namespace rotolidar::sim {
namespace {

using namespace lidar_test;


/// Exit distance of a ray from inside the plain room's box [-5,5]x[-4,4]x[0,3], and the wall's axis.
double RoomExit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, int* axis) {
  const Eigen::Vector3d lo(-5, -4, 0), hi(5, 4, 3);
  double best = 1e9;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) continue;
    const double t = ((d[k] > 0 ? hi[k] : lo[k]) - o[k]) / d[k];
    if (t < best) best = t, *axis = k;
  }
  return best;
}

TEST(Vlp16Caster, FiringTimesFollowTheSchedule) {
  const auto es = testing::MakeEmbree(testing::PlainRoom());
  Vlp16CasterConfig config = NoiseFree();
  config.t0_s = 12.5;
  Vlp16Caster caster(*es, LidarIntrinsics{}, config, 1);
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<LidarTruthPoint> truth;
  const auto pose = [](Seconds) { return Static({0, 0, 1.5}); };
  caster.Fire(300, pose, &seqs, &truth);
  caster.Fire(200, pose, &seqs, &truth);  // continues the schedule
  ASSERT_EQ(seqs.size(), 500u);
  ASSERT_EQ(truth.size(), 500u * 16);
  for (size_t k = 0; k < seqs.size(); ++k) {
    EXPECT_NEAR(seqs[k].t_s, 12.5 + k * 55.296e-6, 1e-12);
    for (int i = 0; i < 16; ++i) {
      const LidarTruthPoint& p = truth[k * 16 + i];
      EXPECT_EQ(p.laser_id, i);
      EXPECT_NEAR(p.t_s, 12.5 + k * 55.296e-6 + i * 2.304e-6, 1e-12);
    }
    if (k > 0) {  // 600 rpm: 0.19906 deg per sequence, rounded to 0.01 deg
      const int step = (seqs[k].azimuth_centideg - seqs[k - 1].azimuth_centideg + 36000) % 36000;
      EXPECT_NEAR(step, 19.906, 1.0);
    }
  }
}

TEST(Vlp16Caster, NoiseFreeRangesMatchAnalyticWalls) {
  const Scene room = testing::PlainRoom();
  const auto es = testing::MakeEmbree(room);
  Vlp16Caster caster(*es, LidarIntrinsics{}, NoiseFree(), 1);
  // Moving and turning: each ray must use the pose at its own firing time.
  const auto pose = [](Seconds t) {
    Pose3 T = Static({0.5 + 2.0 * t, -0.3 + 0.5 * t, 1.2});
    T.linear() = (Eigen::AngleAxisd(3.0 * t, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX())).toRotationMatrix();
    return T;
  };
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<LidarTruthPoint> truth;
  caster.Fire(3000, pose, &seqs, &truth);
  const LidarIntrinsics intr;
  int returned = 0;
  for (size_t r = 0; r < truth.size(); ++r) {
    const Vlp16FiringSequence& seq = seqs[r / 16];
    const int i = static_cast<int>(r % 16);
    const Pose3 T = pose(truth[r].t_s);
    const Eigen::Vector3d o = T * Vlp16RayOrigin(intr.vertical_offset_m[i]);
    const Eigen::Vector3d d = (truth[r].p_world - o).normalized();
    int axis = 0;
    const double analytic_m = RoomExit(o, d, &axis);
    ASSERT_TRUE(truth[r].hit);
    // Float ray casting is good to ~1e-5 m; the truth range must agree with the analytic wall distance.
    EXPECT_NEAR(truth[r].true_range_m, analytic_m, 2e-5);
    if (seq.distance_2mm[i] == 0) continue;
    ++returned;
    // 2 mm quantisation: rounding error <= 1 mm, plus the float error.
    EXPECT_NEAR(seq.distance_2mm[i] * 0.002, analytic_m, 0.001 + 2e-5);
    // Reflectivity: round(100 * albedo * cos(incidence) * exp(-0.004 r)); +-1 for rounding at float precision.
    const double albedo = (axis == 2 && d.z() < 0) ? 0.3 : 0.8;
    const double expected = 100.0 * albedo * std::abs(d[axis]) * std::exp(-0.004 * analytic_m);
    EXPECT_NEAR(seq.reflectivity[i], expected, 1.0);
    EXPECT_EQ(seq.distance2_2mm[i], seq.distance_2mm[i]);
  }
  // Everything in a closed room returns except grazing hits near corners and the floor far away.
  EXPECT_GT(returned, static_cast<int>(truth.size() * 0.9));
}

TEST(Vlp16Caster, AzimuthsAreReproducedByDecoderInterpolation) {
  const auto es = testing::MakeEmbree(testing::PlainRoom());
  Vlp16CasterConfig config = NoiseFree();
  config.azimuth0_deg = 359.0;  // wraps through 0
  config.rpm = 900.0;
  Vlp16Caster caster(*es, LidarIntrinsics{}, config, 1);
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<LidarTruthPoint> truth;
  const Eigen::Vector3d p0(0.2, 0.1, 1.5);
  caster.Fire(400, [&](Seconds) { return Static(p0); }, &seqs, &truth);
  const LidarIntrinsics intr;
  for (size_t k = 0; k + 1 < seqs.size(); ++k) {
    const double d_az = (seqs[k + 1].azimuth_centideg - seqs[k].azimuth_centideg + 36000) % 36000;
    for (int i = 0; i < 16; ++i) {
      // The ROS velodyne driver's per-firing azimuth interpolation, then the shared ray geometry.
      const double az_rad = (seqs[k].azimuth_centideg + d_az * i * 2.304 / 55.296) * 0.01 * kDeg;
      const double range_m = seqs[k].distance_2mm[i] * 0.002;
      if (range_m == 0.0) continue;
      const Eigen::Vector3d p = p0 + Vlp16RayOrigin(intr.vertical_offset_m[i]) +
                                range_m * Vlp16RayDirection(intr.elevation_deg[i] * kDeg, az_rad);
      // 1 mm range rounding + azimuth rounding (<= 0.005 deg at laser 0, interpolated) x <= 6.5 m = 0.6 mm.
      EXPECT_LT((p - truth[k * 16 + i].p_world).norm(), 0.002) << "seq " << k << " laser " << i;
    }
  }
}

TEST(Vlp16Caster, SameSeedIdenticalDifferentSeedDiffers) {
  Scene scene;
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &scene).ok);
  const auto es = testing::MakeEmbree(scene);
  Vlp16CasterConfig config;  // default 3 cm noise
  config.rpm_jitter_frac = 0.01;
  const auto pose = [](Seconds t) { return Static({0.3 * t, 0.0, 1.4}); };
  auto run = [&](uint64_t seed) {
    Vlp16Caster caster(*es, LidarIntrinsics{}, config, seed);
    std::vector<Vlp16FiringSequence> seqs;
    caster.Fire(1000, pose, &seqs, nullptr);
    return seqs;
  };
  const auto a = run(42), b = run(42), c = run(43);
  ASSERT_EQ(a.size(), b.size());
  int differing = 0, total = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].distance_2mm, b[k].distance_2mm);
    EXPECT_EQ(a[k].reflectivity, b[k].reflectivity);
    EXPECT_EQ(a[k].azimuth_centideg, b[k].azimuth_centideg);
    for (int i = 0; i < 16; ++i, ++total) differing += a[k].distance_2mm[i] != c[k].distance_2mm[i];
  }
  // sigma = 3 cm = 15 quantisation steps: two seeds agree on a step rarely (~2 %).
  EXPECT_GT(differing, total * 0.8);
}

TEST(Vlp16Caster, GrazingRaysGiveNoReturn) {
  const auto es = testing::MakeEmbree(testing::BigFloor());
  for (double cutoff_deg : {85.0, 89.5}) {
    Vlp16CasterConfig config = NoiseFree();
    config.grazing_cutoff_deg = cutoff_deg;
    Vlp16Caster caster(*es, LidarIntrinsics{}, config, 1);
    std::vector<Vlp16FiringSequence> seqs;
    std::vector<LidarTruthPoint> truth;
    caster.Fire(200, [](Seconds) { return Static({0, 0, 0.5}); }, &seqs, &truth);
    const LidarIntrinsics intr;
    for (const LidarTruthPoint& p : truth) {
      const double elev = intr.elevation_deg[p.laser_id];
      const double incidence_deg = 90.0 + elev;  // a level head over a level floor
      if (elev > 0) {
        EXPECT_FALSE(p.hit);
      } else if (std::abs(incidence_deg - cutoff_deg) > 0.5) {
        // e = -1 deg hits at 28.6 m with 89 deg incidence, -3 deg at 9.5 m with 87 deg.
        EXPECT_TRUE(p.hit);
        EXPECT_EQ(p.returned, incidence_deg < cutoff_deg) << "elev " << elev << " cutoff " << cutoff_deg;
      }
    }
  }
}

TEST(Vlp16Caster, RangeLimitsDropReturns) {
  const auto es = testing::MakeEmbree(testing::PlainRoom());
  Vlp16CasterConfig config = NoiseFree();
  config.max_range_m = 3.0;
  Vlp16Caster caster(*es, LidarIntrinsics{}, config, 1);
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<LidarTruthPoint> truth;
  caster.Fire(2000, [](Seconds) { return Static({4.7, 0.0, 1.5}); }, &seqs, &truth);  // 0.3 m from a wall
  int too_close = 0, too_far = 0, ok = 0;
  for (size_t r = 0; r < truth.size(); ++r) {
    const uint16_t d = seqs[r / 16].distance_2mm[r % 16];
    EXPECT_EQ(d != 0, truth[r].returned);
    if (!truth[r].hit) {
      ++too_far;  // nothing within the 3 m cast
      EXPECT_EQ(d, 0);
    } else if (truth[r].true_range_m < 0.4) {
      ++too_close;
      EXPECT_EQ(d, 0);
    } else if (d != 0) {
      ++ok;
      EXPECT_LE(d * 0.002, 3.0 + 0.001);
    }
  }
  EXPECT_GT(too_close, 100);
  EXPECT_GT(too_far, 100);
  EXPECT_GT(ok, 100);
}

TEST(Vlp16Caster, RetroreflectiveSignReadsAbove100) {
  Scene scene;
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &scene).ok);
  const auto es = testing::MakeEmbree(scene);
  Vlp16Caster caster(*es, LidarIntrinsics{}, NoiseFree(), 1);
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<LidarTruthPoint> truth;
  caster.Fire(1900, [](Seconds) { return Static({3.5, 0.5, 1.8}); }, &seqs, &truth);  // > 1 revolution
  int on_sign = 0;
  for (size_t r = 0; r < truth.size(); ++r) {
    if (!truth[r].returned) continue;
    const Eigen::Vector3d& p = truth[r].p_world;
    // The sign: x = 4.98, y in 0.5 +- 0.3, z in 1.8 +- 0.2.
    const bool sign = std::abs(p.x() - 4.98) < 1e-4 && std::abs(p.y() - 0.5) < 0.3 && std::abs(p.z() - 1.8) < 0.2;
    const uint8_t byte = seqs[r / 16].reflectivity[r % 16];
    EXPECT_EQ(byte > 100, sign) << "point " << p.transpose() << " byte " << int(byte);
    on_sign += sign;
  }
  EXPECT_GT(on_sign, 50);
}

TEST(Vlp16CasterConfig, ValidateNamesTheField) {
  std::string error;
  EXPECT_TRUE(Vlp16CasterConfig{}.Validate(&error)) << error;
  Vlp16CasterConfig c;
  c.max_range_m = 200.0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("max_range_m"), std::string::npos);
  c = Vlp16CasterConfig{};
  c.rpm = -1;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("rpm"), std::string::npos);
}

}  // namespace
}  // namespace rotolidar::sim
