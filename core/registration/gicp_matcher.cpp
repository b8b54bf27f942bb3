#include "core/registration/gicp_matcher.hpp"

#include <cmath>
#include <string>

#include <pcl/filters/voxel_grid.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>

namespace rotolidar {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

Cloud::Ptr ToCloud(const std::vector<Eigen::Vector3d>& points) {
  Cloud::Ptr cloud(new Cloud);
  cloud->reserve(points.size());
  for (const auto& p : points) cloud->push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
  return cloud;
}

/// PCL's GICP keeps its iteration count protected; this exposes it for the result struct.
class Gicp : public pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> {
 public:
  int iterations() const { return nr_iterations_; }
};

}  // namespace

bool GicpConfig::Validate(std::string* error) const {
  auto fail = [&](const char* m) { if (error) *error = m; return false; };
  if (!(max_correspondence_m > 0)) return fail("registration.max_correspondence_m must be > 0");
  if (max_iterations < 1) return fail("registration.max_iterations must be >= 1");
  if (!(transformation_epsilon > 0)) return fail("registration.transformation_epsilon must be > 0");
  if (k_correspondences < 5) return fail("registration.k_correspondences must be >= 5");
  return true;
}

struct GicpMatcher::Impl {
  GicpConfig config;
  Gicp gicp;
  Cloud::Ptr target;
};

GicpMatcher::GicpMatcher(const GicpConfig& config) : impl_(std::make_unique<Impl>()) {
  impl_->config = config;
  impl_->gicp.setMaxCorrespondenceDistance(config.max_correspondence_m);
  impl_->gicp.setMaximumIterations(config.max_iterations);
  impl_->gicp.setTransformationEpsilon(config.transformation_epsilon);
  impl_->gicp.setCorrespondenceRandomness(config.k_correspondences);
}

GicpMatcher::~GicpMatcher() = default;

void GicpMatcher::SetTarget(const std::vector<Eigen::Vector3d>& p_target) {
  impl_->target = ToCloud(p_target);
  impl_->gicp.setInputTarget(impl_->target);
}

RegistrationResult GicpMatcher::Align(const std::vector<Eigen::Vector3d>& p_source,
                                      const Pose3& T_target_source_guess) {
  RegistrationResult result;
  if (!impl_->target || impl_->target->size() < size_t(impl_->config.k_correspondences) ||
      p_source.size() < size_t(impl_->config.k_correspondences))
    return result;
  Cloud::Ptr source = ToCloud(p_source);
  impl_->gicp.setInputSource(source);
  Cloud aligned;
  impl_->gicp.align(aligned, T_target_source_guess.matrix().cast<float>());
  result.converged = impl_->gicp.hasConverged();
  result.iterations = impl_->gicp.iterations();
  // Re-express the float result in double, re-orthonormalising the rotation.
  const Eigen::Matrix4d M = impl_->gicp.getFinalTransformation().cast<double>();
  result.T_target_source = MakePose(M.block<3, 1>(0, 3), Eigen::Quaterniond(M.block<3, 3>(0, 0)));
  // Inliers and their RMS distance, with the target kd-tree GICP already built.
  const auto tree = impl_->gicp.getSearchMethodTarget();
  std::vector<int> idx(1);
  std::vector<float> sq(1);
  const double max_sq = impl_->config.max_correspondence_m * impl_->config.max_correspondence_m;
  double sum_sq = 0.0;
  for (const auto& p : aligned.points) {
    if (tree->nearestKSearch(p, 1, idx, sq) == 1 && sq[0] <= max_sq) {
      ++result.num_inliers;
      sum_sq += sq[0];
    }
  }
  result.rmse_m = result.num_inliers ? std::sqrt(sum_sq / double(result.num_inliers)) : 0.0;
  return result;
}

std::vector<Eigen::Vector3d> VoxelDownsample(const std::vector<Eigen::Vector3d>& points, double voxel_size_m) {
  Cloud::Ptr cloud = ToCloud(points);
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(cloud);
  grid.setLeafSize(float(voxel_size_m), float(voxel_size_m), float(voxel_size_m));
  Cloud out;
  grid.filter(out);
  std::vector<Eigen::Vector3d> result;
  result.reserve(out.size());
  for (const auto& p : out.points) result.emplace_back(p.x, p.y, p.z);
  return result;
}

}  // namespace rotolidar
