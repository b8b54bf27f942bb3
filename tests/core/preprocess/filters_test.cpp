// Preprocessing (core/preprocess/filters.hpp): range gate, PCL statistical outlier removal, attribute-preserving
// voxel filter, and their removal counts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <tuple>

#include "core/preprocess/filters.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

ScanPoint At(float x, float y, float z, uint8_t ring = 0, double t_s = 0.0) {
  ScanPoint p;
  p.p_base = Eigen::Vector3f(x, y, z);
  p.range_m = p.p_base.norm();
  p.ring = ring;
  p.t_s = t_s;
  return p;
}

// A dense plane z = 0: a 50 x 50 grid at 2 cm spacing (1 m^2), ids in t_s so survivors can be traced.
std::vector<ScanPoint> DensePlane() {
  std::vector<ScanPoint> pts;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 50; ++j) pts.push_back(At(1.0f + 0.02f * i, 0.02f * j, 0.f, 0, double(pts.size())));
  return pts;
}

// Both statistics (PCL's plain one and the range-normalised one) on a dense plane with isolated outliers.
class SorModes : public ::testing::TestWithParam<bool> {};

TEST_P(SorModes, RemovesIsolatedOutliersAndKeepsDensePlane) {
  std::vector<ScanPoint> pts = DensePlane();
  const std::size_t n_plane = pts.size();
  RandomStream rng(7, "filters_test.outliers");
  for (int k = 0; k < 25; ++k) {  // isolated points 0.5..1.5 m off the plane
    const float x = 1.0f + float(rng.Uniform()), y = float(rng.Uniform()), z = 0.5f + float(rng.Uniform());
    pts.push_back(At(x, y, z, 0, -1.0 - k));  // outliers carry negative ids
  }
  const std::size_t removed = StatisticalOutlierFilter(20, 3.0, GetParam(), &pts);
  for (const ScanPoint& p : pts) EXPECT_GE(p.t_s, 0.0) << "outlier kept at " << p.p_base.transpose();
  EXPECT_EQ(removed, n_plane + 25 - pts.size());
  // The plane's border points have larger neighbour distances than its interior, but far less than mu + 3 sigma:
  // every plane point survives (measured: 2500 of 2500 in both modes).
  EXPECT_EQ(pts.size(), n_plane);
  for (std::size_t i = 1; i < pts.size(); ++i) EXPECT_LT(pts[i - 1].t_s, pts[i].t_s) << "input order kept";
}

INSTANTIATE_TEST_SUITE_P(StatisticalOutlierFilter, SorModes, ::testing::Values(false, true));

// A LiDAR samples at fixed angles, so a surface at 12 m gets points 6x sparser than one at 2 m. One revolution of
// 16 rings (0.2 deg steps) sees 2 m everywhere except a 10 deg window onto 12 m (2.8 % of the points). PCL's plain
// statistic calls that far surface an outlier; the range-normalised one keeps it and still removes a stray return.
TEST(StatisticalOutlierFilter, RangeNormalisedKeepsFarSparseSurface) {
  std::vector<ScanPoint> pts;
  for (int a = 0; a < 1800; ++a)
    for (int ring = 0; ring < 16; ++ring) {
      const float az = 0.2f * float(a), el = -15.f + 2.f * float(ring), deg = 3.14159265f / 180.f;
      const float r = az < 350.f ? 2.f : 12.f;
      ScanPoint p = At(r * std::cos(el * deg) * std::cos(az * deg), r * std::cos(el * deg) * std::sin(az * deg),
                       r * std::sin(el * deg), uint8_t(ring), double(pts.size()));
      pts.push_back(p);
    }
  pts.push_back(At(-6.f, 0.f, 0.f, 0, -1.0));  // a stray return 4 m from any surface
  auto count_far = [](const std::vector<ScanPoint>& v) {
    return std::count_if(v.begin(), v.end(), [](const ScanPoint& p) { return p.range_m > 10.f; });
  };
  const long n_far = count_far(pts);
  std::vector<ScanPoint> plain = pts, normalised = pts;
  StatisticalOutlierFilter(20, 3.0, false, &plain);
  StatisticalOutlierFilter(20, 3.0, true, &normalised);
  EXPECT_EQ(count_far(plain), 0);
  EXPECT_EQ(count_far(normalised), n_far);
  EXPECT_EQ(normalised.size(), pts.size() - 1);
  for (const ScanPoint& p : normalised) EXPECT_GE(p.t_s, 0.0);  // the stray return is the one removed
}

TEST(StatisticalOutlierFilter, FewerPointsThanKKeepsAll) {
  std::vector<ScanPoint> pts = {At(1, 0, 0), At(2, 0, 0), At(50, 0, 0)};
  EXPECT_EQ(StatisticalOutlierFilter(5, 1.0, true, &pts), 0u);
  EXPECT_EQ(pts.size(), 3u);
}

TEST(RangeFilter, UsesSensorRangeInclusiveAndCounts) {
  std::vector<ScanPoint> pts;
  for (int i = 0; i < 10; ++i) {
    ScanPoint p = At(0.f, 0.f, 0.f, 0, i);  // base-frame position at the origin: only range_m decides
    p.range_m = 0.25f * float(i);              // 0, 0.25, ..., 2.25 m
    pts.push_back(p);
  }
  EXPECT_EQ(RangeFilter(0.5, 1.5, &pts), 5u);  // keeps 0.5, 0.75, 1.0, 1.25, 1.5 of 0 .. 2.25
  ASSERT_EQ(pts.size(), 5u);
  EXPECT_EQ(pts.front().range_m, 0.5f);
  EXPECT_EQ(pts.back().range_m, 1.5f);
}

