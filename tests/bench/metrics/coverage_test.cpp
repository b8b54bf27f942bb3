// Coverage, visibility, density and map-to-truth distance on scenes whose answers are known in closed form.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "bench/metrics/coverage.hpp"
#include "bench/metrics/map_metrics.hpp"
#include "core/util/rng.hpp"
#include "sim/world/embree_scene.hpp"

namespace rotolidar::bench {
namespace {

// A 4 x 3 x 2.5 m room, floor at z = 0, x in [-2, 2], y in [-1.5, 1.5].
sim::Scene BoxRoom() {
  sim::Scene scene;
  scene.name = "test_room";
  sim::Material m;
  m.name = "paint";
  scene.materials.push_back(m);
  scene.primitives.push_back(sim::MakeRoom("room", Eigen::Vector3d(0, 0, 1.25), Eigen::Vector3d(4, 3, 2.5), 0));
  scene.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-2, -1.5, 0), Eigen::Vector3d(2, 1.5, 2.5));
  return scene;
}

// Points on a 1 cm grid of an axis-aligned rectangle: coordinate `fixed_axis` = value, the other two spanning
// [lo, hi] of their axes.
void AddGrid(int fixed_axis, double value, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
             std::vector<Eigen::Vector3f>* out) {
  const int a = (fixed_axis + 1) % 3, b = (fixed_axis + 2) % 3;
  for (double u = lo[a]; u <= hi[a] + 1e-9; u += 0.01)
    for (double v = lo[b]; v <= hi[b] + 1e-9; v += 0.01) {
      Eigen::Vector3d p;
      p[fixed_axis] = value, p[a] = u, p[b] = v;
      out->push_back(p.cast<float>());
    }
}

// Every inner surface of BoxRoom on a 1 cm grid.
std::vector<Eigen::Vector3f> FullRoomMap() {
  std::vector<Eigen::Vector3f> map;
  const Eigen::Vector3d lo(-2, -1.5, 0), hi(2, 1.5, 2.5);
  for (int axis = 0; axis < 3; ++axis) {
    AddGrid(axis, lo[axis], lo, hi, &map);
    AddGrid(axis, hi[axis], lo, hi, &map);
  }
  return map;
}

double Coverage(const std::vector<SurfaceSample>& s, SurfaceClass c) {
  return SummarizeCoverage(s, false).per_class[static_cast<int>(c)].coverage;
}

TEST(Coverage, SamplesAreAreaUniformAndClassified) {
  const sim::TriangleMesh mesh = sim::BuildMesh(BoxRoom());
  const auto samples = SampleSurfaces(mesh, 0.05, Eigen::AlignedBox3d());
  const CoverageResult r = SummarizeCoverage(samples, false);
  // Weights sum to the exact areas: floor = ceiling = 12 m^2, walls 2 * (4 + 3) * 2.5 = 35 m^2.
  EXPECT_NEAR(r.per_class[int(SurfaceClass::kFloor)].area_m2, 12.0, 1e-3);
  EXPECT_NEAR(r.per_class[int(SurfaceClass::kCeiling)].area_m2, 12.0, 1e-3);
  EXPECT_NEAR(r.per_class[int(SurfaceClass::kWall)].area_m2, 35.0, 1e-3);
  EXPECT_NEAR(r.per_class[int(SurfaceClass::kOther)].area_m2, 0.0, 1e-12);
  // One sample per 0.05 m cell: (12 + 12 + 35) / 0.0025 = 23600, up to a row of cells per triangle edge.
  EXPECT_NEAR(static_cast<double>(samples.size()), 23600.0, 0.05 * 23600.0);
}

TEST(Coverage, FullySampledRoomIsCovered) {
  auto samples = SampleSurfaces(sim::BuildMesh(BoxRoom()), 0.05, Eigen::AlignedBox3d());
  MarkCovered(FullRoomMap(), 0.05, &samples);
  // A 1 cm grid on every surface puts a point within 0.71 cm of every sample: all covered, exactly.
  EXPECT_DOUBLE_EQ(SummarizeCoverage(samples, false).total.coverage, 1.0);
}

