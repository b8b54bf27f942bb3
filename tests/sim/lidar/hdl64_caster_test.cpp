// Simulated HDL-64E: the elevation table, ray directions of the measured points, ranges to a known plane within
// the noise, per-point times spanning one revolution in firing order, per-point poses, seeded determinism.
#include <algorithm>
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "sim/lidar/hdl64_caster.hpp"
#include "tests/sim/world/world_fixtures.hpp"

namespace rotolidar::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kHeightM = 1.73;  // KITTI's Velodyne above the road

Pose3 At(const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.translation() = t;
  return T;
}

/// Geometry only: no grazing cut-off and no reflectance threshold, so that every ray meeting the floor within
/// max_range_m gives a point.
Hdl64CasterConfig Config(double sigma_m, int firings = 720) {
  Hdl64CasterConfig c;
  c.range_noise_sigma_m = sigma_m;
  c.grazing_cutoff_deg = 90.0;
  c.min_reflectance = 0.0;
  c.firings_per_revolution = firings;
  return c;
}

std::vector<Hdl64Point> OneRevolution(const Scene& scene, const Hdl64CasterConfig& config, uint64_t seed,
                                      const std::function<Pose3(Seconds)>& pose) {
  auto es = testing::MakeEmbree(scene);
  Hdl64Caster caster(es.get(), config, seed);
  std::vector<Hdl64Point> points;
  caster.Revolution(0.0, pose, &points);
  return points;
}

TEST(Hdl64Caster, ElevationTableIsKittisLayout) {
  EXPECT_DOUBLE_EQ(Hdl64ElevationDeg(0), 2.0);
  EXPECT_NEAR(Hdl64ElevationDeg(31), -8.33, 0.005);
  EXPECT_DOUBLE_EQ(Hdl64ElevationDeg(32), -8.83);
  EXPECT_DOUBLE_EQ(Hdl64ElevationDeg(63), -24.33);
  for (int i = 1; i < kHdl64Lasers; ++i) {
    const double step = Hdl64ElevationDeg(i - 1) - Hdl64ElevationDeg(i);
    // 1/3 deg in the upper block, 1/2 in the lower, 0.497 deg between the blocks
    EXPECT_NEAR(step, i < 32 ? 1.0 / 3.0 : (i == 32 ? 8.83 - (31.0 / 3.0 - 2.0) : 0.5), 1e-9) << "laser " << i;
    const Eigen::Vector3d d = Hdl64Caster::RayDirection(i, 1.234);
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    EXPECT_NEAR(std::asin(d.z()) / kDeg, Hdl64ElevationDeg(i), 1e-9);
    EXPECT_NEAR(std::atan2(d.y(), d.x()), 1.234, 1e-12);  // counter-clockwise azimuth
  }
}

// Noise-free, standing 1.73 m above a 400 x 400 m floor: every point lies on its laser's ray (elevation from the
// table, azimuth = column * 360 / firings) at the analytic range 1.73 / sin(-elevation); the points come laser by
// laser (top first), each laser's times rising from 0 through one revolution.
TEST(Hdl64Caster, NoiseFreePointsLieOnTheirRaysAtThePlaneRange) {
  const Hdl64CasterConfig config = Config(0.0);
  const auto points = OneRevolution(testing::BigFloor(), config, 1, [](Seconds) { return At({0, 0, kHeightM}); });
  ASSERT_FALSE(points.empty());
  const double dt = 0.1 / config.firings_per_revolution;
  int lasers_seen = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Hdl64Point& p = points[i];
    const Eigen::Vector3d x(p.x_m, p.y_m, p.z_m);
    const double elevation = Hdl64ElevationDeg(p.laser);
    // float storage: ~1e-7 relative, so 1e-4 deg of direction at any range
    EXPECT_NEAR(std::asin(x.z() / x.norm()) / kDeg, elevation, 1e-4);
    const long column = std::lround(p.t_s / dt);
    EXPECT_NEAR(p.t_s, column * dt, 1e-7);
    double az = std::atan2(x.y(), x.x()) / kDeg;
    if (az < -1e-3) az += 360.0;
    EXPECT_NEAR(az, column * 360.0 / config.firings_per_revolution, 1e-3);
    EXPECT_NEAR(x.norm(), kHeightM / std::sin(-elevation * kDeg), 2e-5 * x.norm());  // float + Embree precision
    if (i == 0 || points[i - 1].laser != p.laser) {
      ++lasers_seen;
      if (i > 0) {
        EXPECT_GT(p.laser, points[i - 1].laser);
      }
    } else {
      EXPECT_GT(p.t_s, points[i - 1].t_s);
    }
    EXPECT_GE(p.t_s, 0.f);
    EXPECT_LT(p.t_s, 0.1f);
  }
  // Lasers at or above the horizon see nothing; those below -0.83 deg reach the floor within 120 m (the first
  // below is -0.33 deg: 300 m): lasers 9 (-1.0 deg) .. 63 give points, each a full revolution.
  EXPECT_EQ(lasers_seen, 55);
  EXPECT_EQ(points.size(), 55u * size_t(config.firings_per_revolution));
  EXPECT_EQ(points.front().t_s, 0.f);
  EXPECT_NEAR(points.back().t_s, 0.1 - dt, 1e-7);
}

