// The yaw-invariant Scan Context descriptor and the place index on ray-cast synthetic scenes: a street with
// building facades, poles, trees and parked cars, and an indoor hall with pillars and shelves. Scans are full-sphere
// (a rotary rig), ray-cast with occlusion, range noise from RandomStream, in the gravity-aligned keyframe frame.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/loop/lidar_descriptor.hpp"
#include "core/types/geometry.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::loop {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDeg = M_PI / 180.0;
constexpr double kSectorRad = 2.0 * M_PI / 60.0;  // default sector width: the yaw resolution

struct Box {
  Eigen::Vector3d lo, hi;
};
struct Cylinder {
  double x, y, r, z0, z1;
};
/// Ground at z = 0, an optional ceiling, boxes and vertical cylinders (world frame, metres).
struct Scene {
  std::vector<Box> boxes;
  std::vector<Cylinder> cylinders;
  double ceiling_z = kInf;
};

double HitBox(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t0 = 0.0, t1 = kInf;
  for (int i = 0; i < 3; ++i) {
    const double inv = 1.0 / d[i];
    double a = (b.lo[i] - o[i]) * inv, c = (b.hi[i] - o[i]) * inv;
    if (a > c) std::swap(a, c);
    t0 = std::max(t0, a), t1 = std::min(t1, c);
    if (t0 > t1) return kInf;
  }
  return t0 > 0.0 ? t0 : kInf;
}

double HitCylinder(const Cylinder& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const double ox = o.x() - c.x, oy = o.y() - c.y;
  const double a = d.x() * d.x() + d.y() * d.y(), b = 2 * (ox * d.x() + oy * d.y());
  const double disc = b * b - 4 * a * (ox * ox + oy * oy - c.r * c.r);
  if (a < 1e-12 || disc < 0) return kInf;
  const double t = (-b - std::sqrt(disc)) / (2 * a);
  const double z = o.z() + t * d.z();
  return (t > 0 && z >= c.z0 && z <= c.z1) ? t : kInf;
}

