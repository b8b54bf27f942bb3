#pragma once
// Synthetic feature scenes for registration tests (scan_to_map_test, neighbour_reuse_test): rectangles and
// segments sampled as scan features in the scan frame, and a one-keyframe local map of a scene.
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "core/features/feature_set.hpp"
#include "core/registration/local_map.hpp"
#include "core/registration/residuals.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace feature_scenes {

using Cloud = pcl::PointCloud<pcl::PointXYZI>;

struct Rect {  ///< points origin + a u + b v, a, b in [0, 1]
  Eigen::Vector3d origin, u, v;
};
struct Segment {
  Eigen::Vector3d a, b;
};
struct Scene {
  std::vector<Rect> planes;
  std::vector<Segment> edges;
};

inline void AddBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& size, Scene* s) {
  const Eigen::Vector3d X(size.x(), 0, 0), Y(0, size.y(), 0), Z(0, 0, size.z());
  s->planes.push_back({lo + Z, X, Y});  // top
  s->planes.push_back({lo, X, Z});
  s->planes.push_back({lo + Y, X, Z});
  s->planes.push_back({lo, Y, Z});
  s->planes.push_back({lo + X, Y, Z});
  for (const Eigen::Vector3d& c : {lo, Eigen::Vector3d(lo + X), Eigen::Vector3d(lo + Y), Eigen::Vector3d(lo + X + Y)})
    s->edges.push_back({c, c + Z});  // vertical edges
  for (const Eigen::Vector3d& h : {Eigen::Vector3d(lo), Eigen::Vector3d(lo + Z)}) {  // bottom and top rims
    s->edges.push_back({h, h + X});
    s->edges.push_back({h + Y, h + X + Y});
    s->edges.push_back({h, h + Y});
    s->edges.push_back({h + X, h + X + Y});
  }
}

/// A 10 m x 8 m x 3 m room (its inside surfaces and the 12 room edges) with three boxes on the floor.
inline Scene BoxRoom() {
  Scene s;
  AddBox(Eigen::Vector3d(-5, -4, 0), Eigen::Vector3d(10, 8, 3), &s);
  s.planes.push_back({Eigen::Vector3d(-5, -4, 0), Eigen::Vector3d(10, 0, 0), Eigen::Vector3d(0, 8, 0)});  // floor
  AddBox(Eigen::Vector3d(1.5, 0.5, 0), Eigen::Vector3d(1.0, 1.2, 1.0), &s);
  AddBox(Eigen::Vector3d(-3.0, -2.5, 0), Eigen::Vector3d(0.8, 1.5, 1.4), &s);
  AddBox(Eigen::Vector3d(-1.0, 2.0, 0), Eigen::Vector3d(1.6, 0.7, 0.6), &s);
  return s;
}

/// Two 50 m walls 3 m apart along x, and the floor between them: nothing fixes a shift along x.
inline Scene Corridor() {
  Scene s;
  const Eigen::Vector3d X(50, 0, 0), Z(0, 0, 3);
  s.planes.push_back({Eigen::Vector3d(-25, -1.5, 0), X, Z});
  s.planes.push_back({Eigen::Vector3d(-25, 1.5, 0), X, Z});
  s.planes.push_back({Eigen::Vector3d(-25, -1.5, 0), X, Eigen::Vector3d(0, 3, 0)});
  s.edges.push_back({Eigen::Vector3d(-25, -1.5, 0), Eigen::Vector3d(25, -1.5, 0)});
  s.edges.push_back({Eigen::Vector3d(-25, 1.5, 0), Eigen::Vector3d(25, 1.5, 0)});
  return s;
}

inline Eigen::Vector3d Noise(RandomStream& rng, double sigma_m) {
  return Eigen::Vector3d{rng.Normal(0, sigma_m), rng.Normal(0, sigma_m), rng.Normal(0, sigma_m)};
}

inline void Push(const Eigen::Vector3d& p, Cloud* c) {
  pcl::PointXYZI q;
  q.x = float(p.x());
  q.y = float(p.y());
  q.z = float(p.z());
  q.intensity = 0.0f;
  c->push_back(q);
}

/// Samples the scene (uniform, `per_m2` on planes and `per_m` on edges, isotropic noise sigma_m) and expresses
/// the samples in the scan frame: p_scan = T_map_scan^-1 p_map. Fills edge/planar and less_sharp/less_flat alike.
inline FeatureSet Sample(const Scene& scene, double per_m2, double per_m, double sigma_m, const Pose3& T_map_scan,
                  RandomStream& rng) {
  FeatureSet f;
  const Pose3 T_scan_map = T_map_scan.inverse();
  for (const Rect& r : scene.planes) {
    const int n = int(std::lround(r.u.cross(r.v).norm() * per_m2));
    for (int i = 0; i < n; ++i)
      Push(T_scan_map * (r.origin + rng.Uniform() * r.u + rng.Uniform() * r.v + Noise(rng, sigma_m)), &f.planar);
  }
  for (const Segment& e : scene.edges) {
    const int n = int(std::lround((e.b - e.a).norm() * per_m));
    for (int i = 0; i < n; ++i)
      Push(T_scan_map * (e.a + rng.Uniform() * (e.b - e.a) + Noise(rng, sigma_m)), &f.edge);
  }
  f.less_flat = f.planar;
  f.less_sharp = f.edge;
  return f;
}

inline double RotationErrorRad(const Pose3& a, const Pose3& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

inline LocalMap MapOf(const Scene& scene, RandomStream& rng) {
  LocalMapConfig config;
  config.edge_voxel_m = 0.05;
  config.planar_voxel_m = 0.1;
  LocalMap map(config);
  map.AddKeyframe(Sample(scene, 60.0, 40.0, 0.01, Pose3::Identity(), rng), Pose3::Identity());
  return map;
}

inline const Pose3 kTruth =
    MakePose(Eigen::Vector3d(0.4, -0.3, 1.2), Eigen::Quaterniond(ExpSO3(Eigen::Vector3d(0.02, -0.03, 0.6))));

}  // namespace feature_scenes
}  // namespace rotolidar