// With 2 cm noise the range error to the plane has mean ~0 and standard deviation ~2 cm: 39,600 points, so the
// mean's standard error is 1e-4 m and the sample sigma's about 0.4 %; bounds at >= 5 standard errors.
TEST(Hdl64Caster, RangeNoiseMatchesItsSigma) {
  const Hdl64CasterConfig config = Config(0.02);
  const auto points = OneRevolution(testing::BigFloor(), config, 3, [](Seconds) { return At({0, 0, kHeightM}); });
  double sum = 0, sum2 = 0;
  for (const Hdl64Point& p : points) {
    const double e = Eigen::Vector3d(p.x_m, p.y_m, p.z_m).norm() - kHeightM / std::sin(-Hdl64ElevationDeg(p.laser) * kDeg);
    sum += e;
    sum2 += e * e;
  }
  const double n = double(points.size());
  ASSERT_GT(n, 30000);
  EXPECT_NEAR(sum / n, 0.0, 6e-4);
  EXPECT_NEAR(std::sqrt(sum2 / n - (sum / n) * (sum / n)), 0.02, 0.0005);
}

// Driving at 10 m/s while turning at 1 rad/s: a noise-free point moved into the world with the pose at its own
// firing time lies on the floor (z = 0), while the frame-start pose misplaces points of late columns by
// decimetres. That is the raw (not motion-compensated) convention of the bins.
TEST(Hdl64Caster, EachPointIsMeasuredFromThePoseAtItsFiringTime) {
  const auto pose = [](Seconds t) {
    Pose3 T = At({10.0 * t, 0, kHeightM});
    T.linear() = Eigen::AngleAxisd(1.0 * t, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    return T;
  };
  const auto points = OneRevolution(testing::BigFloor(), Config(0.0), 1, pose);
  double worst_own = 0, worst_start = 0;
  for (const Hdl64Point& p : points) {
    const Eigen::Vector3d x(p.x_m, p.y_m, p.z_m);
    worst_own = std::max(worst_own, std::abs((pose(p.t_s) * x).z()));
    worst_start = std::max(worst_start, (pose(p.t_s) * x - pose(0.0) * x).norm());
  }
  EXPECT_LT(worst_own, 1e-4 * 120.0);  // float storage of up to 120 m ranges
  EXPECT_GT(worst_start, 0.5);         // ~1 m of travel and 0.1 rad of turn over the revolution
}

TEST(Hdl64Caster, SameSeedSameBytesOtherSeedOtherBytes) {
  const auto pose = [](Seconds t) { return At({5.0 * t, 0, kHeightM}); };
  const auto a = OneRevolution(testing::RoomWithCar(), Config(0.02), 7, pose);
  const auto b = OneRevolution(testing::RoomWithCar(), Config(0.02), 7, pose);
  const auto c = OneRevolution(testing::RoomWithCar(), Config(0.02), 8, pose);
  const auto same = [](const std::vector<Hdl64Point>& x, const std::vector<Hdl64Point>& y) {
    if (x.size() != y.size()) return false;
    for (size_t i = 0; i < x.size(); ++i) {  // field by field: the struct has padding
      const float fx[5] = {x[i].x_m, x[i].y_m, x[i].z_m, x[i].reflectance, x[i].t_s};
      const float fy[5] = {y[i].x_m, y[i].y_m, y[i].z_m, y[i].reflectance, y[i].t_s};
      if (std::memcmp(fx, fy, sizeof(fx)) != 0 || x[i].laser != y[i].laser) return false;
    }
    return true;
  };
  ASSERT_FALSE(a.empty());
  EXPECT_TRUE(same(a, b));
  EXPECT_FALSE(same(a, c));
}

// An intrinsic vertical-angle error reports every point 0.22 deg above its laser's elevation at the true range:
// flat ground then reads as a cone (a laser at -10 deg sees the floor 1.73 / sin(10 deg) away but reports it
// 3.8 cm higher).
TEST(Hdl64Caster, ElevationErrorTiltsTheReportedPoints) {
  Hdl64CasterConfig config = Config(0.0);
  config.elevation_error_deg = 0.22;
  const auto points = OneRevolution(testing::BigFloor(), config, 1, [](Seconds) { return At({0, 0, kHeightM}); });
  ASSERT_EQ(points.size(), 55u * size_t(config.firings_per_revolution));  // the same rays hit as without it
  for (const Hdl64Point& p : points) {
    const Eigen::Vector3d x(p.x_m, p.y_m, p.z_m);
    const double elevation = Hdl64ElevationDeg(p.laser);
    ASSERT_NEAR(std::asin(x.z() / x.norm()) / kDeg, elevation + 0.22, 1e-4);
    ASSERT_NEAR(x.norm(), kHeightM / std::sin(-elevation * kDeg), 2e-5 * x.norm());
  }
}

TEST(Hdl64Caster, ValidateNamesTheField) {
  std::string error;
  Hdl64CasterConfig c;
  EXPECT_TRUE(c.Validate(&error));
  c.firings_per_revolution = 10;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("firings_per_revolution"), std::string::npos);
  c = Hdl64CasterConfig();
  c.max_range_m = 0.5;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("max_range_m"), std::string::npos);
}

}  // namespace
}  // namespace rotolidar::sim
