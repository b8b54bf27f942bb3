#pragma once
// Synthetic axis-aligned rooms as point lists for registration tests (visibility_test, weak_direction_test).
#include <vector>

#include <Eigen/Core>

#include "core/features/feature_set.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {

/// Points on the axis-aligned rectangle {axis = value, lo <= other coords <= hi} every `step_m`, with noise.
inline void AddFace(int axis, double value, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, RandomStream& rng,
                    std::vector<Eigen::Vector3d>* out, double step_m = 0.1) {
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  for (double s = lo[a]; s <= hi[a] + 1e-9; s += step_m)
    for (double t = lo[b]; t <= hi[b] + 1e-9; t += step_m) {
      Eigen::Vector3d p;
      p[axis] = value + rng.Normal(0.0, 0.002);
      p[a] = s;
      p[b] = t;
      out->push_back(p);
    }
}

/// Floor, ceiling and side walls of the room between x0 and x1 (y in [-2, 2], z in [0, 3]).
inline void AddShell(double x0, double x1, RandomStream& rng, std::vector<Eigen::Vector3d>* out) {
  AddFace(2, 0.0, {x0, -2, 0}, {x1, 2, 0}, rng, out);
  AddFace(2, 3.0, {x0, -2, 3}, {x1, 2, 3}, rng, out);
  AddFace(1, -2.0, {x0, -2, 0}, {x1, -2, 3}, rng, out);
  AddFace(1, 2.0, {x0, 2, 0}, {x1, 2, 3}, rng, out);
}

/// World points as a FeatureSet in the frame of a sensor at `sensor` (identity rotation), planar sets only.
inline FeatureSet InFrameOf(const std::vector<Eigen::Vector3d>& p_world, const Eigen::Vector3d& sensor) {
  FeatureSet f;
  for (const auto& p : p_world) {
    pcl::PointXYZI q;
    q.x = float(p.x() - sensor.x());
    q.y = float(p.y() - sensor.y());
    q.z = float(p.z() - sensor.z());
    q.intensity = 0.0f;
    f.planar.push_back(q);
  }
  f.less_flat = f.planar;
  return f;
}

}  // namespace rotolidar