TEST(VoxelFilter, KeepsOneRealPointPerVoxelNearestItsCentroid) {
  std::vector<ScanPoint> pts;
  RandomStream rng(11, "filters_test.voxel");
  // 10 voxels of 0.5 m along x, 100 random points in each.
  for (int v = 0; v < 10; ++v)
    for (int k = 0; k < 100; ++k)
      pts.push_back(At(0.5f * v + 0.5f * float(rng.Uniform()), 0.5f * float(rng.Uniform()),
                       0.5f * float(rng.Uniform()), uint8_t(v), double(pts.size())));
  const std::vector<ScanPoint> input = pts;
  EXPECT_EQ(VoxelFilter(0.5, &pts), 990u);
  ASSERT_EQ(pts.size(), 10u);
  for (std::size_t v = 0; v < 10; ++v) {
    const ScanPoint& kept = pts[v];
    EXPECT_EQ(kept.ring, v);  // attributes travel with the point, output in input order
    const ScanPoint& original = input[std::size_t(kept.t_s)];
    EXPECT_EQ(original.p_base, kept.p_base);  // a real input point, not a centroid
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    for (int k = 0; k < 100; ++k) centroid += input[v * 100 + k].p_base / 100.f;
    for (int k = 0; k < 100; ++k)
      EXPECT_LE((kept.p_base - centroid).norm(), (input[v * 100 + k].p_base - centroid).norm() + 1e-6f);
  }
}

// A 400 x 190 x 150 m cloud at 0.05 m spans 9e10 grid voxels: PCL's VoxelGrid would overflow its 32-bit voxel index
// (it then returns the input unfiltered). This filter still downsamples exactly.
TEST(VoxelFilter, WideExtentAndFineVoxels) {
  std::vector<Eigen::Vector3f> positions;
  for (int i = 0; i < 2000; ++i) {
    const float x = -200.f + 0.2f * i + 0.02f;  // 0.02 m into a voxel: no rounding at a voxel face
    positions.push_back({x, 0.01f, 0.01f});
    positions.push_back({x + 0.01f, 0.02f, 0.02f});  // same 0.05 m voxel as the previous point
    positions.push_back({x, 190.f, 150.f});           // far corner of the extent
  }
  positions.push_back({std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f});  // never kept
  const std::vector<std::size_t> kept = VoxelRepresentatives(positions, 0.05);
  EXPECT_EQ(kept.size(), 4000u);
  std::set<std::tuple<int, int, int>> voxels;
  for (const std::size_t i : kept)
    voxels.insert({int(std::floor(positions[i].x() / 0.05f)), int(std::floor(positions[i].y() / 0.05f)),
                   int(std::floor(positions[i].z() / 0.05f))});
  EXPECT_EQ(voxels.size(), 4000u);
}

TEST(Preprocess, StageCountsAddUp) {
  std::vector<ScanPoint> pts = DensePlane();  // ranges 1.0 .. 2.2 m
  pts.push_back(At(0.3f, 0.f, 0.f));          // rig self-hit, inside min range
  pts.push_back(At(80.f, 0.f, 0.f));          // beyond max range
  pts.push_back(At(1.5f, 0.5f, 3.0f));        // isolated outlier
  ScanPoint bad = At(1.f, 1.f, 1.f);
  bad.p_base.x() = std::numeric_limits<float>::infinity();
  pts.push_back(bad);
  PreprocessConfig config;
  config.enable_voxel = true;
  config.voxel_m = 0.1;
  const PreprocessResult r = Preprocess(pts, config);
  EXPECT_EQ(r.num_input, pts.size());
  EXPECT_EQ(r.removed_nonfinite, 1u);
  EXPECT_EQ(r.removed_range, 2u);
  EXPECT_EQ(r.removed_sor, 1u);
  // 1.0 x 1.0 m plane at 2 cm in 0.1 m voxels: x in [1.0, 1.98] and y in [0, 0.98] span 10 x 10 voxels.
  EXPECT_EQ(r.points.size(), 100u);
  EXPECT_EQ(r.num_input,
            r.points.size() + r.removed_nonfinite + r.removed_range + r.removed_sor + r.removed_voxel);
}

TEST(PreprocessConfig, ValidateNamesTheField) {
  std::string error;
  EXPECT_TRUE(PreprocessConfig().Validate(&error)) << error;
  struct Case {
    const char* field;
    void (*breaks)(PreprocessConfig*);
  };
  const Case cases[] = {
      {"preprocess.min_range_m", [](PreprocessConfig* c) { c->min_range_m = -1; }},
      {"preprocess.max_range_m", [](PreprocessConfig* c) { c->max_range_m = 0.5; }},
      {"preprocess.sor_k", [](PreprocessConfig* c) { c->sor_k = 0; }},
      {"preprocess.sor_std_mul", [](PreprocessConfig* c) { c->sor_std_mul = 0; }},
      {"preprocess.voxel_m", [](PreprocessConfig* c) { c->voxel_m = std::nan(""); }},
  };
  for (const Case& c : cases) {
    PreprocessConfig config;
    c.breaks(&config);
    error.clear();
    EXPECT_FALSE(config.Validate(&error)) << c.field;
    EXPECT_NE(error.find(c.field), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace rotolidar
