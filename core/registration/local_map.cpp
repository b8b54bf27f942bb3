#include "core/registration/local_map.hpp"

#include <cmath>
#include <deque>

#include <pcl/common/transforms.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>

#include "core/util/log.hpp"

namespace rotolidar {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZI>;

Cloud Downsample(const Cloud::ConstPtr& in, double voxel_m) {
  Cloud out;
  if (in->empty()) return out;
  pcl::VoxelGrid<pcl::PointXYZI> grid;
  grid.setInputCloud(in);
  const float leaf = float(voxel_m);
  grid.setLeafSize(leaf, leaf, leaf);
  grid.filter(out);
  return out;
}

double RotationAngle(const Pose3& a, const Pose3& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

struct Keyframe {
  Pose3 T_map_scan;
  Cloud edge_map;    ///< downsampled, map frame
  Cloud planar_map;  ///< downsampled, map frame
};

/// One searchable cloud: points plus a kd-tree (absent while the cloud is empty).
struct Searchable {
  Cloud::Ptr cloud{new Cloud};
  pcl::KdTreeFLANN<pcl::PointXYZI> tree;
  void Reset(Cloud&& points) {
    cloud.reset(new Cloud(std::move(points)));
    if (!cloud->empty()) tree.setInputCloud(cloud);
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
  LocalMapConfig config;
  std::deque<Keyframe> keyframes;
  Searchable edge, planar;
  Cloud::Ptr edge_union{new Cloud}, planar_union{new Cloud};  ///< Rebuild's scratch, capacity kept across scans

  const Searchable& Get(FeatureKind kind) const { return kind == FeatureKind::kEdge ? edge : planar; }

  void Trim() {
    while (int(keyframes.size()) > config.max_keyframes) keyframes.pop_front();
    const Eigen::Vector3d newest = keyframes.back().T_map_scan.translation();
    while ((keyframes.front().T_map_scan.translation() - newest).norm() > config.max_distance_m)
      keyframes.pop_front();  // the newest keyframe is at distance 0, so the loop ends
  }

  /// The keyframes' `member` clouds concatenated into *out (oldest first), reusing its memory.
  void Union(Cloud Keyframe::*member, Cloud* out) const {
    size_t total = 0;
    for (const Keyframe& kf : keyframes) total += (kf.*member).size();
    out->clear();
    out->reserve(total);
    out->is_dense = true;
    for (const Keyframe& kf : keyframes) {
      out->insert(out->end(), (kf.*member).begin(), (kf.*member).end());
      out->is_dense = out->is_dense && (kf.*member).is_dense;  // as PointCloud::operator+= (VoxelGrid's NaN check)
    }
  }

  void Rebuild() {
    Union(&Keyframe::edge_map, edge_union.get());
    Union(&Keyframe::planar_map, planar_union.get());
    edge.Reset(Downsample(edge_union, config.edge_voxel_m));
    planar.Reset(Downsample(planar_union, config.planar_voxel_m));
  }
};

LocalMap::LocalMap(const LocalMapConfig& config) : impl_(std::make_unique<Impl>()) {
  std::string error;
  ROTOLIDAR_CHECK(config.Validate(&error), error);
  impl_->config = config;
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
  Cloud::Ptr transformed(new Cloud);
  pcl::transformPointCloud(features.less_sharp, *transformed, M);
  kf.edge_map = Downsample(transformed, impl_->config.edge_voxel_m);
  pcl::transformPointCloud(features.less_flat, *transformed, M);
  kf.planar_map = Downsample(transformed, impl_->config.planar_voxel_m);
  impl_->keyframes.push_back(std::move(kf));
  impl_->Trim();
  impl_->Rebuild();
}

void LocalMap::Clear() {
  impl_->keyframes.clear();
  impl_->Rebuild();
}

int LocalMap::Nearest(FeatureKind kind, const Eigen::Vector3d& p_map, int k, std::vector<Eigen::Vector3d>* points,
                      std::vector<float>* sq_dist_m2) const {
  ROTOLIDAR_CHECK(k >= 1 && points != nullptr && sq_dist_m2 != nullptr, "k = " << k);
  points->clear();
  sq_dist_m2->clear();
  const Searchable& s = impl_->Get(kind);
  if (s.cloud->empty()) return 0;
  pcl::PointXYZI query;
  query.x = float(p_map.x());
  query.y = float(p_map.y());
  query.z = float(p_map.z());
  thread_local std::vector<int> indices;
  const int found = s.tree.nearestKSearch(query, k, indices, *sq_dist_m2);
  points->reserve(size_t(found));
  for (int i = 0; i < found; ++i) {
    const pcl::PointXYZI& p = (*s.cloud)[size_t(indices[size_t(i)])];
    points->emplace_back(p.x, p.y, p.z);
  }
  return found;
}

const pcl::PointCloud<pcl::PointXYZI>& LocalMap::cloud(FeatureKind kind) const { return *impl_->Get(kind).cloud; }

std::vector<Pose3> LocalMap::keyframe_poses() const {
  std::vector<Pose3> poses;
  for (const Keyframe& kf : impl_->keyframes) poses.push_back(kf.T_map_scan);
  return poses;
}

size_t LocalMap::num_keyframes() const { return impl_->keyframes.size(); }
const LocalMapConfig& LocalMap::config() const { return impl_->config; }

}  // namespace rotolidar
