#include "bench/metrics/coverage.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <tuple>
#include <unordered_set>

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "sim/world/embree_scene.hpp"
#include "core/util/log.hpp"

namespace rotolidar::bench {
namespace {

constexpr double kVisibilityToleranceM = 0.005;  // a ray "reaches" a sample when its first hit is this close

pcl::PointCloud<pcl::PointXYZ>::Ptr ToCloud(const std::vector<Eigen::Vector3f>& points) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(points.size());
  for (const Eigen::Vector3f& p : points) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  return cloud;
}

// The cubic cell (edge cell_m) holding p: floor(p / cell_m) per axis. One definition for the coverage
// pre-filter, the visibility tiles and the density cells.
using CellKey = std::tuple<long, long, long>;
CellKey CellOf(const Eigen::Vector3f& p, double cell_m) {
  return {std::lround(std::floor(p.x() / cell_m)), std::lround(std::floor(p.y() / cell_m)),
          std::lround(std::floor(p.z() / cell_m))};
}

// The cells (edge cell_m) holding a point, dilated by one cell in every direction.
class CellGrid {
 public:
  CellGrid(const std::vector<Eigen::Vector3f>& points, double cell_m) : cell_m_(cell_m) {
    std::unordered_set<int64_t> occupied;
    for (const Eigen::Vector3f& p : points) occupied.insert(Pack(CellOf(p, cell_m)));
    for (int64_t key : occupied) {
      const auto [x, y, z] = Unpack(key);
      for (long dx = -1; dx <= 1; ++dx)
        for (long dy = -1; dy <= 1; ++dy)
          for (long dz = -1; dz <= 1; ++dz) cells_.insert(Pack({x + dx, y + dy, z + dz}));
    }
  }
  bool Contains(const Eigen::Vector3f& p) const { return cells_.count(Pack(CellOf(p, cell_m_))) > 0; }

 private:
  static constexpr int64_t kBias = 1 << 20;  // cells in [-2^20, 2^20) per axis: +-1000 km at 1 m
  static constexpr int64_t kMask = (int64_t(1) << 21) - 1;
  static int64_t Pack(const CellKey& c) {
    return ((std::get<0>(c) + kBias) << 42) | ((std::get<1>(c) + kBias) << 21) | (std::get<2>(c) + kBias);
  }
  static CellKey Unpack(int64_t k) {
    return {((k >> 42) & kMask) - kBias, ((k >> 21) & kMask) - kBias, (k & kMask) - kBias};
  }
  double cell_m_;
  std::unordered_set<int64_t> cells_;
};

// Grid points (cell centres of spacing s) of one triangle, in its own plane; the centroid when none fall inside.
void SampleTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, double s,
                    std::vector<Eigen::Vector3d>* out) {
  out->clear();
  const Eigen::Vector3d ab = b - a, ac = c - a;
  const Eigen::Vector3d u = ab.normalized();
  const Eigen::Vector3d v = ab.cross(ac).cross(ab).normalized();  // in plane, towards c
  const Eigen::Vector2d B(ab.norm(), 0.0), C(ac.dot(u), ac.dot(v));
  const double x0 = std::min(0.0, C.x()), x1 = std::max(B.x(), C.x());
  const double det = B.x() * C.y();  // 2D barycentric with A at the origin
  for (double y = 0.5 * s; y < C.y(); y += s) {
    for (double x = x0 + 0.5 * s; x < x1; x += s) {
      const double l2 = (x * C.y() - y * C.x()) / det;  // weight of B
      const double l3 = (B.x() * y) / det;              // weight of C
      if (l2 < 0 || l3 < 0 || l2 + l3 > 1) continue;
      out->push_back(a + x * u + y * v);
    }
  }
  if (out->empty()) out->push_back((a + b + c) / 3.0);
}

}  // namespace

const char* SurfaceClassName(SurfaceClass c) {
  switch (c) {
    case SurfaceClass::kWall: return "wall";
    case SurfaceClass::kFloor: return "floor";
    case SurfaceClass::kCeiling: return "ceiling";
    case SurfaceClass::kOther: return "other";
  }
  return "other";
}

SurfaceClass ClassifyNormal(const Eigen::Vector3d& n) {
  if (n.z() > 0.9) return SurfaceClass::kFloor;
  if (n.z() < -0.9) return SurfaceClass::kCeiling;
  if (std::abs(n.z()) < 0.3) return SurfaceClass::kWall;
  return SurfaceClass::kOther;
}