TEST(Coverage, FloorOnlyCoversTheFloorFraction) {
  auto samples = SampleSurfaces(sim::BuildMesh(BoxRoom()), 0.05, Eigen::AlignedBox3d());
  std::vector<Eigen::Vector3f> map;
  AddGrid(2, 0.0, Eigen::Vector3d(-2, -1.5, 0), Eigen::Vector3d(2, 1.5, 0), &map);
  MarkCovered(map, 0.05, &samples);
  EXPECT_DOUBLE_EQ(Coverage(samples, SurfaceClass::kFloor), 1.0);
  EXPECT_DOUBLE_EQ(Coverage(samples, SurfaceClass::kCeiling), 0.0);
  // Walls: only their bottom 5 cm strip is within the distance: 0.05 / 2.5 = 0.02 of their area, give or
  // take one 5 cm sample row (0.02).
  EXPECT_NEAR(Coverage(samples, SurfaceClass::kWall), 0.02, 0.02);
  // Total: the floor's 12 of 59 m^2 plus that strip (0.7 m^2).
  EXPECT_NEAR(SummarizeCoverage(samples, false).total.coverage, (12.0 + 0.7) / 59.0, 0.02 * 35.0 / 59.0);
}

TEST(Coverage, HalfAWallInARegion) {
  // Region: the wall x = -2 only. Map: its lower half (z <= 1.25).
  const Eigen::AlignedBox3d region(Eigen::Vector3d(-2.01, -1.6, -0.1), Eigen::Vector3d(-1.99, 1.6, 2.6));
  auto samples = SampleSurfaces(sim::BuildMesh(BoxRoom()), 0.05, region);
  std::vector<Eigen::Vector3f> map;
  AddGrid(0, -2.0, Eigen::Vector3d(-2, -1.5, 0), Eigen::Vector3d(-2, 1.5, 1.25), &map);
  MarkCovered(map, 0.05, &samples);
  // Covered up to z = 1.25 + 0.05: (1.30) / 2.5 = 0.52 of the wall, within one sample row (0.05 / 2.5).
  EXPECT_NEAR(Coverage(samples, SurfaceClass::kWall), 0.52, 0.02);
  EXPECT_NEAR(SummarizeCoverage(samples, false).per_class[int(SurfaceClass::kWall)].area_m2, 3.0 * 2.5, 0.1);
}

TEST(Coverage, VisibilityHidesWhatABoxOccludes) {
  sim::Scene scene = BoxRoom();
  sim::Primitive crate;
  crate.type = sim::PrimitiveType::kBox;
  crate.name = "crate";
  crate.center_m = Eigen::Vector3d(0, 0, 0.25);
  crate.size_m = Eigen::Vector3d(1.0, 1.0, 0.5);
  scene.primitives.push_back(crate);
  const sim::TriangleMesh mesh = sim::BuildMesh(scene);
  auto samples = SampleSurfaces(mesh, 0.05, Eigen::AlignedBox3d());
  // Seen from four points above the room around the crate (each shadow of one is lit by another), everything
  // is visible except the floor under the crate and the crate's bottom face (1 m^2 each).
  const std::vector<Eigen::Vector3d> views = {{-1.2, 0, 2}, {1.2, 0, 2}, {0, -1.2, 2}, {0, 1.2, 2}};
  ASSERT_TRUE(MarkVisible(mesh, views, 0.1, 30.0, &samples));
  const CoverageResult r = SummarizeCoverage(samples, true);
  // Bound: a 5 cm row of samples along the 4 m perimeter of each hidden square may fall either way: 2 * 0.2 m^2.
  EXPECT_NEAR(r.total.area_m2 - r.total.visible_area_m2, 2.0, 0.4);
  // Ceiling class: the room's ceiling (12 m^2, all visible) and the crate's bottom (1 m^2, hidden but its rim row).
  EXPECT_NEAR(r.per_class[int(SurfaceClass::kCeiling)].area_m2, 13.0, 1e-3);
  EXPECT_NEAR(r.per_class[int(SurfaceClass::kCeiling)].visible_area_m2, 12.0, 0.2);
  // A range limit of 1 m from the same points hides most of the room.
  ASSERT_TRUE(MarkVisible(mesh, {Eigen::Vector3d(-1.2, 0, 2.0)}, 0.1, 1.0, &samples));
  EXPECT_LT(SummarizeCoverage(samples, true).total.visible_area_m2, 0.2 * r.total.area_m2);
}