/// A full-sphere scan from T_world_kf (gravity-aligned: yaw only): elevation -85..85 deg every 1.5 deg, azimuth
/// every 1 deg with a random start, 60 m max range, 2 cm range noise. Points in the keyframe frame.
std::vector<Eigen::Vector3f> Scan(const Scene& scene, const Pose3& T_world_kf, RandomStream* rng) {
  const Eigen::Vector3d o = T_world_kf.translation();
  constexpr double kMaxRange = 60.0;
  Scene near;  // primitives that a ray can reach
  near.ceiling_z = scene.ceiling_z;
  for (const Box& b : scene.boxes) {
    const Eigen::Vector3d closest = o.cwiseMax(b.lo).cwiseMin(b.hi);
    if ((closest - o).norm() < kMaxRange) near.boxes.push_back(b);
  }
  for (const Cylinder& c : scene.cylinders)
    if (std::hypot(c.x - o.x(), c.y - o.y()) < kMaxRange + c.r) near.cylinders.push_back(c);
  std::vector<Eigen::Vector3f> points;
  const double az0 = rng->Uniform() * kDeg;
  for (double el = -85 * kDeg; el <= 85.01 * kDeg; el += 1.5 * kDeg) {
    for (double az = az0; az < 2 * M_PI; az += kDeg) {
      const Eigen::Vector3d d_kf(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const Eigen::Vector3d d = T_world_kf.linear() * d_kf;
      double t = kMaxRange;
      if (d.z() < 0) t = std::min(t, -o.z() / d.z());
      if (d.z() > 0) t = std::min(t, (near.ceiling_z - o.z()) / d.z());
      for (const Box& b : near.boxes) t = std::min(t, HitBox(b, o, d));
      for (const Cylinder& c : near.cylinders) t = std::min(t, HitCylinder(c, o, d));
      if (t >= kMaxRange) continue;
      points.push_back(((t + rng->Normal(0.0, 0.02)) * d_kf).cast<float>());
    }
  }
  return points;
}

/// A 300 m street along x (y = 0 in the middle): facades of random setback/height/length with alleys, poles,
/// trees and parked cars on both sides.
Scene Street(uint64_t seed) {
  RandomStream rng(seed, "street-scene");
  Scene s;
  for (const double side : {-1.0, 1.0}) {
    for (double x = -40; x < 260;) {
      const double len = 6 + 14 * rng.Uniform(), setback = 3 * rng.Uniform(), height = 4 + 21 * rng.Uniform();
      const double y_near = side * (7 + setback), y_far = side * (19 + setback);
      s.boxes.push_back({{x, std::min(y_near, y_far), 0}, {x + len, std::max(y_near, y_far), height}});
      x += len + (rng.Uniform() < 0.3 ? 3 + 5 * rng.Uniform() : 0.0);
    }
    for (double x = -40; x < 260; x += 10 + 8 * rng.Uniform())  // poles
      s.cylinders.push_back({x, side * 6.2, 0.15, 0, 6});
    for (double x = -40; x < 260; x += 8 + 10 * rng.Uniform())  // trees
      s.cylinders.push_back({x, side * (5.2 + rng.Uniform()), 0.3 + 0.3 * rng.Uniform(), 0, 3 + 6 * rng.Uniform()});
    for (double x = -40; x < 260; x += 6 + 15 * rng.Uniform()) {  // parked cars
      const double y = side * (3.5 + rng.Uniform());
      s.boxes.push_back({{x, y - 0.9, 0}, {x + 4.2, y + 0.9, 1.5}});
    }
  }
  return s;
}

/// A 40 x 26 m hall, 4.5 m ceiling, pillars on an 8 m grid, random shelves and crates.
Scene Hall(uint64_t seed) {
  RandomStream rng(seed, "hall-scene");
  Scene s;
  s.ceiling_z = 4.5;
  s.boxes.push_back({{-20.5, -13.5, 0}, {-20, 13.5, 4.5}});
  s.boxes.push_back({{20, -13.5, 0}, {20.5, 13.5, 4.5}});
  s.boxes.push_back({{-20, -13.5, 0}, {20, -13, 4.5}});
  s.boxes.push_back({{-20, 13, 0}, {20, 13.5, 4.5}});
  for (double x = -16; x <= 16; x += 8)
    for (double y = -8; y <= 8; y += 8) s.boxes.push_back({{x - 0.25, y - 0.25, 0}, {x + 0.25, y + 0.25, 4.5}});
  for (int i = 0; i < 14; ++i) {
    const double x = -18 + 33 * rng.Uniform(), y = -11 + 20 * rng.Uniform();
    const bool along_x = rng.Uniform() < 0.5;
    const double lx = along_x ? 3 + 4 * rng.Uniform() : 0.8, ly = along_x ? 0.8 : 3 + 4 * rng.Uniform();
    s.boxes.push_back({{x, y, 0}, {x + lx, y + ly, 0.6 + 2.4 * rng.Uniform()}});
  }
  return s;
}

Pose3 KeyframePose(double x, double y, double z, double yaw_rad) {
  Pose3 T = RotZ(yaw_rad);
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

double WrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

template <typename F>
double MillisecondsOf(F&& f, int repeats = 1) {
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < repeats; ++i) f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / repeats;
}

TEST(LidarDescriptorConfig, ValidatesEveryField) {
  std::string error;
  EXPECT_TRUE(LidarDescriptorConfig{}.Validate(&error)) << error;
  LidarDescriptorConfig c;
  c.num_rings = 0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("num_rings"), std::string::npos);
  c = {};
  c.max_radius_m = -1;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("max_radius_m"), std::string::npos);
  c = {};
  c.max_z_m = c.min_z_m;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("max_z_m"), std::string::npos);
  c = {};
  c.num_height_bands = 33;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("num_height_bands"), std::string::npos);
}

using CellValue = LidarDescriptorConfig::CellValue;

LidarDescriptorConfig ConfigWith(CellValue value) {
  LidarDescriptorConfig c;
  c.cell_value = value;
  return c;
}

const char* Name(CellValue v) { return v == CellValue::kHeightBands ? "height-bands" : "max-height"; }

class DescriptorPlaces : public ::testing::TestWithParam<CellValue> {};