std::vector<SurfaceSample> SampleSurfaces(const sim::TriangleMesh& mesh, double spacing_m,
                                          const Eigen::AlignedBox3d& region) {
  ROTOLIDAR_CHECK(spacing_m > 0, "sample spacing must be positive");
  std::vector<SurfaceSample> samples;
  std::vector<Eigen::Vector3d> points;
  double area_m2 = 0.0;  // reserve for the whole scene at once (a parking lot has millions of samples)
  for (const Eigen::Vector3i& tri : mesh.triangles)
    area_m2 += 0.5 * (mesh.vertices_m[tri[1]] - mesh.vertices_m[tri[0]])
                         .cross(mesh.vertices_m[tri[2]] - mesh.vertices_m[tri[0]])
                         .norm();
  samples.reserve(size_t(area_m2 / (spacing_m * spacing_m)) + mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector3d &a = mesh.vertices_m[tri[0]], &b = mesh.vertices_m[tri[1]], &c = mesh.vertices_m[tri[2]];
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double area = 0.5 * cross.norm();
    if (!(area > 1e-12)) continue;  // degenerate: no surface
    SampleTriangle(a, b, c, spacing_m, &points);
    const SurfaceClass cls = ClassifyNormal(cross.normalized());
    const float weight = static_cast<float>(area / static_cast<double>(points.size()));
    for (const Eigen::Vector3d& p : points) {
      if (!region.isEmpty() && !region.contains(p)) continue;
      SurfaceSample s;
      s.p_world = p.cast<float>();
      s.area_m2 = weight;
      s.surface_class = cls;
      s.triangle_id = static_cast<int>(t);
      samples.push_back(s);
    }
  }
  return samples;
}

void MarkCovered(const std::vector<Eigen::Vector3f>& map_world, double distance_m,
                 std::vector<SurfaceSample>* samples) {
  for (SurfaceSample& s : *samples) s.covered = false;
  if (map_world.empty()) return;
  // Most samples of a large scene lie far from every map point: they skip the tree. A point within distance_m
  // of a sample lies in the sample's cell or a neighbour when cells are at least distance_m wide.
  const CellGrid near_map(map_world, std::max(1.0, distance_m));
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(ToCloud(map_world));
  std::vector<int> index(1);
  std::vector<float> sq_dist(1);
  const double d2 = distance_m * distance_m;
  for (SurfaceSample& s : *samples) {
    if (!near_map.Contains(s.p_world)) continue;
    const pcl::PointXYZ q(s.p_world.x(), s.p_world.y(), s.p_world.z());
    s.covered = tree.nearestKSearch(q, 1, index, sq_dist) == 1 && sq_dist[0] <= d2;
  }
}

namespace {

constexpr double kVisibilityTileM = 2.0;  // samples are grouped in cubes of this edge for the viewpoint search

/// Samples grouped by tile (indices into the sample array), tiles in key order (deterministic).
std::vector<std::vector<size_t>> GroupByTile(const std::vector<SurfaceSample>& samples) {
  std::map<CellKey, std::vector<size_t>> tiles;
  for (size_t i = 0; i < samples.size(); ++i) tiles[CellOf(samples[i].p_world, kVisibilityTileM)].push_back(i);
  std::vector<std::vector<size_t>> out;
  out.reserve(tiles.size());
  for (auto& [key, members] : tiles) out.push_back(std::move(members));
  return out;
}

/// The viewpoints that can lie in [min_range_m, max_range_m] of some sample of the tile (bounding sphere test),
/// nearest the tile's centre first: a visible sample usually stops at the first ray.
std::vector<Eigen::Vector3d> TileCandidates(const std::vector<SurfaceSample>& samples,
                                            const std::vector<size_t>& tile,
                                            const std::vector<Eigen::Vector3d>& viewpoints, double min_range_m,
                                            double max_range_m) {
  Eigen::AlignedBox3d box;
  for (size_t i : tile) box.extend(samples[i].p_world.cast<double>());
  const Eigen::Vector3d centre = box.center();
  const double radius = 0.5 * box.diagonal().norm();
  std::vector<std::pair<double, size_t>> near;
  for (size_t v = 0; v < viewpoints.size(); ++v) {
    const double d = (viewpoints[v] - centre).norm();
    if (d + radius >= min_range_m && d - radius <= max_range_m) near.emplace_back(d, v);
  }
  std::sort(near.begin(), near.end());
  std::vector<Eigen::Vector3d> out;
  out.reserve(near.size());
  for (const auto& [d, v] : near) out.push_back(viewpoints[v]);
  return out;
}

bool SeenFromAny(const sim::EmbreeScene& embree, const Eigen::Vector3d& p,
                 const std::vector<Eigen::Vector3d>& candidates, double min_range_m, double max_range_m) {
  for (const Eigen::Vector3d& o : candidates) {
    const double range = (p - o).norm();
    if (range < min_range_m || range > max_range_m) continue;
    const sim::RayHit hit = embree.Intersect(o, p - o, range + kVisibilityToleranceM);
    if (!hit.hit || hit.distance_m >= range - kVisibilityToleranceM) return true;
  }
  return false;
}

}  // namespace

