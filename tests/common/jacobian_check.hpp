#pragma once
// Analytic Jacobians against Ceres' numeric differentiation, shared by the factor tests.
#include <algorithm>
#include <memory>
#include <vector>

#include <ceres/gradient_checker.h>
#include <ceres/manifold.h>
#include <Eigen/Core>
#include <gtest/gtest.h>

#include "core/imu/imu_factor.hpp"

namespace rotolidar::test_util {

/// max |a - n| / (1 + |n|) over the entries: relative where the numeric value is large, absolute near zero.
inline double MaxMixedError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& n) {
  return ((a - n).array().abs() / (1.0 + n.array().abs())).maxCoeff();
}

/// Worst mixed error between analytic and numeric Jacobians (tangent and ambient) of `cost` at `blocks`; blocks of
/// size 7 get the pose manifold (MakeImuPoseManifold). `relative_step`: Ridders' initial step, also its minimum
/// absolute step (Ceres' default 1e-2 is too coarse for a block whose value is ~1e-2, e.g. an inverse depth).
inline double JacobianError(const ceres::CostFunction& cost, const std::vector<double*>& blocks,
                            double relative_step = ceres::NumericDiffOptions{}.ridders_relative_initial_step_size) {
  const std::unique_ptr<ceres::Manifold> pose_manifold = MakeImuPoseManifold();
  std::vector<const ceres::Manifold*> manifolds;
  for (size_t k = 0; k < blocks.size(); ++k)
    manifolds.push_back(cost.parameter_block_sizes()[k] == kImuPoseBlockSize ? pose_manifold.get() : nullptr);
  ceres::NumericDiffOptions options;
  options.ridders_relative_initial_step_size = relative_step;
  ceres::GradientChecker checker(&cost, &manifolds, options);
  ceres::GradientChecker::ProbeResults results;
  std::vector<const double*> parameters(blocks.begin(), blocks.end());
  checker.Probe(parameters.data(), 1e-5, &results);
  EXPECT_TRUE(results.return_value);
  double worst = 0.0;
  for (size_t k = 0; k < blocks.size(); ++k) {
    worst = std::max(worst, MaxMixedError(results.local_jacobians[k], results.local_numeric_jacobians[k]));
    worst = std::max(worst, MaxMixedError(results.jacobians[k], results.numeric_jacobians[k]));
  }
  return worst;
}

}  // namespace rotolidar::test_util