TEST_P(DescriptorPlaces, RevisitWithYawAndOffsetMatchesAndAFarPlaceDoesNot) {
  const LidarDescriptorConfig config = ConfigWith(GetParam());
  const Scene street = Street(7);
  RandomStream rng(11, "descriptor-places");
  // b revisits a 0.5 m away with the sensor turned by 73 deg; c is 20 m down the street; d is in a hall.
  const Pose3 T_w_a = KeyframePose(60, 0.3, 1.8, 10 * kDeg);
  const Pose3 T_w_b = KeyframePose(60.3, 0.7, 1.8, 83 * kDeg);
  const Pose3 T_w_c = KeyframePose(80, 0.3, 1.8, 10 * kDeg);
  const std::vector<Eigen::Vector3f> scan_a = Scan(street, T_w_a, &rng);
  LidarDescriptor a;
  const double compute_ms = MillisecondsOf([&] { a = ComputeLidarDescriptor(scan_a, config); }, 20);
  const LidarDescriptor b = ComputeLidarDescriptor(Scan(street, T_w_b, &rng), config);
  const LidarDescriptor c = ComputeLidarDescriptor(Scan(street, T_w_c, &rng), config);
  const LidarDescriptor d = ComputeLidarDescriptor(Scan(Hall(3), KeyframePose(2, 1, 1.5, 0), &rng), config);
  DescriptorMatch same;
  const double full_ms = MillisecondsOf([&] { same = DescriptorDistance(a, b); }, 200);
  DescriptorMatch fast;
  const double fast_ms = MillisecondsOf([&] { fast = DescriptorDistance(a, b, ShiftSearch{2}); }, 200);
  const DescriptorMatch far = DescriptorDistance(a, c), other_scene = DescriptorDistance(a, d);
  std::printf("[%s] %zu points: compute %.3f ms; distance full search %.4f ms, coarse-to-fine %.4f ms\n",
              Name(GetParam()), scan_a.size(), compute_ms, full_ms, fast_ms);
  std::printf("[%s] revisit %.3f (yaw %.1f deg), 20 m away %.3f, other scene %.3f; ring key %.3f / %.3f / %.3f\n",
              Name(GetParam()), same.distance, same.yaw_rad / kDeg, far.distance, other_scene.distance,
              RingKeyDistance(a, b), RingKeyDistance(a, c), RingKeyDistance(a, d));
  // yaw_rad is the yaw of T_b_a = yaw_a - yaw_b; one sector (6 deg) is the resolution of the shift search.
  EXPECT_LE(std::abs(WrapAngle(same.yaw_rad - (10 - 83) * kDeg)), kSectorRad);
  EXPECT_EQ(fast.best_shift, same.best_shift);  // the sector key finds the same shift here
  EXPECT_LT(same.distance, 0.2);
  EXPECT_GT(far.distance, same.distance + 0.15);
  EXPECT_GT(other_scene.distance, same.distance + 0.15);
  EXPECT_LT(RingKeyDistance(a, b), RingKeyDistance(a, c));
}

INSTANTIATE_TEST_SUITE_P(CellValues, DescriptorPlaces, ::testing::Values(CellValue::kHeightBands, CellValue::kMaxHeight));

TEST(LidarDescriptor, HeightBandsSeparateHallPlacesBetterThanMaxHeight) {
  // Under a ceiling every cell's max height is the ceiling's: the paper's cell value sees only the footprint.
  const Scene hall = Hall(3);
  double margin[2];
  for (const CellValue value : {CellValue::kHeightBands, CellValue::kMaxHeight}) {
    RandomStream rng(5, "hall-places");
    const LidarDescriptorConfig config = ConfigWith(value);
    const LidarDescriptor a = ComputeLidarDescriptor(Scan(hall, KeyframePose(-6, -2, 1.5, 0.2), &rng), config);
    const LidarDescriptor b = ComputeLidarDescriptor(Scan(hall, KeyframePose(-5.6, -2.3, 1.5, 1.5), &rng), config);
    const LidarDescriptor c = ComputeLidarDescriptor(Scan(hall, KeyframePose(2, -2, 1.5, 0.2), &rng), config);
    const double same = DescriptorDistance(a, b).distance, other = DescriptorDistance(a, c).distance;
    margin[value == CellValue::kHeightBands ? 0 : 1] = other - same;
    std::printf("[%s] hall: revisit %.3f, 8 m away %.3f\n", Name(value), same, other);
  }
  EXPECT_GT(margin[0], 1.5 * margin[1]);
}

