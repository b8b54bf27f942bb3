#include "core/visual/feature_depth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/util/validation.hpp"

namespace rotolidar::visual {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

bool Finite(double v) { return std::isfinite(v); }

FeatureDepth Reject(FeatureDepth out, DepthStatus status) {
  out.valid = false;
  out.status = status;
  return out;
}

/// Smallest standard deviation [rad] of the bearings `idx` of `points` across any direction of the tangent plane at
/// `bearing` (the square root of the 2x2 covariance's smaller eigenvalue).
double MinBearingSpreadRad(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& idx,
                           const Eigen::Vector3d& bearing) {
  const Eigen::Vector3d e1 = bearing.unitOrthogonal(), e2 = bearing.cross(e1);
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
  for (int i : idx) {
    const Eigen::Vector3d b = points[size_t(i)].normalized();
    const Eigen::Vector2d u(e1.dot(b), e2.dot(b));
    mean += u;
    second += u * u.transpose();
  }
  const double n = double(idx.size());
  mean /= n;
  const Eigen::Matrix2d cov = second / n - mean * mean.transpose();
  const double half_trace = 0.5 * (cov(0, 0) + cov(1, 1)), half_diff = 0.5 * (cov(0, 0) - cov(1, 1));
  return std::sqrt(std::max(0.0, half_trace - std::sqrt(half_diff * half_diff + cov(0, 1) * cov(0, 1))));
}

/// A plane not through the camera centre as the points p with w . p = 1 (w = n / d for n . p = d). Along a unit
/// bearing b it lies at range 1 / (w . b): the inverse range is linear in the bearing.
struct Plane {
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  double rms_m = 0.0;  ///< RMS range residual of the points along their own bearings [m]
};

/// Fits the plane to the points `idx` by least squares on their range residuals r_i - 1 / (w . b_i), linearised as
/// r_i (w . p_i - 1): LiDAR noise is range noise, so this is the maximum-likelihood plane. A PCA plane (smallest
/// covariance eigenvector) is not: when the patch is narrow against the noise it turns to contain the rays (the
/// noise's direction) and reads as grazing (measured on the tests' dense floor with 24 neighbours: 5-9 deg for
/// 10-20 deg true, and every ray there rejected as grazing).
Plane FitPlane(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& idx) {
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int i : idx) {
    const Eigen::Vector3d& p = points[size_t(i)];
    const double r2 = p.squaredNorm();
    M += r2 * p * p.transpose();
    v += r2 * p;
  }
  Plane plane;
  plane.w = M.ldlt().solve(v);
  double sum = 0.0;
  for (int i : idx) {
    const Eigen::Vector3d& p = points[size_t(i)];
    const double wb = plane.w.dot(p.normalized());
    const double e = wb > 0.0 ? p.norm() - 1.0 / wb : std::numeric_limits<double>::infinity();
    sum += e * e;
  }
  plane.rms_m = std::sqrt(sum / double(idx.size()));
  return plane;
}

}  // namespace

const char* ToString(DepthStatus status) {
  switch (status) {
    case DepthStatus::kValid: return "valid";
    case DepthStatus::kInvalidConfig: return "invalid config";
    case DepthStatus::kInvalidInput: return "invalid input";
    case DepthStatus::kNoPoints: return "no points";
    case DepthStatus::kDepthEdge: return "depth edge";
    case DepthStatus::kCollinear: return "collinear";
    case DepthStatus::kNotPlanar: return "not planar";
    case DepthStatus::kGrazing: return "grazing";
    case DepthStatus::kOutOfRange: return "out of range";
  }
  return "unknown";
}

bool LidarDepthConfig::Validate(std::string* error) const {
  if (!(search_radius_deg > 0.0 && search_radius_deg <= 30.0))
    return FailValidation(error, "feature_depth.search_radius_deg must be in (0, 30]");
  if (min_neighbours < 3) return FailValidation(error, "feature_depth.min_neighbours must be >= 3");
  if (max_neighbours < min_neighbours || max_neighbours > 1000)
    return FailValidation(error, "feature_depth.max_neighbours must be in [min_neighbours, 1000]");
  if (!(max_depth_spread_m > 0.0) || !Finite(max_depth_spread_m))
    return FailValidation(error, "feature_depth.max_depth_spread_m must be > 0 and finite");
  if (!(min_bearing_spread_deg >= 0.0 && min_bearing_spread_deg < search_radius_deg))
    return FailValidation(error, "feature_depth.min_bearing_spread_deg must be in [0, search_radius_deg)");
  if (!(max_plane_rms_m > 0.0) || !Finite(max_plane_rms_m))
    return FailValidation(error, "feature_depth.max_plane_rms_m must be > 0 and finite");
  if (!(min_incidence_deg >= 0.0 && min_incidence_deg < 90.0))
    return FailValidation(error, "feature_depth.min_incidence_deg must be in [0, 90)");
  if (!(min_depth_m > 0.0) || !Finite(min_depth_m))
    return FailValidation(error, "feature_depth.min_depth_m must be > 0 and finite");
  if (!(max_depth_m > min_depth_m) || !Finite(max_depth_m))
    return FailValidation(error, "feature_depth.max_depth_m must be > min_depth_m and finite");
  return true;
}

