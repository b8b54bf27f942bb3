#pragma once
// Shared helpers of the pose graph tests: random poses and vectors, diagonal information, the edge perturbation.
#include "core/graph/pose_graph.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::graph::test_util {

inline Vector6d RandomVector6(RandomStream& rng, double sigma_t, double sigma_r) {
  Vector6d v;
  for (int i = 0; i < 3; ++i) v(i) = rng.Normal(0.0, sigma_t);
  for (int i = 3; i < 6; ++i) v(i) = rng.Normal(0.0, sigma_r);
  return v;
}

/// T * E with E = (Exp(e_r), e_t): e is exactly the edge error of T relative to the measurement T.
inline Pose3 RightPerturb(const Pose3& T, const Vector6d& e) {
  Pose3 E = Pose3::Identity();
  E.linear() = ExpSO3(e.tail<3>());
  E.translation() = e.head<3>();
  return T * E;
}

inline Pose3 RandomPose(RandomStream& rng, double sigma_t_m) {
  const Eigen::Vector3d t{rng.Normal(0, sigma_t_m), rng.Normal(0, sigma_t_m), rng.Normal(0, sigma_t_m)};
  return MakePose(t, Eigen::Quaterniond{rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal()});
}

inline Matrix6d DiagonalInformation(double sigma_t_m, double sigma_r_rad) {
  Vector6d d;
  d << Eigen::Vector3d::Constant(1.0 / (sigma_t_m * sigma_t_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_r_rad * sigma_r_rad));
  return d.asDiagonal();
}
}  // namespace rotolidar::graph::test_util
