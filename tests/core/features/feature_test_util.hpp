#pragma once
// Helpers shared by the feature tests.
#include <map>
#include <utility>
#include <vector>

#include "core/features/curvature_features.hpp"
#include "core/wire/vlp16.hpp"

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

/// The return of a synthetic 600 rpm VLP-16 revolution at firing sequence k and `ring` (elevation -15 + 2 ring
/// deg), along unit ray d at range r_m, lidar = base frame.
inline ScanPoint SyntheticReturn(const Eigen::Vector3d& d, double r_m, double az_deg, int ring, int k) {
  ScanPoint p;
  p.p_base = (d * r_m).cast<float>();
  p.range_m = static_cast<float>(r_m);
  p.azimuth_deg = static_cast<float>(az_deg);
  p.ring = static_cast<uint8_t>(ring);
  p.t_s = k * kVlp16SequencePeriodS + ring * kVlp16FiringPeriodS;
  return p;
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