struct LidarDepthMap::Index {
  pcl::PointCloud<pcl::PointXYZ>::Ptr bearings{new pcl::PointCloud<pcl::PointXYZ>};
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
};

LidarDepthMap::LidarDepthMap(const LidarDepthConfig& config) : config_(config), index_(new Index) {
  if (!config_.Validate(&config_error_) && config_error_.empty()) config_error_ = "invalid config";
}
LidarDepthMap::~LidarDepthMap() = default;
LidarDepthMap::LidarDepthMap(LidarDepthMap&&) noexcept = default;
LidarDepthMap& LidarDepthMap::operator=(LidarDepthMap&&) noexcept = default;

size_t LidarDepthMap::Build(const std::vector<Eigen::Vector3d>& points_cam) {
  return Build(points_cam, Pose3::Identity());
}

size_t LidarDepthMap::Build(const std::vector<Eigen::Vector3d>& points, const Pose3& T_cam_points) {
  points_.clear();
  index_.reset(new Index);
  if (!config_valid() || !T_cam_points.matrix().allFinite()) return 0;
  points_.reserve(points.size());
  index_->bearings->reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    if (!p.allFinite()) continue;
    const Eigen::Vector3d p_cam = T_cam_points * p;
    if (!(p_cam.z() > config_.min_depth_m)) continue;
    points_.push_back(p_cam);
    const Eigen::Vector3f b = p_cam.normalized().cast<float>();
    index_->bearings->push_back(pcl::PointXYZ(b.x(), b.y(), b.z()));
  }
  if (!points_.empty()) index_->tree.setInputCloud(index_->bearings);
  return points_.size();
}

FeatureDepth LidarDepthMap::Query(const Eigen::Vector2d& xy_normalised) const {
  FeatureDepth out;
  if (!config_valid()) return Reject(out, DepthStatus::kInvalidConfig);
  if (!xy_normalised.allFinite()) return Reject(out, DepthStatus::kInvalidInput);
  if (points_.empty() || !index_) return Reject(out, DepthStatus::kNoPoints);
  const Eigen::Vector3d ray(xy_normalised.x(), xy_normalised.y(), 1.0);  // z = 1: its multiple is the depth
  const Eigen::Vector3d bearing = ray.normalized();
  // Nearest bearings, then the radius: the chord between unit vectors at angle a is 2 sin(a / 2).
  std::vector<int> idx;
  std::vector<float> sq_chord;
  index_->tree.nearestKSearch(pcl::PointXYZ(float(bearing.x()), float(bearing.y()), float(bearing.z())),
                              config_.max_neighbours, idx, sq_chord);
  const double max_chord = 2.0 * std::sin(0.5 * config_.search_radius_deg * kDegToRad);
  size_t n = 0;
  while (n < idx.size() && double(sq_chord[n]) <= max_chord * max_chord) ++n;  // sorted by distance
  idx.resize(n);
  out.num_neighbours = int(n);
  if (out.num_neighbours < config_.min_neighbours) return Reject(out, DepthStatus::kNoPoints);

  double min_range = std::numeric_limits<double>::infinity(), max_range = 0.0;
  for (int i : idx) {
    const double r = points_[size_t(i)].norm();
    min_range = std::min(min_range, r);
    max_range = std::max(max_range, r);
  }
  out.range_spread_m = max_range - min_range;
  if (out.range_spread_m > config_.max_depth_spread_m) return Reject(out, DepthStatus::kDepthEdge);
  if (MinBearingSpreadRad(points_, idx, bearing) < config_.min_bearing_spread_deg * kDegToRad)
    return Reject(out, DepthStatus::kCollinear);

  const Plane plane = FitPlane(points_, idx);
  out.plane_rms_m = plane.rms_m;
  if (!plane.w.allFinite() || !(plane.rms_m <= config_.max_plane_rms_m)) return Reject(out, DepthStatus::kNotPlanar);
  const double w_dot_ray = plane.w.dot(ray);  // the ray s (x, y, 1) meets the plane at s = z = 1 / (w . ray)
  out.incidence_deg = std::asin(std::min(1.0, std::abs(plane.w.dot(bearing)) / plane.w.norm())) / kDegToRad;
  if (out.incidence_deg < config_.min_incidence_deg) return Reject(out, DepthStatus::kGrazing);
  if (!(w_dot_ray > 0.0)) return Reject(out, DepthStatus::kOutOfRange);  // the plane is behind the camera
  out.depth_m = 1.0 / w_dot_ray;
  out.range_m = out.depth_m * ray.norm();
  if (!(out.depth_m >= config_.min_depth_m && out.depth_m <= config_.max_depth_m))
    return Reject(out, DepthStatus::kOutOfRange);
  out.valid = true;
  out.status = DepthStatus::kValid;
  return out;
}

