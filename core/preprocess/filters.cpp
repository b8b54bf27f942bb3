#include "core/preprocess/filters.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/search/kdtree.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/util/log.hpp"

namespace rotolidar {
namespace {

/// Keeps the points whose `keep` flag is set, in order; returns how many went.
std::size_t Compact(const std::vector<uint8_t>& keep, std::vector<ScanPoint>* points) {
  std::size_t out = 0;
  for (std::size_t i = 0; i < points->size(); ++i) {
    if (keep[i]) (*points)[out++] = (*points)[i];
  }
  const std::size_t removed = points->size() - out;
  points->resize(out);
  return removed;
}

bool IsFinite(const ScanPoint& p) { return p.p_base.allFinite() && std::isfinite(p.range_m); }

// PCL's own filter: the seed's rule as written.
std::vector<uint8_t> PclSorKeep(const pcl::PointCloud<pcl::PointXYZ>::Ptr& cloud, int k, double std_mul) {
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
  sor.setInputCloud(cloud);
  sor.setMeanK(k);
  sor.setStddevMulThresh(std_mul);
  pcl::Indices kept;
  sor.filter(kept);
  std::vector<uint8_t> keep(cloud->size(), 0);
  for (const auto i : kept) keep[static_cast<std::size_t>(i)] = 1;
  return keep;
}

// The same statistics as PCL's filter (K-NN search excluding the query, sample variance), on d_i / range_i.
std::vector<uint8_t> RangeNormalizedSorKeep(const pcl::PointCloud<pcl::PointXYZ>::Ptr& cloud,
                                            const std::vector<ScanPoint>& points, int k, double std_mul) {
  pcl::search::KdTree<pcl::PointXYZ> tree(false);
  tree.setInputCloud(cloud);
  pcl::Indices nn(k + 1);
  std::vector<float> nn_sq(k + 1);
  std::vector<double> stat(points.size(), 0.0);
  double sum = 0.0, sq_sum = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!(points[i].range_m > 0.f)) continue;  // no statistic: removed below, outside mu and sigma
    const int found = tree.nearestKSearch(static_cast<pcl::index_t>(i), k + 1, nn, nn_sq);
    double dist_sum = 0.0;  // over all k + 1 results: the query itself adds 0 wherever the search ranks it
    for (int j = 0; j < found; ++j) dist_sum += std::sqrt(double(nn_sq[j]));
    stat[i] = dist_sum / k / points[i].range_m;
    sum += stat[i], sq_sum += stat[i] * stat[i];
  }
  const double n = static_cast<double>(std::count_if(points.begin(), points.end(),
                                                      [](const ScanPoint& p) { return p.range_m > 0.f; }));
  const double mean = sum / n, stddev = std::sqrt(std::max(0.0, (sq_sum - sum * sum / n) / (n - 1.0)));
  std::vector<uint8_t> keep(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)  // fewer than 2 valid points: no spread, keep the valid ones
    keep[i] = points[i].range_m > 0.f && (n < 2.0 || stat[i] <= mean + std_mul * stddev);
  return keep;
}

}  // namespace

std::vector<ScanPoint> MakeScanPoints(const LidarScan& scan, const std::vector<Eigen::Vector3d>& p_base_start) {
  ROTOLIDAR_CHECK(scan.points.size() == p_base_start.size(),
                  "scan has " << scan.points.size() << " points, positions " << p_base_start.size());
  std::vector<ScanPoint> out(scan.points.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const LidarPoint& lp = scan.points[i];
    ScanPoint& sp = out[i];
    sp.p_base = p_base_start[i].cast<float>();
    sp.range_m = Eigen::Vector3f(lp.x_m, lp.y_m, lp.z_m).norm();
    sp.azimuth_deg = lp.azimuth_deg;
    sp.intensity = lp.intensity;
    sp.ring = lp.ring;
    sp.t_s = lp.t_s;
  }
  return out;
}

bool PreprocessConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& field, const std::string& rule, double got) {
    if (error) {
      std::ostringstream os;
      os << "preprocess." << field << " must be " << rule << " (got " << got << ")";
      *error = os.str();
    }
    return false;
  };
  if (!(min_range_m >= 0.0)) return fail("min_range_m", ">= 0", min_range_m);
  if (!(max_range_m > min_range_m) || !std::isfinite(max_range_m))
    return fail("max_range_m", "finite and > min_range_m", max_range_m);
  if (sor_k < 1) return fail("sor_k", ">= 1", sor_k);
  if (!(sor_std_mul > 0.0) || !std::isfinite(sor_std_mul)) return fail("sor_std_mul", "finite and > 0", sor_std_mul);
  if (!(voxel_m > 0.0) || !std::isfinite(voxel_m)) return fail("voxel_m", "finite and > 0", voxel_m);
  return true;
}

