#pragma once
// The relative-pose residual of the SE(3) pose graph (core/graph/pose_graph.hpp), exposed for tests and for anyone
// who wants to add the same constraint to another Ceres problem, and the helpers that make an edge's information
// matrix (from a registration covariance, or from the `from`-frame convention).
//
// Parameter blocks of a node (the pose T_world_node): translation t (3, metres, world frame) and the unit
// quaternion q (4, Eigen memory order x y z w, Ceres' EigenQuaternionManifold).
//
// Error of an edge with measurement T_from_to_meas, at estimated poses T_world_from and T_world_to:
//   E   = T_from_to_meas^-1 * (T_world_from^-1 * T_world_to)          (identity when the poses agree)
//   e   = [t(E) (m); Log(R(E)) (rad)]                                  (translation FIRST, then rotation)
// E is the right perturbation of the measurement, T_from_to_est = T_from_to_meas * E, so both parts of e are
// expressed in the `to` keyframe frame as the measurement places it: t_est = t_meas + R_meas t(E) and
// R_est = R_meas Exp(Log(R(E))). An edge's information matrix lives in these coordinates (InformationInToFrame
// below converts one given in the `from` frame).
// Whitened residual r = S e with S = L^T, information = L L^T (Cholesky), so |r|^2 = e^T information e = chi2.
//
// Thread safety: the functor is immutable after construction; evaluation is const and may run concurrently. The
// helpers are pure functions.
#include <cmath>
#include <string>

#include <ceres/rotation.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/types/geometry.hpp"
#include "core/util/status.hpp"
#include "core/util/validation.hpp"

namespace ceres {
class CostFunction;
}  // namespace ceres

namespace rotolidar::graph {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Reference (non-templated) error e of an edge, as defined above; zero when T_world_from^-1 T_world_to equals the
/// measurement. Rotation part in [-pi, pi] rad.
Vector6d RelativePoseError(const Pose3& T_world_from, const Pose3& T_world_to, const Pose3& T_from_to_meas);

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
  static ceres::CostFunction* Create(const Pose3& T_from_to_meas, const Matrix6d& sqrt_information);

 private:
  Eigen::Vector3d t_meas_;
  Eigen::Quaterniond q_meas_inv_;
  Matrix6d sqrt_information_;
};

// --------------------------------------------------------------------------------- edge information helpers

/// Floors on the standard deviations of an information matrix made from a registration covariance.
struct InformationFloor {
  double min_sigma_translation_m = 0.01;   ///< > 0
  double min_sigma_rotation_rad = 0.001;   ///< > 0 (~0.06 deg)

  bool Validate(std::string* error) const {
    if (!(std::isfinite(min_sigma_translation_m) && min_sigma_translation_m > 0.0)) {
      return FailValidation(error, "information_floor.min_sigma_translation_m must be > 0");
    }
    if (!(std::isfinite(min_sigma_rotation_rad) && min_sigma_rotation_rad > 0.0)) {
      return FailValidation(error, "information_floor.min_sigma_rotation_rad must be > 0");
    }
    return true;
  }
};

/// Information from an ICP/GICP 6x6 covariance ([translation m; rotation rad], in the edge's error coordinates):
/// a regularised inverse. With D = diag(floor_t x3, floor_r x3), the dimensionless D^-1 C D^-1 is symmetrised and
/// its eigenvalues are clamped to >= 1 before inverting, so the result satisfies information <= D^-2 (no direction
/// is more certain than its floor, whatever the conditioning of C: a near-singular covariance cannot make one
/// loop dominate) and equals C^-1 when every direction of C is already above the floor. Negative (round-off or
/// indefinite) eigenvalues are clamped as well. Fails on a non-finite covariance or an invalid floor.
Status InformationFromCovariance(const Matrix6d& covariance, const InformationFloor& floor,
                                 Matrix6d* information);

/// Converts an information matrix given in the `from`-frame convention of core/ (T_from_to (+) xi = (t + dt,
/// Exp(dtheta) R), xi = [dt; dtheta] in frame `from`, as core/backend/pose_factors.hpp) into this edge's `to`-frame
/// error coordinates. The map is exact and linear: xi = A e with A = blockdiag(R, R), R = T_from_to.linear(), so
/// information_to = A^T information_from A.
Matrix6d InformationInToFrame(const Matrix6d& information_from, const Pose3& T_from_to);

}  // namespace rotolidar::graph
