#include "core/registration/local_fits.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

namespace rotolidar {
namespace {

/// Mean and covariance of a small point set (upper triangle summed, mirrored: the same operations in the same
/// order, hence the same bits, as the Eigen form sum (p - mean)(p - mean)^T / n, at a third of its cost).
void MeanCovariance(const std::vector<Eigen::Vector3d>& points, Eigen::Vector3d* mean, Eigen::Matrix3d* cov) {
  *mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) *mean += p;
  const double n = double(points.size());
  *mean /= n;
  double c[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};  // xx xy xz yy yz zz
  for (const auto& p : points) {
    const Eigen::Vector3d d = p - *mean;
    for (int i = 0, e = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) c[e++] += d[i] * d[j];
  }
  for (int i = 0, e = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j, ++e) (*cov)(i, j) = (*cov)(j, i) = c[e] / n;
}

}  // namespace

bool FitLine(const std::vector<Eigen::Vector3d>& points, double min_ratio, Eigen::Vector3d* point,
             Eigen::Vector3d* direction) {
  if (points.size() < 2) return false;
  Eigen::Matrix3d cov;
  MeanCovariance(points, point, &cov);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);  // closed form (ascending): ~3x cheaper than the iterative QL
  if (!(eig.eigenvalues()(2) > 0.0) || eig.eigenvalues()(2) < min_ratio * eig.eigenvalues()(1)) return false;
  *direction = eig.eigenvectors().col(2).normalized();
  return true;
}

bool FitPlane(const std::vector<Eigen::Vector3d>& points, double max_ratio, double max_deviation_m,
              Eigen::Vector3d* normal, double* d_m) {
  if (points.size() < 3) return false;
  Eigen::Vector3d mean;
  Eigen::Matrix3d cov;
  MeanCovariance(points, &mean, &cov);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);
  if (!(eig.eigenvalues()(1) > 0.0) || eig.eigenvalues()(0) > max_ratio * eig.eigenvalues()(1)) return false;
  *normal = eig.eigenvectors().col(0).normalized();
  *d_m = -normal->dot(mean);
  for (const auto& p : points)
    if (std::abs(normal->dot(p) + *d_m) > max_deviation_m) return false;
  return true;
}

}  // namespace rotolidar
