#include "core/registration/local_map.hpp"

#include <cmath>
#include <deque>

#include <pcl/common/transforms.h>
#include <pcl/filters/voxel_grid.h>

#include "core/registration/centroid_index.hpp"
#include "core/registration/voxel_centroids.hpp"
#include "core/util/log.hpp"

namespace rotolidar {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZI>;

/// `in` moved into the map frame by M, then one point per voxel_m voxel (PCL's VoxelGrid centroids). An empty
/// set stays empty (PCL's transformPointCloud warns on a width-0 cloud, e.g. a scan without edges).
Cloud TransformedDownsample(const Cloud& in, const Eigen::Matrix4f& M, double voxel_m) {
  Cloud out;
  if (in.empty()) return out;
  Cloud::Ptr transformed(new Cloud);
  pcl::transformPointCloud(in, *transformed, M);
  pcl::VoxelGrid<pcl::PointXYZI> grid;
  grid.setInputCloud(transformed);
  const float leaf = float(voxel_m);
  grid.setLeafSize(leaf, leaf, leaf);
  grid.filter(out);
  return out;
}

double RotationAngle(const Pose3& a, const Pose3& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

/// Where a keyframe's points were seen from: its base origin in the map frame (the LiDAR rides within ~0.2 m of
/// it; views only decide which side of a surface was seen).
Eigen::Vector3f SensorOf(const Pose3& T_map_scan) { return T_map_scan.translation().cast<float>(); }

struct Keyframe {
  Pose3 T_map_scan;
  Cloud edge_map;    ///< downsampled, map frame
  Cloud planar_map;  ///< downsampled, map frame
};

/// One searchable cloud: the table's centroids plus an index over them that follows the table's changes.
struct Searchable {
  explicit Searchable(double voxel_m) : table(voxel_m) {}
  VoxelCentroidTable table;  ///< running per-voxel sums of the live keyframes' points
  CentroidIndex index;
  mutable Cloud cloud;              ///< the centroids as a cloud, exported on demand (cloud())
  mutable bool cloud_stale = true;

  void Sync() {
    index.Sync(&table);
    cloud_stale = true;
  }
  const Cloud& Exported() const {
    if (cloud_stale) table.Centroids(&cloud);
    cloud_stale = false;
    return cloud;
  }
};

}  // namespace

bool LocalMapConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(keyframe_distance_m >= 0)) return fail("local_map.keyframe_distance_m must be >= 0");
  if (!(keyframe_angle_rad >= 0)) return fail("local_map.keyframe_angle_rad must be >= 0");
  if (max_keyframes < 1) return fail("local_map.max_keyframes must be >= 1");
  if (!(max_distance_m > 0)) return fail("local_map.max_distance_m must be > 0");
  if (!(edge_voxel_m > 0)) return fail("local_map.edge_voxel_m must be > 0");
  if (!(planar_voxel_m > 0)) return fail("local_map.planar_voxel_m must be > 0");
  return true;
}

struct LocalMap::Impl {
  explicit Impl(const LocalMapConfig& c) : config(c), edge(c.edge_voxel_m), planar(c.planar_voxel_m) {}
  LocalMapConfig config;
  std::deque<Keyframe> keyframes;
  Searchable edge, planar;

  const Searchable& Get(FeatureKind kind) const { return kind == FeatureKind::kEdge ? edge : planar; }

  void PopFront() {
    const Eigen::Vector3f sensor = SensorOf(keyframes.front().T_map_scan);
    edge.table.Remove(keyframes.front().edge_map, sensor);
    planar.table.Remove(keyframes.front().planar_map, sensor);
    keyframes.pop_front();
  }

  void Trim() {
    while (int(keyframes.size()) > config.max_keyframes) PopFront();
    const Eigen::Vector3d newest = keyframes.back().T_map_scan.translation();
    while ((keyframes.front().T_map_scan.translation() - newest).norm() > config.max_distance_m)
      PopFront();  // the newest keyframe is at distance 0, so the loop ends
  }

  void Sync() {
    edge.Sync();
    planar.Sync();
  }
};

LocalMap::LocalMap(const LocalMapConfig& config) {
  std::string error;
  ROTOLIDAR_CHECK(config.Validate(&error), error);
  impl_ = std::make_unique<Impl>(config);
}
LocalMap::~LocalMap() = default;
LocalMap::LocalMap(LocalMap&&) noexcept = default;
LocalMap& LocalMap::operator=(LocalMap&&) noexcept = default;

bool LocalMap::NeedsKeyframe(const Pose3& T_map_scan) const {
  if (impl_->keyframes.empty()) return true;
  const Pose3& last = impl_->keyframes.back().T_map_scan;
  return (T_map_scan.translation() - last.translation()).norm() >= impl_->config.keyframe_distance_m ||
         RotationAngle(last, T_map_scan) >= impl_->config.keyframe_angle_rad;
}

void LocalMap::AddKeyframe(const FeatureSet& features, const Pose3& T_map_scan) {
  Keyframe kf;
  kf.T_map_scan = T_map_scan;
  const Eigen::Matrix4f M = T_map_scan.matrix().cast<float>();
  kf.edge_map = TransformedDownsample(features.less_sharp, M, impl_->config.edge_voxel_m);
  kf.planar_map = TransformedDownsample(features.less_flat, M, impl_->config.planar_voxel_m);
  impl_->edge.table.Add(kf.edge_map, SensorOf(T_map_scan));
  impl_->planar.table.Add(kf.planar_map, SensorOf(T_map_scan));
  impl_->keyframes.push_back(std::move(kf));
  impl_->Trim();
  impl_->Sync();
}

void LocalMap::Clear() {
  impl_->keyframes.clear();
  impl_->edge.table.Clear();
  impl_->planar.table.Clear();
  impl_->Sync();
}

int LocalMap::Nearest(FeatureKind kind, const Eigen::Vector3d& p_map, int k, std::vector<Eigen::Vector3d>* points,
                      std::vector<float>* sq_dist_m2, float max_sq_dist_m2,
                      std::vector<Eigen::Vector3f>* views) const {
  ROTOLIDAR_CHECK(k >= 1 && k <= kMaxNearest && points != nullptr && sq_dist_m2 != nullptr, "k = " << k);
  const Searchable& s = impl_->Get(kind);
  const float query[3] = {float(p_map.x()), float(p_map.y()), float(p_map.z())};
  int slots[kMaxNearest];
  sq_dist_m2->resize(size_t(k));
  float xyz[3 * kMaxNearest];  // the centroids (the index's copy of them)
  const int found = s.index.Nearest(query, k, slots, sq_dist_m2->data(), max_sq_dist_m2, xyz);
  sq_dist_m2->resize(size_t(found));
  points->resize(size_t(found));
  for (int i = 0; i < found; ++i) (*points)[size_t(i)] = Eigen::Vector3d(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  if (views != nullptr) {
    views->resize(size_t(found));
    for (int i = 0; i < found; ++i) (*views)[size_t(i)] = s.index.view(slots[i]);
  }
  return found;
}

const pcl::PointCloud<pcl::PointXYZI>& LocalMap::cloud(FeatureKind kind) const { return impl_->Get(kind).Exported(); }

std::vector<Pose3> LocalMap::keyframe_poses() const {
  std::vector<Pose3> poses;
  for (const Keyframe& kf : impl_->keyframes) poses.push_back(kf.T_map_scan);
  return poses;
}

size_t LocalMap::num_keyframes() const { return impl_->keyframes.size(); }
const LocalMapConfig& LocalMap::config() const { return impl_->config; }

}  // namespace rotolidar
