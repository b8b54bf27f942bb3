// VoxelRepresentatives' run path (core/preprocess/filters.cpp): consecutive points are taken as runs of one voxel,
// tested against the scaled coordinates' bounds [k, k + 1) instead of recomputing the key. These cases pin the
// bounds to the per-point key floor(p * (1 / voxel_m)): points on and next to voxel faces, signed zeros and tiny
// negatives, non-finite points inside a run, and coordinates whose scaled value is beyond 2^52 (no exact k + 1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>
#include <vector>

#include "core/preprocess/filters.hpp"
#include "tests/core/preprocess/voxel_reference.hpp"

namespace rotolidar {
namespace {

// The straightforward rule, point by point: key = floor(p * (1 / voxel_m)) per axis (the product the filter uses),
// centroid = the double sum in index order / count, nearest by (p - centroid).squaredNorm(), ties to the lower index.
std::vector<std::size_t> PerPointReference(const std::vector<Eigen::Vector3f>& positions, double voxel_m) {
  const double inv = 1.0 / voxel_m;
  std::map<std::tuple<double, double, double>, std::vector<std::size_t>> voxels;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Eigen::Vector3f& p = positions[i];
    if (!p.allFinite()) continue;
    voxels[{std::floor(p.x() * inv), std::floor(p.y() * inv), std::floor(p.z() * inv)}].push_back(i);
  }
  return test::NearestToCentroids(voxels, positions);
}

float Next(float v, float toward) { return std::nextafter(v, toward); }

TEST(VoxelRepresentativesRuns, FacesZerosAndNonFiniteInsideRunsMatchThePerPointKey) {
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Eigen::Vector3f> pts;
  for (const float face : {0.f, 0.25f, 0.5f, -0.25f, -0.5f, 1.75f})  // exact faces of the 0.25 m grid
    for (const float x : {Next(face, -inf), face, Next(face, inf), face, Next(face, -inf), Next(face, -inf)})
      pts.push_back({x, 0.1f, 0.1f});
  for (const float z : {0.f, -0.f, -1e-30f, 1e-30f, -0.f, 0.f, -1e-30f}) pts.push_back({0.1f, 0.1f, z});
  for (const Eigen::Vector3f& odd : {Eigen::Vector3f(nan, 0.1f, 0.1f), Eigen::Vector3f(0.1f, inf, 0.1f),
                                     Eigen::Vector3f(0.1f, 0.1f, -inf)}) {
    pts.push_back({0.11f, 0.12f, 0.13f});
    pts.push_back(odd);  // inside a run of one voxel: skipped, the run resumes in the same voxel
    pts.push_back({0.12f, 0.11f, 0.1f});
  }
  for (const double voxel_m : {0.25, 0.1, 0.05})
    EXPECT_EQ(VoxelRepresentatives(pts, voxel_m), PerPointReference(pts, voxel_m)) << voxel_m;
}

TEST(VoxelRepresentativesRuns, ScaledCoordinatesBeyondTwoToThe52) {
  std::vector<Eigen::Vector3f> pts;
  for (const float big : {1e15f, 3e15f, 1e17f, -1e17f}) {  // / 0.2: 5e15 .. 5e17, past 2^52 = 4.5e15
    for (int rep = 0; rep < 3; ++rep) pts.push_back({big, 1.f, 1.f});  // repeats: one voxel
    pts.push_back({Next(big, 0.f), 1.f, 1.f});
    pts.push_back({big, 1.f, 1.f});
    pts.push_back({Next(big, 2.f * big), 1.f, 1.f});
  }
  EXPECT_EQ(VoxelRepresentatives(pts, 0.2), PerPointReference(pts, 0.2));
}

}  // namespace
}  // namespace rotolidar
