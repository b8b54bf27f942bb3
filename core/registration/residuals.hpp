#pragma once
// LOAM-style geometric residuals for scan-to-map registration (seed Sec. 3, LOAM's edge and planar terms), as
// Ceres cost functions with analytic Jacobians.
//
// Pose block (7 doubles): T_map_scan = [tx ty tz qx qy qz qw] (translation [m], then an Eigen-ordered unit
// quaternion, scalar last) on `PoseManifold` = ProductManifold<EuclideanManifold<3>, EigenQuaternionManifold>.
// Ceres only needs d r / d[t, q] (the ambient 7-column Jacobian); it chains it with the manifold's PlusJacobian.
//
// Tangent ordering used everywhere else in core/registration (Hessian, degeneracy, PoseBoxPlus/Minus):
//   delta = [dt (3, metres, map frame); dtheta (3, rad, rotation vector in the map frame)],
//   T [+] delta:  t <- t + dt,  R <- Exp(dtheta) * R.
// NOTE: Ceres 2.1's own quaternion tangent is HALF of this dtheta (its Plus is q <- [cos|d|, sin|d| d/|d|] * q,
// a rotation by 2|d|; residuals_test pins this), which is why the Hessian is computed from EvaluateTangent below
// and never taken from Ceres' tangent-space Jacobian.
//
// Many of these are solved as one Ceres block each run of points: GroupedResidual (grouped_residual.hpp).
//
// Thread-safety: Evaluate is const and re-entrant. Reset (re-targets a pooled cost function at another
// correspondence) must not run while a Ceres solve that uses the function is in progress.
#include <array>
#include <cstddef>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/manifold.h>
#include <ceres/product_manifold.h>
#include <ceres/sized_cost_function.h>
#include <Eigen/Core>

#include "core/registration/degeneracy.hpp"  // Vector6d, Matrix6d
#include "core/types/geometry.hpp"

namespace rotolidar {

using PoseManifold = ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold>;
using PoseParameters = std::array<double, 7>;  ///< [tx ty tz qx qy qz qw]

/// T -> [t, q(x y z w)] with a normalised quaternion.
PoseParameters PoseToParameters(const Pose3& T);
/// [t, q] -> T (the quaternion is normalised here).
Pose3 ParametersToPose(const double* parameters);
/// T [+] delta with delta = [dt; dtheta] as above (t + dt, Exp(dtheta) R).
Pose3 PoseBoxPlus(const Pose3& T, const Vector6d& delta);
/// The delta with T_x [+] delta = T_y: [t_y - t_x; Log(R_y R_x^T)] (|dtheta| <= pi).
Vector6d PoseBoxMinus(const Pose3& T_y, const Pose3& T_x);

/// d(R(q) p)/d[qx qy qz qw] (3x4) for a unit quaternion q, evaluated on the extension
/// R(q) p = p + 2 w (v x p) + 2 v x (v x p), v = [qx qy qz]. Only its projection onto the unit sphere's tangent
/// matters to Ceres (it multiplies the manifold's PlusJacobian), so the extension off the sphere is irrelevant.
Eigen::Matrix<double, 3, 4> RotatedPointQuaternionJacobian(const Eigen::Quaterniond& q, const Eigen::Vector3d& p);

/// Point-to-plane residual (1 row, metres): r = w (n . (R p_scan + t) + d), the signed distance of the transformed
/// scan point to the map plane {x : n . x + d = 0}, times the weight w > 0 (1: the plain distance; the
/// registration's incidence weights, scan_to_map.hpp). `n_map` must be unit length (checked). Stored as w n, w d.
class PointToPlaneResidual final : public ceres::SizedCostFunction<1, 7> {
 public:
  static constexpr int kRows = 1;
  PointToPlaneResidual(const Eigen::Vector3d& p_scan, const Eigen::Vector3d& n_map, double d_m,
                       double weight = 1.0);
  /// Becomes PointToPlaneResidual(p_scan, n_map, d_m, weight) (same checks).
  void Reset(const Eigen::Vector3d& p_scan, const Eigen::Vector3d& n_map, double d_m, double weight = 1.0);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  /// Residual at pose T and (if J != nullptr) its Jacobian w.r.t. delta = [dt; dtheta]: [n^T, -n^T [R p]x]
  /// (Linearize / Residual at T's rotation and translation).
  double EvaluateTangent(const Pose3& T, Eigen::Matrix<double, 1, 6>* J) const;
  /// The residual at rotation R and translation t, into r[0] (the grouped solve's cost-only inner loop).
  void Residual(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, double* r) const {
    r[0] = n_map_.dot(R * p_scan_ + t) + d_m_;
  }
  /// EvaluateTangent at rotation R and translation t, into r[0] and J[0..5] (the grouped solve's inner loop).
  void Linearize(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, double* r, double* J) const {
    const Eigen::Vector3d Rp = R * p_scan_;
    r[0] = n_map_.dot(Rp + t) + d_m_;
    const Eigen::Vector3d Rp_x_n = Rp.cross(n_map_);  // -n^T [Rp]x = (Rp x n)^T
    for (int a = 0; a < 3; ++a) {
      J[a] = n_map_(a);
      J[3 + a] = Rp_x_n(a);
    }
  }