// Reference: every viewpoint tried for every sample, in input order, on one thread.
std::vector<bool> BruteForceVisible(const sim::TriangleMesh& mesh, const std::vector<SurfaceSample>& samples,
                                    const std::vector<Eigen::Vector3d>& views, double min_m, double max_m) {
  std::unique_ptr<sim::EmbreeScene> embree;
  EXPECT_TRUE(sim::EmbreeScene::Create(mesh, &embree));
  std::vector<bool> out;
  for (const SurfaceSample& s : samples) {
    bool seen = false;
    for (const Eigen::Vector3d& o : views) {
      const Eigen::Vector3d p = s.p_world.cast<double>();
      const double r = (p - o).norm();
      if (r < min_m || r > max_m) continue;
      const sim::RayHit hit = embree->Intersect(o, p - o, r + 0.005);
      if (!hit.hit || hit.distance_m >= r - 0.005) seen = true;
    }
    out.push_back(seen);
  }
  return out;
}

TEST(Coverage, TiledThreadedVisibilityEqualsTryingEveryViewpoint) {
  // A 24 x 16 m hall (many 2 m tiles) with crates; viewpoints along a path, a range band that leaves some
  // samples in range of only far viewpoints and some of none.
  sim::Scene scene = BoxRoom();
  scene.primitives.clear();
  scene.primitives.push_back(sim::MakeRoom("hall", Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(24, 16, 3), 0));
  RandomStream rng(7, "coverage_test");
  for (int k = 0; k < 12; ++k) {
    sim::Primitive crate;
    crate.type = sim::PrimitiveType::kBox;
    crate.name = "crate" + std::to_string(k);
    crate.center_m = Eigen::Vector3d{-10 + 20 * rng.Uniform(), -6 + 12 * rng.Uniform(), 0.5};
    crate.size_m = Eigen::Vector3d(1.0, 1.5, 1.0);
    scene.primitives.push_back(crate);
  }
  const sim::TriangleMesh mesh = sim::BuildMesh(scene);
  auto samples = SampleSurfaces(mesh, 0.2, Eigen::AlignedBox3d());
  std::vector<Eigen::Vector3d> views;
  for (double x = -9; x <= 3; x += 0.5) views.emplace_back(x, 0.3 * x, 1.2);
  std::vector<double> fractions;
  ASSERT_TRUE(MarkVisible(mesh, views, 1.0, 9.0, &samples, [&](double f) { fractions.push_back(f); }));
  const std::vector<bool> expected = BruteForceVisible(mesh, samples, views, 1.0, 9.0);
  size_t visible = 0, mismatches = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    visible += samples[i].visible;
    mismatches += samples[i].visible != expected[i];
  }
  EXPECT_EQ(mismatches, 0u) << "of " << samples.size() << " samples";
  // Not a trivial answer either way: the range band and the crates hide a good share.
  EXPECT_GT(visible, samples.size() / 5);
  EXPECT_LT(visible, samples.size() * 4 / 5);
  ASSERT_FALSE(fractions.empty());
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
}

