#include "bench/metrics/dynamic_share.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <set>
#include <utility>

#include <nlohmann/json.hpp>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "bench/metrics/surface_distance.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::bench {
namespace {

bool PositiveFinite(double v) { return v > 0.0 && std::isfinite(v); }

using VoxelKey = std::array<int64_t, 3>;

/// The voxel (floor(p / voxel_m) per axis) of a hit.
VoxelKey VoxelOf(const sim::DynamicHitSample& h, double voxel_m) {
  VoxelKey key;
  for (int a = 0; a < 3; ++a) key[a] = static_cast<int64_t>(std::floor(h.p_world[a] / voxel_m));
  return key;
}

/// Distinct voxels of the hits, in all and per object (an entry per object id seen, by id).
std::size_t CountVoxels(const std::vector<sim::DynamicHitSample>& hits, double voxel_m,
                        std::vector<DynamicObjectShare>* per_object) {
  std::set<VoxelKey> voxels;
  std::set<std::pair<int, VoxelKey>> object_voxels;
  for (const sim::DynamicHitSample& h : hits) {
    const VoxelKey key = VoxelOf(h, voxel_m);
    voxels.insert(key);
    object_voxels.insert({h.object_id, key});
    if (h.object_id >= int(per_object->size())) per_object->resize(size_t(h.object_id) + 1);
    ++(*per_object)[size_t(h.object_id)].returns_seen;
  }
  for (const auto& ov : object_voxels) ++(*per_object)[size_t(ov.first)].voxels_seen;
  for (size_t id = 0; id < per_object->size(); ++id) (*per_object)[id].object_id = int(id);
  return voxels.size();
}

/// Map points within radius_m of some hit and farther than clearance_m from the static surface; *voxels_reached:
/// the distinct voxels of those points' nearest hits.
std::size_t CountDynamicPoints(const std::vector<sim::DynamicHitSample>& hits,
                               const std::vector<Eigen::Vector3f>& map_world, const StaticDistanceFn& static_distance,
                               const DynamicShareConfig& config, std::size_t* voxels_reached,
                               std::vector<DynamicObjectShare>* per_object) {
  *voxels_reached = 0;
  if (hits.empty() || map_world.empty()) return 0;
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(hits.size());
  for (const sim::DynamicHitSample& h : hits) {
    const Eigen::Vector3f p = h.p_world.cast<float>();
    cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  std::vector<int> index;
  std::vector<float> sq_dist;
  std::size_t count = 0;
  std::set<VoxelKey> reached;
  std::set<std::pair<int, VoxelKey>> object_reached;
  // A radius search (sorted: nearest first) instead of a nearest-neighbour one: most map points are far from
  // every hit, and the radius prunes the tree at once where an unbounded search descends to some far hit
  // (minutes on a long run's map). The same nearest hit within the radius either way.
  for (const Eigen::Vector3f& p : map_world) {
    const pcl::PointXYZ q(p.x(), p.y(), p.z());
    if (tree.radiusSearch(q, config.hit_radius_m, index, sq_dist) < 1) continue;
    if (static_distance(p.cast<double>(), config.static_clearance_m) <= config.static_clearance_m) continue;
    ++count;
    const sim::DynamicHitSample& nearest = hits[std::size_t(index[0])];
    const VoxelKey key = VoxelOf(nearest, config.voxel_m);
    reached.insert(key);
    object_reached.insert({nearest.object_id, key});
    ++(*per_object)[size_t(nearest.object_id)].map_points_dynamic;
  }
  *voxels_reached = reached.size();
  for (const auto& ov : object_reached) ++(*per_object)[size_t(ov.first)].voxels_reached;
  return count;
}

}  // namespace

bool DynamicShareConfig::Validate(std::string* error) const {
  if (!PositiveFinite(voxel_m)) return FailValidation(error, "dynamic.voxel_m must be > 0 and finite");
  if (!PositiveFinite(static_clearance_m))
    return FailValidation(error, "dynamic.static_clearance_m must be > 0 and finite");
  if (!PositiveFinite(hit_radius_m)) return FailValidation(error, "dynamic.hit_radius_m must be > 0 and finite");
  return true;
}

Status ComputeDynamicShare(const std::vector<sim::DynamicHitSample>& hits,
                           const std::vector<Eigen::Vector3f>& map_world, const StaticDistanceFn& static_distance,
                           const DynamicShareConfig& config, DynamicShare* out) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error("dynamic share: " + why);
  if (!static_distance) return Status::Error("dynamic share: no static distance function");
  *out = DynamicShare{};
  out->returns_seen = hits.size();
  for (const sim::DynamicHitSample& h : hits)
    if (h.object_id < 0) return Status::Error("dynamic share: a hit with object_id < 0");
  out->voxels_seen = CountVoxels(hits, config.voxel_m, &out->per_object);
  out->map_points = map_world.size();
  out->map_points_dynamic =
      CountDynamicPoints(hits, map_world, static_distance, config, &out->voxels_reached, &out->per_object);
  for (DynamicObjectShare& o : out->per_object)
    if (o.voxels_seen > 0) o.share_of_seen = double(o.voxels_reached) / double(o.voxels_seen);
  if (out->voxels_seen > 0)
    out->share_of_seen = static_cast<double>(out->voxels_reached) / static_cast<double>(out->voxels_seen);
  if (out->map_points > 0)
    out->share_of_map = static_cast<double>(out->map_points_dynamic) / static_cast<double>(out->map_points);
  return Status::Ok();
}

