#pragma once
// A synthetic world for loop-closure tests: a yard of boxes on a ground plane, a sensor that sees everything
// within 25 m (no occlusion), and a two-lap walk with a drifting odometry. Deterministic for a seed.
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "core/types/geometry.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::graph::test_util {

// A yard of pillars and walls sampled as points (world frame); deterministic for a seed.
inline std::vector<Eigen::Vector3d> MakeWorld(uint64_t seed) {
  RandomStream rng(seed, "loop-closer-test-world");
  std::vector<Eigen::Vector3d> world;
  auto add_box = [&](Eigen::Vector3d c, Eigen::Vector3d half) {
    const double step = 0.1;
    for (double z = 0.0; z <= 2.0 * half.z(); z += step)
      for (double a = -half.x(); a <= half.x(); a += step) {
        world.emplace_back(c.x() + a, c.y() - half.y(), z);
        world.emplace_back(c.x() + a, c.y() + half.y(), z);
      }
    for (double z = 0.0; z <= 2.0 * half.z(); z += step)
      for (double b = -half.y(); b <= half.y(); b += step) {
        world.emplace_back(c.x() - half.x(), c.y() + b, z);
        world.emplace_back(c.x() + half.x(), c.y() + b, z);
      }
  };
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector3d c{-10.0 + 60.0 * rng.Uniform(), -10.0 + 60.0 * rng.Uniform(), 0.0};
    add_box(c, Eigen::Vector3d{0.3 + 1.5 * rng.Uniform(), 0.3 + 1.5 * rng.Uniform(), 0.5 + 1.5 * rng.Uniform()});
  }
  for (double x = -15.0; x <= 55.0; x += 0.5)  // ground
    for (double y = -15.0; y <= 55.0; y += 0.5) world.emplace_back(x, y, -1.0);
  return world;
}

// The points a sensor at T_world_base sees (within 25 m; no occlusion), base frame.
inline std::vector<Eigen::Vector3f> Observe(const std::vector<Eigen::Vector3d>& world, const Pose3& T_world_base) {
  const Pose3 T_base_world = T_world_base.inverse();
  const Eigen::Vector3d sensor = T_world_base.translation();
  std::vector<Eigen::Vector3f> out;
  for (const Eigen::Vector3d& p : world) {
    // A cheap pre-check with a margin (the exact test below decides): most of the world is out of range.
    if ((p - sensor).squaredNorm() > 26.0 * 26.0) continue;
    const Eigen::Vector3d q = T_base_world * p;
    if (q.norm() < 25.0) out.push_back(q.cast<float>());
  }
  return out;
}

// Truth: two laps of a 40 m x 40 m square (0.5 m steps, heading along the path). Odometry: the truth with a yaw
// drift of 0.003 deg and 2 mm per step composed on (about 1.3 m and 1 deg after one lap).
struct Walk {
  std::vector<Pose3> truth, odometry;
};
inline Walk MakeWalk() {
  Walk w;
  std::vector<Eigen::Vector2d> corners = {{0, 0}, {40, 0}, {40, 40}, {0, 40}};
  for (int lap = 0; lap < 2; ++lap)
    for (int side = 0; side < 4; ++side) {
      const Eigen::Vector2d a = corners[side], b = corners[(side + 1) % 4];
      const double yaw = std::atan2(b.y() - a.y(), b.x() - a.x());
      for (int s = 0; s < 80; ++s) {
        Pose3 T = RotZ(yaw);
        T.translation() << a.x() + (b.x() - a.x()) * s / 80.0, a.y() + (b.y() - a.y()) * s / 80.0, 0.0;
        w.truth.push_back(T);
      }
    }
  w.odometry.push_back(w.truth.front());
  Pose3 drift_step = RotZ(0.003 * M_PI / 180.0);
  drift_step.translation() << 0.002, 0.0, 0.0;
  for (size_t i = 1; i < w.truth.size(); ++i)
    w.odometry.push_back(w.odometry.back() * drift_step * (w.truth[i - 1].inverse() * w.truth[i]));
  return w;
}

}  // namespace rotolidar::graph::test_util
