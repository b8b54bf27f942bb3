#pragma once
// Helpers shared by the feature tests.
#include <map>
#include <utility>
#include <vector>

#include "core/features/curvature_features.hpp"

namespace rotolidar::test {

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
