#pragma once
// The relative-pose residual of the SE(3) pose graph (core/graph/pose_graph.hpp), exposed for tests and for anyone
// who wants to add the same constraint to another Ceres problem.
//
// Parameter blocks of a node (the pose T_world_node): translation t (3, metres, world frame) and the unit
// quaternion q (4, Eigen memory order x y z w, Ceres' EigenQuaternionManifold).
//
// Error of an edge with measurement T_from_to_meas, at estimated poses T_world_from and T_world_to:
//   E   = T_from_to_meas^-1 * (T_world_from^-1 * T_world_to)          (identity when the poses agree)
//   e   = [t(E) (m); Log(R(E)) (rad)]                                  (translation FIRST, then rotation)
// E is the right perturbation of the measurement, T_from_to_est = T_from_to_meas * E, so both parts of e are
// expressed in the `to` keyframe frame as the measurement places it: t_est = t_meas + R_meas t(E) and
// R_est = R_meas Exp(Log(R(E))). An edge's information matrix lives in these coordinates (see pose_graph.hpp for
// converting an information matrix given in the `from` frame).
// Whitened residual r = S e with S = L^T, information = L L^T (Cholesky), so |r|^2 = e^T information e = chi2.
//
// Thread safety: the functor is immutable after construction; evaluation is const and may run concurrently.
#include <ceres/autodiff_cost_function.h>
#include <ceres/rotation.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/types/geometry.hpp"

namespace rotolidar::graph {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Reference (non-templated) error e of an edge, as defined above; zero when T_world_from^-1 T_world_to equals the
/// measurement. Rotation part in [-pi, pi] rad.
inline Vector6d RelativePoseError(const Pose3& T_world_from, const Pose3& T_world_to, const Pose3& T_from_to_meas) {
  const Pose3 E = T_from_to_meas.inverse() * (T_world_from.inverse() * T_world_to);
  Vector6d e;
  e.head<3>() = E.translation();
  e.tail<3>() = LogSO3(E.linear());
  return e;
}

/// Ceres functor of the whitened edge residual r = S e, parameter blocks (t_from, q_from, t_to, q_to).
class RelativePoseResidual {
 public:
  /// sqrt_information: S with S^T S = information (e.g. the transposed Cholesky factor L^T); not checked here.
  RelativePoseResidual(const Pose3& T_from_to_meas, const Matrix6d& sqrt_information)
      : t_meas_(T_from_to_meas.translation()),
        q_meas_inv_(Eigen::Quaterniond(T_from_to_meas.linear()).normalized().conjugate()),
        sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* t_from_ptr, const T* q_from_ptr, const T* t_to_ptr, const T* q_to_ptr,
                  T* residual_ptr) const {
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Vec3> t_from(t_from_ptr), t_to(t_to_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_from(q_from_ptr), q_to(q_to_ptr);
    // Estimated relative pose T_from_to_est = T_world_from^-1 * T_world_to.
    const Eigen::Quaternion<T> q_from_inv = q_from.conjugate();
    const Eigen::Quaternion<T> q_est = q_from_inv * q_to;
    const Vec3 t_est = q_from_inv * (t_to - t_from);
    // E = T_meas^-1 * T_est.
    const Eigen::Quaternion<T> q_meas_inv = q_meas_inv_.cast<T>();
    const Eigen::Quaternion<T> q_err = q_meas_inv * q_est;
    Eigen::Matrix<T, 6, 1> e;
    e.template head<3>() = q_meas_inv * (t_est - t_meas_.cast<T>());
    // Log via the angle-axis of the quaternion (Ceres wants w x y z; it picks the angle in [-pi, pi], so q and -q
    // give the same error, and its derivative stays exact at zero and round-off-sized rotations).
    const T q_wxyz[4] = {q_err.w(), q_err.x(), q_err.y(), q_err.z()};
    T log_r[3];
    ceres::QuaternionToAngleAxis(q_wxyz, log_r);
    e.template tail<3>() = Eigen::Matrix<T, 3, 1>(log_r[0], log_r[1], log_r[2]);
    Eigen::Map<Eigen::Matrix<T, 6, 1>>{residual_ptr} = sqrt_information_.cast<T>() * e;
    return true;
  }

  /// An automatically differentiated cost (6 residuals; blocks 3, 4, 3, 4), owned by the caller (or by the
  /// ceres::Problem it is added to).
  static ceres::CostFunction* Create(const Pose3& T_from_to_meas, const Matrix6d& sqrt_information) {
    return new ceres::AutoDiffCostFunction<RelativePoseResidual, 6, 3, 4, 3, 4>(
        new RelativePoseResidual(T_from_to_meas, sqrt_information));
  }

 private:
  Eigen::Vector3d t_meas_;
  Eigen::Quaterniond q_meas_inv_;
  Matrix6d sqrt_information_;
};

}  // namespace rotolidar::graph