Status MarkVisible(const sim::TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& viewpoints_world,
                   double min_range_m, double max_range_m, std::vector<SurfaceSample>* samples,
                   const std::function<void(double)>& progress) {
  std::unique_ptr<sim::EmbreeScene> embree;
  if (Status st = sim::EmbreeScene::Create(mesh, &embree); !st) return Status::Error("visibility: " + st.message);
  const std::vector<std::vector<size_t>> tiles = GroupByTile(*samples);
  std::atomic<size_t> next_tile{0};
  size_t tiles_done = 0;  // guarded by progress_mutex
  std::mutex progress_mutex;
  // Each sample's flag is written by the one thread that owns its tile; Embree queries are const and
  // thread-safe. The result does not depend on the order (visible = some viewpoint sees it).
  auto worker = [&]() {
    for (size_t t = next_tile++; t < tiles.size(); t = next_tile++) {
      const auto candidates = TileCandidates(*samples, tiles[t], viewpoints_world, min_range_m, max_range_m);
      for (size_t i : tiles[t]) {
        SurfaceSample& s = (*samples)[i];
        s.visible = SeenFromAny(*embree, s.p_world.cast<double>(), candidates, min_range_m, max_range_m);
      }
      if (progress) {  // counted under the lock, so that reported fractions never go back
        std::lock_guard<std::mutex> lock(progress_mutex);
        progress(double(++tiles_done) / double(tiles.size()));
      }
    }
  };
  const unsigned num_threads = std::max(1u, std::min(std::thread::hardware_concurrency(), 16u));
  std::vector<std::thread> threads;
  for (unsigned k = 1; k < num_threads; ++k) threads.emplace_back(worker);
  worker();
  for (std::thread& th : threads) th.join();
  return Status::Ok();
}

CoverageResult SummarizeCoverage(const std::vector<SurfaceSample>& samples, bool has_visibility) {
  CoverageResult r;
  r.has_visibility = has_visibility;
  for (const SurfaceSample& s : samples) {
    for (ClassCoverage* c : {&r.per_class[static_cast<int>(s.surface_class)], &r.total}) {
      c->area_m2 += s.area_m2;
      if (s.covered) c->covered_area_m2 += s.area_m2;
      if (s.visible) c->visible_area_m2 += s.area_m2;
      if (s.visible && s.covered) c->covered_visible_area_m2 += s.area_m2;
    }
  }
  for (ClassCoverage* c : {&r.per_class[0], &r.per_class[1], &r.per_class[2], &r.per_class[3], &r.total}) {
    c->coverage = c->area_m2 > 0 ? c->covered_area_m2 / c->area_m2 : 0.0;
    c->completeness = c->visible_area_m2 > 0 ? c->covered_visible_area_m2 / c->visible_area_m2 : 0.0;
  }
  return r;
}

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(pos));
  if (i + 1 >= values.size()) return values.back();
  return values[i] + (pos - static_cast<double>(i)) * (values[i + 1] - values[i]);
}

DensityResult ComputeDensity(const std::vector<SurfaceSample>& samples,
                             const std::vector<Eigen::Vector3f>& map_world, double distance_m, double cell_m) {
  struct Cell {
    double area_m2 = 0.0;
    size_t points = 0;
  };
  std::vector<Eigen::Vector3f> visible;
  std::vector<CellKey> keys;
  std::map<CellKey, Cell> cells;
  for (const SurfaceSample& s : samples) {
    if (!s.visible) continue;
    const CellKey k = CellOf(s.p_world, cell_m);
    visible.push_back(s.p_world);
    keys.push_back(k);
    cells[k].area_m2 += s.area_m2;
  }
  DensityResult r;
  if (visible.empty()) return r;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(ToCloud(visible));
  std::vector<int> index(1);
  std::vector<float> sq_dist(1);
  for (const Eigen::Vector3f& p : map_world) {
    if (tree.nearestKSearch(pcl::PointXYZ(p.x(), p.y(), p.z()), 1, index, sq_dist) == 1 &&
        sq_dist[0] <= distance_m * distance_m)
      ++cells[keys[static_cast<size_t>(index[0])]].points;
  }
  std::vector<double> density;
  for (const auto& [key, cell] : cells) {
    if (cell.area_m2 < 0.25 * cell_m * cell_m) continue;
    ++r.cells;
    if (cell.points == 0) continue;
    density.push_back(static_cast<double>(cell.points) / cell.area_m2);
  }
  r.occupied_cells = density.size();
  r.occupied_fraction = r.cells > 0 ? static_cast<double>(r.occupied_cells) / static_cast<double>(r.cells) : 0.0;
  if (density.empty()) return r;
  double sum = 0.0, sum2 = 0.0;
  for (double d : density) sum += d, sum2 += d * d;
  const double n = static_cast<double>(density.size());
  r.mean_per_m2 = sum / n;
  r.cv = r.mean_per_m2 > 0 ? std::sqrt(std::max(0.0, sum2 / n - r.mean_per_m2 * r.mean_per_m2)) / r.mean_per_m2 : 0.0;
  r.median_per_m2 = Quantile(density, 0.5);
  r.p05_per_m2 = Quantile(density, 0.05);
  r.p95_per_m2 = Quantile(density, 0.95);
  return r;
}

}  // namespace rotolidar::bench