TEST(LidarDescriptor, RingKeyIsInvariantToWholeSectorRotations) {
  const LidarDescriptorConfig config;
  RandomStream rng(13, "ring-key-invariance");
  const std::vector<Eigen::Vector3f> scan = Scan(Street(7), KeyframePose(100, 0, 1.8, 0), &rng);
  const LidarDescriptor d0 = ComputeLidarDescriptor(scan, config);
  for (const int k : {1, 15, 37, 59}) {
    // Rotating the points by k sectors (in double, then rounded to float as a sensor driver would).
    const Eigen::Matrix3f R = RotZ(k * kSectorRad).linear().cast<float>();
    std::vector<Eigen::Vector3f> rotated;
    for (const auto& p : scan) rotated.push_back((RotZ(k * kSectorRad) * p.cast<double>()).cast<float>());
    const LidarDescriptor dk = ComputeLidarDescriptor(rotated, config);
    for (int r = 0; r < config.num_rings; ++r) EXPECT_FLOAT_EQ(dk.ring_key[r], d0.ring_key[r]) << "k " << k;
    // The whole grid moves by k columns: the full distance is 0 at shift k.
    int mismatches = 0;
    for (int j = 0; j < config.num_sectors; ++j)
      mismatches += (dk.cells.col((j + k) % config.num_sectors) != d0.cells.col(j));
    EXPECT_EQ(mismatches, 0) << "k " << k;
    const DescriptorMatch m = DescriptorDistance(d0, dk);
    EXPECT_EQ(m.best_shift, k);
    EXPECT_NEAR(m.distance, 0.0, 1e-6);
    (void)R;
  }
}

TEST(LidarDescriptor, EmptyAndOutOfRangeCloudsGiveAnEmptyDescriptor) {
  const LidarDescriptorConfig config;
  const LidarDescriptor empty = ComputeLidarDescriptor(std::vector<Eigen::Vector3f>{}, config);
  ASSERT_EQ(empty.num_rings(), config.num_rings);
  ASSERT_EQ(empty.num_sectors(), config.num_sectors);
  EXPECT_EQ(empty.num_points, 0u);
  EXPECT_EQ(empty.cells.cwiseAbs().maxCoeff(), 0.0f);
  EXPECT_EQ(empty.ring_key.cwiseAbs().maxCoeff(), 0.0f);
  // Beyond the radius, above max_z, below min_z, not finite: all skipped.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<Eigen::Vector3f> outside = {{41, 0, 0}, {0, -40, 0}, {1, 1, 6}, {1, 1, -3}, {nan, 1, 0}};
  const LidarDescriptor none = ComputeLidarDescriptor(outside, config);
  EXPECT_EQ(none.num_points, 0u);
  EXPECT_EQ(none.cells.cwiseAbs().maxCoeff(), 0.0f);
  pcl::PointCloud<pcl::PointXYZ> one;
  one.push_back(pcl::PointXYZ(3, 4, 0));  // range 5 m: ring 2, azimuth 53.1 deg: sector 38
  const LidarDescriptor single = ComputeLidarDescriptor(one, config);
  EXPECT_EQ(single.num_points, 1u);
  EXPECT_GT(single.cells(2, 38), 0.0f);
  EXPECT_EQ((single.cells.array() > 0).count(), 1);
  // Nothing to compare: distance 1 (never a match), also between two empty descriptors.
  EXPECT_EQ(DescriptorDistance(empty, single).distance, 1.0);
  EXPECT_EQ(DescriptorDistance(empty, empty).distance, 1.0);
  // An invalid config gives a 0 x 0 descriptor; sizes that differ never match.
  LidarDescriptorConfig bad;
  bad.num_sectors = 1;
  const LidarDescriptor invalid = ComputeLidarDescriptor(outside, bad);
  EXPECT_EQ(invalid.cells.size(), 0);
  EXPECT_EQ(DescriptorDistance(invalid, single).distance, 1.0);
  EXPECT_TRUE(std::isinf(RingKeyDistance(invalid, single)));
}

}  // namespace
}  // namespace rotolidar::loop