PreprocessResult Preprocess(const std::vector<ScanPoint>& points, const PreprocessConfig& config) {
  std::string why;
  ROTOLIDAR_CHECK(config.Validate(&why), why);
  PreprocessResult result;
  result.num_input = points.size();
  result.points = points;
  result.removed_nonfinite = RemoveNonFinite(&result.points);
  if (config.enable_range) result.removed_range = RangeFilter(config.min_range_m, config.max_range_m, &result.points);
  if (config.enable_sor)
    result.removed_sor =
        StatisticalOutlierFilter(config.sor_k, config.sor_std_mul, config.sor_range_normalized, &result.points);
  if (config.enable_voxel) result.removed_voxel = VoxelFilter(config.voxel_m, &result.points);
  return result;
}

std::size_t RemoveNonFinite(std::vector<ScanPoint>* points) {
  std::vector<uint8_t> keep(points->size());
  for (std::size_t i = 0; i < points->size(); ++i) keep[i] = IsFinite((*points)[i]);
  return Compact(keep, points);
}

std::size_t RangeFilter(double min_range_m, double max_range_m, std::vector<ScanPoint>* points) {
  std::vector<uint8_t> keep(points->size());
  for (std::size_t i = 0; i < points->size(); ++i) {
    const double r = (*points)[i].range_m;
    keep[i] = r >= min_range_m && r <= max_range_m;
  }
  return Compact(keep, points);
}

// Seed Eq. 1-2 on PCL's kd-tree (and, un-normalised, PCL's StatisticalOutlierRemoval itself).
std::size_t StatisticalOutlierFilter(int k, double std_mul, bool range_normalized, std::vector<ScanPoint>* points) {
  ROTOLIDAR_CHECK(k >= 1, "k = " << k);
  if (points->size() <= static_cast<std::size_t>(k)) return 0;  // no point has K neighbours: no statistic
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(points->size());
  for (const ScanPoint& p : *points) cloud->push_back(pcl::PointXYZ(p.p_base.x(), p.p_base.y(), p.p_base.z()));
  const std::vector<uint8_t> keep =
      range_normalized ? RangeNormalizedSorKeep(cloud, *points, k, std_mul) : PclSorKeep(cloud, k, std_mul);
  return Compact(keep, points);
}

// A sort on integer voxel coordinates instead of pcl::VoxelGrid: VoxelGrid numbers voxels with a 32-bit index over
// the cloud's bounding box and, when that overflows (e.g. a rotating rig's 60 m-range scan, a 120 m cube, at
// 0.05 m: 1.4e10 voxels), logs a warning and returns the input unfiltered; and it outputs centroids, which carry no
// ring or firing time.
std::vector<std::size_t> VoxelRepresentatives(const std::vector<Eigen::Vector3f>& positions, double voxel_m) {
  ROTOLIDAR_CHECK(voxel_m > 0.0 && std::isfinite(voxel_m), "voxel_m = " << voxel_m);
  using Key = std::array<int64_t, 3>;
  std::vector<std::pair<Key, std::size_t>> keyed;
  keyed.reserve(positions.size());
  const double inv = 1.0 / voxel_m;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Eigen::Vector3f& p = positions[i];
    if (!p.allFinite()) continue;
    keyed.push_back({Key{static_cast<int64_t>(std::floor(p.x() * inv)), static_cast<int64_t>(std::floor(p.y() * inv)),
                         static_cast<int64_t>(std::floor(p.z() * inv))},
                     i});
  }
  std::sort(keyed.begin(), keyed.end());  // by voxel, then by index
  std::vector<std::size_t> kept;
  for (std::size_t begin = 0, end = 0; begin < keyed.size(); begin = end) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (end = begin; end < keyed.size() && keyed[end].first == keyed[begin].first; ++end)
      sum += positions[keyed[end].second].cast<double>();
    const Eigen::Vector3d centroid = sum / static_cast<double>(end - begin);
    std::size_t best = keyed[begin].second;
    double best_sq = std::numeric_limits<double>::infinity();
    for (auto it = keyed.begin() + begin; it != keyed.begin() + end; ++it) {
      const double sq = (positions[it->second].cast<double>() - centroid).squaredNorm();
      if (sq < best_sq) best_sq = sq, best = it->second;  // strict: ties keep the lower index
    }
    kept.push_back(best);
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

std::size_t VoxelFilter(double voxel_m, std::vector<ScanPoint>* points) {
  std::vector<Eigen::Vector3f> positions(points->size());
  for (std::size_t i = 0; i < points->size(); ++i) positions[i] = (*points)[i].p_base;
  std::vector<uint8_t> keep(points->size(), 0);
  for (const std::size_t i : VoxelRepresentatives(positions, voxel_m)) keep[i] = 1;
  return Compact(keep, points);
}

}  // namespace rotolidar
