#pragma once
// Helpers shared by the feature tests.
#include <map>
#include <utility>
#include <vector>

#include "core/features/curvature_features.hpp"

namespace rotolidar::test {

/// The seed's selection rule (Sec. 3.1: 4 edge + 4 planar points per sector, every selected point kept) with
/// A-LOAM's noise gate and map-side voxel: what these tests check, independent of the estimator's tuned defaults.
inline FeatureConfig SeedFeatureConfig() {
  FeatureConfig c;
  c.planars_per_sector = 4;
  c.planar_voxel_m = 0.0;
  c.less_flat_voxel_m = 0.2;
  c.edge_min_snr = 3.0;
  return c;
}

/// (ring, sector) -> count of points with one of the given labels, sectors of 360 / `sectors` degrees.
inline std::map<std::pair<int, int>, int> CountPerCell(const std::vector<ScanPoint>& pts, const FeatureResult& r,
                                                       const std::vector<FeatureLabel>& which, int sectors) {
  std::map<std::pair<int, int>, int> counts;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (const FeatureLabel l : which)
      if (r.labels[i] == l) ++counts[{pts[i].ring, int(pts[i].azimuth_deg / (360.0 / sectors))}];
  return counts;
}

/// Bit-equal clouds (x, y, z and intensity of every point, in order).
inline bool SameCloud(const pcl::PointCloud<pcl::PointXYZI>& a, const pcl::PointCloud<pcl::PointXYZI>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z || a[i].intensity != b[i].intensity) return false;
  return true;
}

}  // namespace rotolidar::test