TEST(Coverage, CoveredEqualsTheNearestPointTestAcrossCellBorders) {
  // A sparse map (80 points within 8 cm of the room's surfaces: most 1 m cells of the pre-filter empty, so
  // samples across a cell border from their only covering point occur) against a brute-force check.
  auto samples = SampleSurfaces(sim::BuildMesh(BoxRoom()), 0.05, Eigen::AlignedBox3d());
  RandomStream rng(11, "covered_test");
  std::vector<Eigen::Vector3f> map;
  for (int k = 0; k < 80; ++k) {
    const SurfaceSample& s = samples[size_t(rng.Uniform() * double(samples.size())) % samples.size()];
    map.push_back(s.p_world + 0.08f * Eigen::Vector3f{float(rng.Uniform() - 0.5), float(rng.Uniform() - 0.5),
                                                       float(rng.Uniform() - 0.5)});
  }
  MarkCovered(map, 0.05, &samples);
  size_t covered = 0, mismatches = 0;
  for (const SurfaceSample& s : samples) {
    float best = std::numeric_limits<float>::infinity();
    for (const Eigen::Vector3f& p : map) best = std::min(best, (p - s.p_world).squaredNorm());
    covered += s.covered;
    mismatches += s.covered != (best <= 0.05f * 0.05f);
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_GT(covered, 80u);  // not trivially empty: each point covers a few samples
}

TEST(Coverage, DensityIsUniformForAGridAndNotForAHalfDenseMap) {
  auto samples = SampleSurfaces(sim::BuildMesh(BoxRoom()), 0.05, Eigen::AlignedBox3d());
  const std::vector<Eigen::Vector3f> map = FullRoomMap();
  const DensityResult uniform = ComputeDensity(samples, map, 0.05, 0.5);
  // 1 cm grid: 1e4 points/m^2 (edges and corners carry a little more); measured CV 0.06.
  EXPECT_NEAR(uniform.median_per_m2, 1e4, 500);
  EXPECT_LT(uniform.cv, 0.1);
  EXPECT_EQ(uniform.occupied_cells, uniform.cells);
  // Doubling the points on every surface with x < 0 (half the cells at 2x): CV of {1, 2} = 1/3.
  std::vector<Eigen::Vector3f> uneven = map;
  for (const Eigen::Vector3f& p : map)
    if (p.x() < 0) uneven.push_back(p + Eigen::Vector3f(0.001f, 0.001f, 0.001f));
  const DensityResult half = ComputeDensity(samples, uneven, 0.05, 0.5);
  EXPECT_NEAR(half.cv, 1.0 / 3.0, 0.08);
}

TEST(MapToTruth, PointsOffsetByAKnownDistance) {
  const sim::Scene scene = BoxRoom();
  // Floor points lifted by a known offset in [0, 0.2] m, at least 0.3 m away from the walls: the nearest
  // surface is the floor, so the exact distance is the offset (float coordinates: ~1e-6 m).
  RandomStream rng(7, "map_to_truth_test");
  std::vector<Eigen::Vector3f> map;
  std::vector<double> offsets;
  for (int i = 0; i < 2000; ++i) {
    const double offset = 0.2 * rng.Uniform();
    map.push_back(Eigen::Vector3d{-1.7 + 3.4 * rng.Uniform(), -1.2 + 2.4 * rng.Uniform(), offset}.cast<float>());
    offsets.push_back(offset);
  }
  MapMetricsConfig config;
  MapMetrics m;
  ASSERT_TRUE(ComputeMapMetrics(scene, map, config, &m));
  ASSERT_EQ(m.point_distance_m.size(), map.size());
  for (size_t i = 0; i < map.size(); ++i) ASSERT_NEAR(m.point_distance_m[i], offsets[i], 2e-6) << i;
  EXPECT_NEAR(m.map_to_truth.median_m, 0.1, 0.01);    // uniform on [0, 0.2]: median 0.1, 2000 samples
  EXPECT_NEAR(m.map_to_truth.rmse_m, 0.2 / std::sqrt(3.0), 0.005);
  EXPECT_NEAR(m.map_to_truth.fraction_within_m, 0.25, 0.03);  // <= 0.05 m: a quarter
  EXPECT_LE(m.map_to_truth.max_m, 0.2);
}

TEST(MapAlignment, FirstPoseRecoversTheGauge) {
  Eigen::Isometry3d T_scene_slam = Eigen::Isometry3d::Identity();
  T_scene_slam.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.1, 0.2, 1).normalized()).toRotationMatrix();
  T_scene_slam.translation() = Eigen::Vector3d(1.5, 2.5, 1.2);
  Trajectory truth, estimate;
  for (int i = 0; i < 50; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(0.1 * i, std::sin(0.2 * i), 0.01 * i);
    truth.push_back({0.1 * i, T});
    if (i >= 5) estimate.push_back({0.1 * i, T_scene_slam.inverse() * T});
  }
  for (MapAlignment a : {MapAlignment::kFirstPose, MapAlignment::kSe3}) {
    Eigen::Isometry3d T;
    ASSERT_TRUE(MapToSceneTransform(truth, estimate, a, &T));
    EXPECT_LT((T.matrix() - T_scene_slam.matrix()).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace rotolidar::bench
