#include "core/registration/residuals.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/log.hpp"

namespace rotolidar {
namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

/// The transformed scan point R p + t for a raw pose block.
Eigen::Vector3d TransformPoint(const double* pose, const Eigen::Vector3d& p, Eigen::Quaterniond* q_out) {
  const Eigen::Map<const Eigen::Vector3d> t(pose);
  const Eigen::Map<const Eigen::Quaterniond> q(pose + 3);
  *q_out = q;
  return q * p + t;  // Eigen's q * v normalises nothing: the manifold keeps q unit
}

/// a^T RotatedPointQuaternionJacobian(q, p) (1x4), with vector algebra only (the same extension off the sphere).
Eigen::Matrix<double, 1, 4> ProjectedQuaternionJacobian(const Eigen::Vector3d& a, const Eigen::Quaterniond& q,
                                                        const Eigen::Vector3d& p) {
  const Eigen::Vector3d v = q.vec();
  const double w = q.w();
  // a^T (-2 w [p]x) = -2 w (a x p)^T;  a^T 2((v.p) I + v p^T - 2 p v^T) = 2 ((v.p) a + (a.v) p - 2 (a.p) v)^T
  const Eigen::Vector3d dv = -2.0 * w * a.cross(p) + 2.0 * (v.dot(p) * a + a.dot(v) * p - 2.0 * a.dot(p) * v);
  Eigen::Matrix<double, 1, 4> J;
  J << dv.transpose(), 2.0 * a.dot(v.cross(p));
  return J;
}

}  // namespace

PoseParameters PoseToParameters(const Pose3& T) {
  const Eigen::Quaterniond q = Eigen::Quaterniond(T.linear()).normalized();
  const Eigen::Vector3d t = T.translation();
  return {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
}

Pose3 ParametersToPose(const double* parameters) {
  const Eigen::Quaterniond q(parameters[6], parameters[3], parameters[4], parameters[5]);
  return MakePose(Eigen::Vector3d(parameters[0], parameters[1], parameters[2]), q);
}

Pose3 PoseBoxPlus(const Pose3& T, const Vector6d& delta) {
  Pose3 out = Pose3::Identity();
  out.linear() = ExpSO3(delta.tail<3>()) * T.linear();
  out.translation() = T.translation() + delta.head<3>();
  return out;
}

Vector6d PoseBoxMinus(const Pose3& T_y, const Pose3& T_x) {
  Vector6d delta;
  delta << T_y.translation() - T_x.translation(), LogSO3(T_y.linear() * T_x.linear().transpose());
  return delta;
}

Eigen::Matrix<double, 3, 4> RotatedPointQuaternionJacobian(const Eigen::Quaterniond& q, const Eigen::Vector3d& p) {
  const Eigen::Vector3d v = q.vec();
  const double w = q.w();
  Eigen::Matrix<double, 3, 4> J;
  // d/dv [2 w (v x p)] = -2 w [p]x ;  d/dv [2 v x (v x p)] = 2 ((v.p) I + v p^T - 2 p v^T)
  J.leftCols<3>() = -2.0 * w * Skew(p) +
                    2.0 * (v.dot(p) * Eigen::Matrix3d::Identity() + v * p.transpose() - 2.0 * p * v.transpose());
  J.col(3) = 2.0 * v.cross(p);  // d/dw
  return J;
}

PointToPlaneResidual::PointToPlaneResidual(const Eigen::Vector3d& p_scan, const Eigen::Vector3d& n_map, double d_m,
                                           double weight) {
  Reset(p_scan, n_map, d_m, weight);
}

void PointToPlaneResidual::Reset(const Eigen::Vector3d& p_scan, const Eigen::Vector3d& n_map, double d_m,
                                 double weight) {
  ROTOLIDAR_CHECK(std::abs(n_map.norm() - 1.0) < 1e-6, "plane normal must be unit, |n| = " << n_map.norm());
  ROTOLIDAR_CHECK(weight > 0.0 && std::isfinite(weight), "plane weight must be > 0, w = " << weight);
  p_scan_ = p_scan;
  n_map_ = weight * n_map;  // r is linear in (n, d): the weight rides on them
  d_m_ = weight * d_m;
}

bool PointToPlaneResidual::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  Eigen::Quaterniond q;
  const Eigen::Vector3d p_map = TransformPoint(parameters[0], p_scan_, &q);
  residuals[0] = n_map_.dot(p_map) + d_m_;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 1, 7, Eigen::RowMajor>> J(jacobians[0]);
    J.leftCols<3>() = n_map_.transpose();
    J.rightCols<4>() = ProjectedQuaternionJacobian(n_map_, q, p_scan_);
  }
  return true;
}

double PointToPlaneResidual::EvaluateTangent(const Pose3& T, Eigen::Matrix<double, 1, 6>* J) const {
  double r = 0.0;
  if (J != nullptr)
    Linearize(T.linear(), T.translation(), &r, J->data());  // a row vector: row- and column-major alike
  else
    Residual(T.linear(), T.translation(), &r);
  return r;
}

PointToLineResidual::PointToLineResidual(const Eigen::Vector3d& p_scan, const Eigen::Vector3d& a_map,
                                         const Eigen::Vector3d& u_map) {
  Reset(p_scan, a_map, u_map);
}

void PointToLineResidual::Reset(const Eigen::Vector3d& p_scan, const Eigen::Vector3d& a_map,
                                const Eigen::Vector3d& u_map) {
  p_scan_ = p_scan;
  a_map_ = a_map;
  ROTOLIDAR_CHECK(std::abs(u_map.norm() - 1.0) < 1e-6, "line direction must be unit, |u| = " << u_map.norm());
  // b1: u crossed with the world axis least aligned with u (well conditioned); b2 = u x b1.
  Eigen::Index axis = 0;
  u_map.cwiseAbs().minCoeff(&axis);
  const Eigen::Vector3d b1 = u_map.cross(Eigen::Vector3d::Unit(axis)).normalized();
  const Eigen::Vector3d b2 = u_map.cross(b1);
  Bt_.row(0) = b1.transpose();
  Bt_.row(1) = b2.transpose();
}

bool PointToLineResidual::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  Eigen::Quaterniond q;
  const Eigen::Vector3d p_map = TransformPoint(parameters[0], p_scan_, &q);
  Eigen::Map<Eigen::Vector2d> r(residuals);
  r = Bt_ * (p_map - a_map_);
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 2, 7, Eigen::RowMajor>> J(jacobians[0]);
    J.leftCols<3>() = Bt_;
    J.block<1, 4>(0, 3) = ProjectedQuaternionJacobian(Bt_.row(0).transpose(), q, p_scan_);
    J.block<1, 4>(1, 3) = ProjectedQuaternionJacobian(Bt_.row(1).transpose(), q, p_scan_);
  }
  return true;
}

Eigen::Vector2d PointToLineResidual::EvaluateTangent(const Pose3& T, Eigen::Matrix<double, 2, 6>* J) const {
  Eigen::Vector2d r;
  if (J == nullptr) {
    Residual(T.linear(), T.translation(), r.data());
    return r;
  }
  Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J_rows;  // Linearize's layout
  Linearize(T.linear(), T.translation(), r.data(), J_rows.data());
  *J = J_rows;
  return r;
}

}  // namespace rotolidar

