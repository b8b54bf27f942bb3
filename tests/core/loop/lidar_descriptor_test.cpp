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
  EXPECT_LT(same.distance, 0.25);  // measured 0.17 (bands) / 0.19 (max height)
  EXPECT_GT(far.distance, same.distance + 0.15);  // measured margins 0.26 and 0.35
  EXPECT_GT(other_scene.distance, same.distance + 0.15);
  EXPECT_LT(RingKeyDistance(a, b), RingKeyDistance(a, c));
}

INSTANTIATE_TEST_SUITE_P(CellValues, DescriptorPlaces,
                         ::testing::Values(CellValue::kHeightBands, CellValue::kMaxHeight));

TEST(LidarDescriptor, RingKeyIsInvariantToWholeSectorRotations) {
  const LidarDescriptorConfig config;
  RandomStream rng(13, "ring-key-invariance");
  const std::vector<Eigen::Vector3f> scan = Scan(Street(7), KeyframePose(100, 0, 1.8, 0), &rng);
  const LidarDescriptor d0 = ComputeLidarDescriptor(scan, config);
  for (const int k : {1, 15, 37, 59}) {
    // Rotating the points by k sectors (in double, then rounded to float as a sensor driver would).
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

/// Keyframes at `places` (random yaw) and their revisits 0.5 m away in a random direction with a random yaw, one
/// descriptor set per config (the same scans).
struct Revisits {
  std::vector<std::vector<LidarDescriptor>> keyframes, queries;  ///< [config][place]
  std::vector<double> yaw_query_to_keyframe_rad;                 ///< [place]: the yaw of T_keyframe_query
};

Revisits MakeRevisits(const Scene& scene, const std::vector<Eigen::Vector3d>& places,
                      const std::vector<LidarDescriptorConfig>& configs, uint64_t seed) {
  RandomStream rng(seed, "revisits");
  Revisits r;
  r.keyframes.resize(configs.size());
  r.queries.resize(configs.size());
  for (const Eigen::Vector3d& p : places) {
    const double yaw_k = 2 * M_PI * rng.Uniform(), yaw_q = 2 * M_PI * rng.Uniform(), dir = 2 * M_PI * rng.Uniform();
    const std::vector<Eigen::Vector3f> kf = Scan(scene, KeyframePose(p.x(), p.y(), p.z(), yaw_k), &rng);
    const std::vector<Eigen::Vector3f> query =
        Scan(scene, KeyframePose(p.x() + 0.5 * std::cos(dir), p.y() + 0.5 * std::sin(dir), p.z(), yaw_q), &rng);
    for (size_t c = 0; c < configs.size(); ++c) {
      r.keyframes[c].push_back(ComputeLidarDescriptor(kf, configs[c]));
      r.queries[c].push_back(ComputeLidarDescriptor(query, configs[c]));
    }
    r.yaw_query_to_keyframe_rad.push_back(yaw_q - yaw_k);
  }
  return r;
}

/// Retrieval of every revisit from an index of the keyframes (keyframe i has id i and time i s).
struct Recall {
  int top1 = 0, yaw_within_sector = 0;
  double worst_true_distance = 0.0, mean_query_ms = 0.0;
};

Recall Retrieve(const std::vector<LidarDescriptor>& keyframes, const std::vector<LidarDescriptor>& queries,
                const std::vector<double>& yaw_query_to_keyframe_rad) {
  LidarPlaceIndex index;
  for (size_t i = 0; i < keyframes.size(); ++i) EXPECT_TRUE(index.Add(int64_t(i), double(i), keyframes[i]).ok);
  Recall recall;
  for (size_t i = 0; i < queries.size(); ++i) {
    std::vector<PlaceCandidate> best;
    recall.mean_query_ms += MillisecondsOf([&] { best = index.Query(queries[i], PlaceQuery{}); }, 10);
    if (best.empty() || best[0].keyframe_id != int64_t(i)) continue;
    ++recall.top1;
    recall.yaw_within_sector +=
        std::abs(WrapAngle(best[0].match.yaw_rad - yaw_query_to_keyframe_rad[i])) <= kSectorRad;
    recall.worst_true_distance = std::max(recall.worst_true_distance, best[0].match.distance);
  }
  recall.mean_query_ms /= double(queries.size());
  return recall;
}

/// The revisits of 50 street places 4 m apart, or of 54 hall places on a 4 m grid, for both cell values (built
/// once: ray casting dominates the test time).
Revisits BuildRevisits(bool street) {
  std::vector<Eigen::Vector3d> places;
  if (street) {
    for (int i = 0; i < 50; ++i) places.emplace_back(10 + 4 * i, 0.5 * std::sin(i), 1.8);
  } else {
    for (double x = -16; x <= 18; x += 4)
      for (double y = -9; y <= 11; y += 4) places.emplace_back(x, y, 1.5);
  }
  return MakeRevisits(street ? Street(7) : Hall(3), places,
                      {ConfigWith(CellValue::kHeightBands), ConfigWith(CellValue::kMaxHeight)}, 31);
}

const Revisits& SceneRevisits(bool street) {
  if (street) {
    static const Revisits street_revisits = BuildRevisits(true);
    return street_revisits;
  }
  static const Revisits hall_revisits = BuildRevisits(false);
  return hall_revisits;
}

class PlaceIndexScenes : public ::testing::TestWithParam<const char*> {};

TEST_P(PlaceIndexScenes, RevisitsReturnTheTrueKeyframeFirstWithItsYaw) {
  // 50 places 4 m apart along the street, or 54 places on a 4 m grid in the hall; revisits 0.5 m away, any yaw.
  const Revisits& r = SceneRevisits(std::string(GetParam()) == "street");
  const size_t num_places = r.yaw_query_to_keyframe_rad.size();
  const Recall bands = Retrieve(r.keyframes[0], r.queries[0], r.yaw_query_to_keyframe_rad);
  const Recall max_height = Retrieve(r.keyframes[1], r.queries[1], r.yaw_query_to_keyframe_rad);
  for (const auto& [name, recall] : {std::pair{"height-bands", bands}, std::pair{"max-height", max_height}})
    std::printf("[%s] %s: top-1 %d / %zu, yaw within a sector %d, worst true distance %.3f, Query %.3f ms\n", name,
                GetParam(), recall.top1, num_places, recall.yaw_within_sector, recall.worst_true_distance,
                recall.mean_query_ms);
  // The default cell value retrieves every revisit with its yaw. (Measured with the paper's max height: the street
  // also 50 / 50, the hall 52 / 54 and 4 of those 52 with the yaw off by more than a sector: under the ceiling it
  // sees the hall's point-symmetric footprint rather than the shelves.)
  EXPECT_EQ(bands.top1, int(num_places));
  EXPECT_EQ(bands.yaw_within_sector, int(num_places));
  // True revisits measured up to 0.28: PlaceQuery's default max_distance (0.35) keeps them.
  EXPECT_LT(bands.worst_true_distance, PlaceQuery{}.max_distance);
}

INSTANTIATE_TEST_SUITE_P(Scenes, PlaceIndexScenes, ::testing::Values("street", "hall"));

TEST(LidarPlaceIndex, ExcludesRecentAndListedKeyframes) {
  const Revisits& r = SceneRevisits(true);  // 50 street places, keyframe i at t = i s
  LidarPlaceIndex index;
  for (size_t i = 0; i < r.keyframes[0].size(); ++i)
    ASSERT_TRUE(index.Add(int64_t(i), double(i), r.keyframes[0][i]).ok);
  PlaceQuery q;
  q.num_results = 5;
  q.max_distance = 1.0;
  ASSERT_FALSE(index.Query(r.queries[0][45], q).empty());
  EXPECT_EQ(index.Query(r.queries[0][45], q)[0].keyframe_id, 45);
  // Query at t = 49.5 s ignoring the last 10 s: keyframes 40..49 (t > 39.5 s) are never returned.
  q.t_s = 49.5;
  q.exclude_recent_s = 10.0;
  const std::vector<PlaceCandidate> old_only = index.Query(r.queries[0][45], q);
  EXPECT_FALSE(old_only.empty());
  for (const PlaceCandidate& c : old_only) EXPECT_LE(c.t_s, 39.5);
  // Excluded by id.
  q = PlaceQuery{};
  q.num_results = 5;
  q.max_distance = 1.0;
  q.exclude_ids = {44, 45, 46};
  for (const PlaceCandidate& c : index.Query(r.queries[0][45], q))
    EXPECT_TRUE(c.keyframe_id < 44 || c.keyframe_id > 46) << c.keyframe_id;
  // Everything excluded: empty.
  q.t_s = -1.0;
  EXPECT_TRUE(index.Query(r.queries[0][45], q).empty());
}

TEST(LidarPlaceIndex, AddReportsDuplicatesSizeMismatchAndAFullIndex) {
  LidarPlaceIndexConfig config;
  config.max_keyframes = 2;
  LidarPlaceIndex index(config);
  const std::vector<Eigen::Vector3f> cloud = {{3, 4, 0}, {-5, 1, 1}};
  const LidarDescriptor d = ComputeLidarDescriptor(cloud, LidarDescriptorConfig{});
  LidarDescriptorConfig small;
  small.num_sectors = 30;
  EXPECT_TRUE(index.Add(7, 0.0, d).ok);
  const Status duplicate = index.Add(7, 1.0, d);
  EXPECT_FALSE(duplicate.ok);
  EXPECT_NE(duplicate.message.find("keyframe 7"), std::string::npos);
  EXPECT_FALSE(index.Add(8, 1.0, ComputeLidarDescriptor(cloud, small)).ok);
  EXPECT_FALSE(index.Add(9, 1.0, LidarDescriptor{}).ok);
  EXPECT_TRUE(index.Add(8, 1.0, d).ok);
  const Status full = index.Add(10, 2.0, d);
  EXPECT_FALSE(full.ok);
  EXPECT_NE(full.message.find("max_keyframes"), std::string::npos);
  EXPECT_EQ(index.size(), 2u);
  ASSERT_NE(index.Find(8), nullptr);
  EXPECT_EQ(index.Find(8)->cells, d.cells);
  EXPECT_EQ(index.Find(10), nullptr);
  // A query of another size finds nothing.
  EXPECT_TRUE(index.Query(ComputeLidarDescriptor(cloud, small), PlaceQuery{}).empty());
}

TEST(LidarPlaceIndex, QueryCostWithThousandsOfKeyframes) {
  // 5000 keyframes (the 50 street places repeated under new ids): brute-force ring keys + 10 full distances.
  const Revisits& r = SceneRevisits(true);
  LidarPlaceIndex index;
  for (int copy = 0; copy < 100; ++copy)
    for (size_t i = 0; i < 50; ++i)
      ASSERT_TRUE(index.Add(int64_t(copy * 50 + i), double(copy * 50 + i), r.keyframes[0][i]).ok);
  std::vector<PlaceCandidate> best;
  const double ms = MillisecondsOf([&] { best = index.Query(r.queries[0][20], PlaceQuery{}); }, 20);
  std::printf("Query over %zu keyframes: %.3f ms; %zu bytes per keyframe\n", index.size(), ms,
              LidarPlaceIndex::BytesPerKeyframe(20, 60));
  ASSERT_EQ(best.size(), 1u);
  EXPECT_EQ(best[0].keyframe_id % 50, 20);  // one of the copies of place 20
}

}  // namespace
}  // namespace rotolidar::loop