std::vector<FeatureDepth> LidarDepthMap::Query(const std::vector<Eigen::Vector2d>& xy_normalised) const {
  std::vector<FeatureDepth> out;
  out.reserve(xy_normalised.size());
  for (const Eigen::Vector2d& xy : xy_normalised) out.push_back(Query(xy));
  return out;
}

RayNeighbourhood::RayNeighbourhood(const std::vector<Eigen::Vector2d>& xy_normalised, double radius_rad)
    : rays_(Eigen::Index(xy_normalised.size()), 3), min_cos_(float(std::cos(radius_rad + 1e-4))) {
  for (size_t i = 0; i < xy_normalised.size(); ++i)
    rays_.row(Eigen::Index(i)) = xy_normalised[i].homogeneous().normalized().cast<float>();
}

// ------------------------------------------------------------------------------------------------ triangulation

namespace {

Triangulation Fail(Triangulation out, TriangulationStatus status) {
  out.valid = false;
  out.status = status;
  return out;
}

/// Largest angle [rad] between two of the unit directions.
double MaxAngle(const std::vector<Eigen::Vector3d>& dirs) {
  double best = 0.0;
  for (size_t i = 0; i < dirs.size(); ++i)
    for (size_t j = i + 1; j < dirs.size(); ++j)
      best = std::max(best, std::atan2(dirs[i].cross(dirs[j]).norm(), dirs[i].dot(dirs[j])));
  return best;
}

/// The observations' geometry relative to the anchor camera's centre (keeps the solve well conditioned far from
/// the world origin): p_cam_k = R[k] * y + t[k] for a point y = p_world - anchor centre.
struct Views {
  std::vector<Eigen::Matrix3d> R;
  std::vector<Eigen::Vector3d> t, centre, dir;  ///< dir: unit ray, world axes
};

/// Sum of squared normalised-plane residuals of y; false when y is not in front (z > 0) of every camera.
bool Cost(const Views& v, const std::vector<Eigen::Vector2d>& xy, const Eigen::Vector3d& y, double* cost) {
  *cost = 0.0;
  bool in_front = true;
  for (size_t k = 0; k < xy.size(); ++k) {
    const Eigen::Vector3d p = v.R[k] * y + v.t[k];
    in_front = in_front && p.z() > 0.0;
    *cost += (p.head<2>() / p.z() - xy[k]).squaredNorm();
  }
  return in_front;
}

/// Gauss-Newton on the normalised-plane reprojection error; a step is kept only when it lowers the cost.
int GaussNewton(const Views& v, const std::vector<Eigen::Vector2d>& xy, int max_iterations, Eigen::Vector3d* y) {
  double cost = 0.0;
  Cost(v, xy, *y, &cost);
  int it = 0;
  for (; it < max_iterations; ++it) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < xy.size(); ++k) {
      const Eigen::Vector3d p = v.R[k] * *y + v.t[k];
      if (std::abs(p.z()) < 1e-9) return it;  // on a camera's focal plane: no linearisation
      const double iz = 1.0 / p.z();
      Eigen::Matrix<double, 2, 3> dpi;
      dpi << iz, 0.0, -p.x() * iz * iz, 0.0, iz, -p.y() * iz * iz;
      const Eigen::Matrix<double, 2, 3> J = dpi * v.R[k];
      const Eigen::Vector2d r = p.head<2>() * iz - xy[k];
      H += J.transpose() * J;
      g += J.transpose() * r;
    }
    const Eigen::Vector3d step = -H.ldlt().solve(g);
    double new_cost = 0.0;
    if (!step.allFinite()) return it;
    Cost(v, xy, *y + step, &new_cost);
    if (!(new_cost < cost)) return it;
    *y += step;
    cost = new_cost;
    if (step.norm() < 1e-12 * (1.0 + y->norm())) return it + 1;
  }
  return it;
}

}  // namespace