StaticDistanceFn StaticDistanceOf(const SurfaceDistance& surface) {
  // Searching a little beyond the clearance is enough: farther answers only need to exceed it.
  return [&surface](const Eigen::Vector3d& p, double at_least_m) { return surface.Distance(p, 2.0 * at_least_m); };
}

void ToJson(const DynamicShare& s, const DynamicShareConfig& c, nlohmann::json* out) {
  *out = {{"returns_seen", s.returns_seen},
          {"voxels_seen", s.voxels_seen},
          {"map_points", s.map_points},
          {"map_points_dynamic", s.map_points_dynamic},
          {"voxels_reached", s.voxels_reached},
          {"share_of_seen", s.share_of_seen},
          {"share_of_map", s.share_of_map},
          {"voxel_m", c.voxel_m},
          {"static_clearance_m", c.static_clearance_m},
          {"hit_radius_m", c.hit_radius_m}};
  nlohmann::json objects = nlohmann::json::array();
  for (const DynamicObjectShare& o : s.per_object) {
    if (o.returns_seen == 0) continue;
    objects.push_back({{"object_id", o.object_id},
                       {"name", o.name},
                       {"returns_seen", o.returns_seen},
                       {"voxels_seen", o.voxels_seen},
                       {"map_points_dynamic", o.map_points_dynamic},
                       {"voxels_reached", o.voxels_reached},
                       {"share_of_seen", o.share_of_seen}});
  }
  (*out)["per_object"] = objects;
}

std::string DynamicShareLine(const DynamicShare& s) {
  char line[200];
  std::snprintf(line, sizeof(line),
                "dynamic objects: %zu returns seen in %zu voxels; the dense map reached %zu of those voxels "
                "(%.2f %%) with %zu points (%.2f %% of the map)",
                s.returns_seen, s.voxels_seen, s.voxels_reached, 100.0 * s.share_of_seen, s.map_points_dynamic,
                100.0 * s.share_of_map);
  return line;
}

std::string DynamicObjectLines(const DynamicShare& s) {
  std::string lines;
  for (const DynamicObjectShare& o : s.per_object) {
    if (o.returns_seen == 0) continue;
    char line[240];
    std::snprintf(line, sizeof(line),
                  "  %s (id %d): %zu returns, %zu voxels; the map reached %zu (%.2f %%) with %zu points\n",
                  o.name.empty() ? "object" : o.name.c_str(), o.object_id, o.returns_seen, o.voxels_seen,
                  o.voxels_reached, 100.0 * o.share_of_seen, o.map_points_dynamic);
    lines += line;
  }
  return lines;
}

}  // namespace rotolidar::bench