 private:
  Eigen::Vector3d p_scan_;
  Eigen::Vector3d n_map_;
  double d_m_;
};

/// Point-to-line residual (2 rows, metres): r = B^T (R p_scan + t - a_map), where B = [b1 b2] is an orthonormal
/// basis of the plane perpendicular to the map line's unit direction u_map. |r| is the point's distance to the
/// line through a_map; unlike the scalar distance, r is smooth at zero, so Gauss-Newton sees a full-rank 2-row
/// Jacobian. `u_map` must be unit length (checked).
class PointToLineResidual final : public ceres::SizedCostFunction<2, 7> {
 public:
  static constexpr int kRows = 2;
  PointToLineResidual(const Eigen::Vector3d& p_scan, const Eigen::Vector3d& a_map, const Eigen::Vector3d& u_map);
  /// Becomes PointToLineResidual(p_scan, a_map, u_map) (same checks, same basis B).
  void Reset(const Eigen::Vector3d& p_scan, const Eigen::Vector3d& a_map, const Eigen::Vector3d& u_map);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  /// Residual at pose T and (if J != nullptr) its Jacobian w.r.t. delta = [dt; dtheta]: [B^T, -B^T [R p]x]
  /// (Linearize / Residual at T's rotation and translation).
  Eigen::Vector2d EvaluateTangent(const Pose3& T, Eigen::Matrix<double, 2, 6>* J) const;
  /// The residual at rotation R and translation t, into r[0..1] (the grouped solve's cost-only inner loop).
  void Residual(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, double* r) const {
    const Eigen::Vector2d v = Bt_ * (R * p_scan_ + t - a_map_);
    r[0] = v(0);
    r[1] = v(1);
  }
  /// EvaluateTangent at rotation R and translation t, into r[0..1] and J (2 x 6, row-major).
  void Linearize(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, double* r, double* J) const {
    const Eigen::Vector3d Rp = R * p_scan_;
    const Eigen::Vector3d e = Rp + t - a_map_;
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d b = Bt_.row(k).transpose();
      r[k] = b.dot(e);
      const Eigen::Vector3d Rp_x_b = Rp.cross(b);
      for (int a = 0; a < 3; ++a) {
        J[6 * k + a] = b(a);
        J[6 * k + 3 + a] = Rp_x_b(a);
      }
    }
  }

 private:
  Eigen::Vector3d p_scan_;
  Eigen::Vector3d a_map_;
  Eigen::Matrix<double, 2, 3> Bt_;  ///< rows b1^T, b2^T
};

}  // namespace rotolidar
