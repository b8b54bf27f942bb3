#pragma once
// Line and plane fits of a scan point's map neighbours (LOAM mapping), used by scan-to-map registration.
// Points in any one frame [m]; pure functions, thread-safe; a rejected fit returns false and leaves no promise
// about the outputs.
#include <vector>

#include <Eigen/Core>

namespace rotolidar {

/// LOAM line fit of neighbours (map frame): true when lambda_max >= min_ratio * lambda_mid of their covariance;
/// *point = centroid, *direction = unit principal axis.
bool FitLine(const std::vector<Eigen::Vector3d>& points, double min_ratio, Eigen::Vector3d* point,
             Eigen::Vector3d* direction);
/// Plane fit of neighbours: true when lambda_min <= max_ratio * lambda_mid and every point lies within
/// max_deviation_m of the plane; the plane is {x : normal . x + d = 0}, |normal| = 1.
bool FitPlane(const std::vector<Eigen::Vector3d>& points, double max_ratio, double max_deviation_m,
              Eigen::Vector3d* normal, double* d_m);

}  // namespace rotolidar