const char* ToString(TriangulationStatus status) {
  switch (status) {
    case TriangulationStatus::kValid: return "valid";
    case TriangulationStatus::kInvalidConfig: return "invalid config";
    case TriangulationStatus::kInvalidInput: return "invalid input";
    case TriangulationStatus::kLowParallax: return "low parallax";
    case TriangulationStatus::kDegenerate: return "degenerate";
    case TriangulationStatus::kBehindCamera: return "behind camera";
    case TriangulationStatus::kLargeReprojection: return "large reprojection error";
  }
  return "unknown";
}

bool TriangulationConfig::Validate(std::string* error) const {
  if (!(min_parallax_deg >= 0.0 && min_parallax_deg < 180.0))
    return FailValidation(error, "triangulation.min_parallax_deg must be in [0, 180)");
  if (!(max_reprojection_rms_px > 0.0) || !Finite(max_reprojection_rms_px))
    return FailValidation(error, "triangulation.max_reprojection_rms_px must be > 0 and finite");
  if (!(focal_length_px > 0.0) || !Finite(focal_length_px))
    return FailValidation(error, "triangulation.focal_length_px must be > 0 and finite");
  if (!(min_depth_m >= 0.0) || !Finite(min_depth_m))
    return FailValidation(error, "triangulation.min_depth_m must be >= 0 and finite");
  if (max_iterations < 0 || max_iterations > 100)
    return FailValidation(error, "triangulation.max_iterations must be in [0, 100]");
  return true;
}

Triangulation TriangulateFeature(const std::vector<Eigen::Vector2d>& xy_normalised,
                                 const std::vector<Pose3>& T_world_cam, const TriangulationConfig& config) {
  Triangulation out;
  if (!config.Validate(nullptr)) return Fail(out, TriangulationStatus::kInvalidConfig);
  const size_t n = xy_normalised.size();
  if (n < 2 || T_world_cam.size() != n) return Fail(out, TriangulationStatus::kInvalidInput);
  for (size_t k = 0; k < n; ++k)
    if (!xy_normalised[k].allFinite() || !T_world_cam[k].matrix().allFinite())
      return Fail(out, TriangulationStatus::kInvalidInput);

  const Eigen::Vector3d anchor = T_world_cam[0].translation();
  Views v;
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Matrix3d R_wc = T_world_cam[k].linear();
    v.R.push_back(R_wc.transpose());
    v.centre.push_back(T_world_cam[k].translation() - anchor);
    v.t.push_back(-v.R.back() * v.centre.back());
    v.dir.push_back((R_wc * xy_normalised[k].homogeneous()).normalized());
  }
  out.parallax_rad = MaxAngle(v.dir);
  if (out.parallax_rad < config.min_parallax_deg * kDegToRad) return Fail(out, TriangulationStatus::kLowParallax);

  // Midpoint: argmin_y sum_k |(I - d_k d_k^T)(y - c_k)|^2.
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - v.dir[k] * v.dir[k].transpose();
    A += P;
    b += P * v.centre[k];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(A);
  if (!(eig.eigenvalues()(0) > 1e-12 * eig.eigenvalues()(2))) return Fail(out, TriangulationStatus::kDegenerate);
  Eigen::Vector3d y = A.ldlt().solve(b);
  if (!y.allFinite()) return Fail(out, TriangulationStatus::kDegenerate);
  out.iterations = GaussNewton(v, xy_normalised, config.max_iterations, &y);

  out.point_world = anchor + y;
  out.depth_anchor_m = (v.R[0] * y + v.t[0]).z();
  double cost = 0.0;
  Cost(v, xy_normalised, y, &cost);
  out.reprojection_rms_px = std::sqrt(cost / double(2 * n)) * config.focal_length_px;
  for (size_t k = 0; k < n; ++k)
    if (!((v.R[k] * y + v.t[k]).z() > config.min_depth_m)) return Fail(out, TriangulationStatus::kBehindCamera);
  if (!(out.reprojection_rms_px <= config.max_reprojection_rms_px))
    return Fail(out, TriangulationStatus::kLargeReprojection);
  out.valid = true;
  out.status = TriangulationStatus::kValid;
  return out;
}

}  // namespace rotolidar::visual
