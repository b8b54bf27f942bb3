// Geometric verification of loop candidates on synthetic submaps: points sampled on the surfaces of an indoor hall
// (walls, floor, ceiling, pillars, shelves), cut to a radius around a keyframe and expressed in its frame, as an
// accumulated keyframe submap would be (no occlusion: several scans fill the shadows).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

#include <Eigen/Eigenvalues>

#include "core/loop/geometric_verification.hpp"
#include "core/types/geometry.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::loop {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Box {
  Eigen::Vector3d lo, hi;
};

/// A hall of boxes (world frame): floor and ceiling (zero thickness: one surface each), four walls, pillars, and
/// shelves placed by `seed`. `size_x_m` lets two halls differ in shape as well as in content.
std::vector<Box> Hall(uint64_t seed, double size_x_m = 40.0) {
  RandomStream rng(seed, "verification-hall");
  const double hx = size_x_m / 2;
  std::vector<Box> boxes = {{{-hx, -13, 0}, {hx, 13, 0}},          {{-hx, -13, 4.5}, {hx, 13, 4.5}},
                            {{-hx - 0.5, -13, 0}, {-hx, 13, 4.5}}, {{hx, -13, 0}, {hx + 0.5, 13, 4.5}},
                            {{-hx, -13.5, 0}, {hx, -13, 4.5}},     {{-hx, 13, 0}, {hx, 13.5, 4.5}}};
  for (double x = -hx + 4; x <= hx - 4; x += 8)
    for (double y = -8; y <= 8; y += 8) boxes.push_back({{x - 0.25, y - 0.25, 0}, {x + 0.25, y + 0.25, 4.5}});
  for (int i = 0; i < 16; ++i) {
    const double x = -hx + 2 + (size_x_m - 7) * rng.Uniform(), y = -11 + 20 * rng.Uniform();
    const bool along_x = rng.Uniform() < 0.5;
    const double lx = along_x ? 3 + 4 * rng.Uniform() : 0.8, ly = along_x ? 0.8 : 3 + 4 * rng.Uniform();
    boxes.push_back({{x, y, 0}, {x + lx, y + ly, 0.6 + 2.4 * rng.Uniform()}});
  }
  return boxes;
}

/// Points uniform over the boxes' surfaces (one per `area_per_point_m2`), within `radius_m` of T_world_kf's origin,
/// in the keyframe frame, with isotropic noise `noise_m`.
std::vector<Eigen::Vector3d> Submap(const std::vector<Box>& boxes, const Pose3& T_world_kf, double radius_m,
                                    double noise_m, RandomStream* rng, double area_per_point_m2 = 0.01) {
  const Pose3 T_kf_world = T_world_kf.inverse();
  std::vector<Eigen::Vector3d> points;
  for (const Box& b : boxes) {
    const Eigen::Vector3d e = b.hi - b.lo;
    for (int axis = 0; axis < 3; ++axis) {  // the faces normal to `axis` (one when the box is flat along it)
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const int n = int(e[u] * e[v] / area_per_point_m2);
      for (int side = 0; side < (e[axis] > 0 ? 2 : 1); ++side) {
        for (int i = 0; i < n; ++i) {
          Eigen::Vector3d p = b.lo;
          p[axis] += side * e[axis];
          p[u] += rng->Uniform() * e[u];
          p[v] += rng->Uniform() * e[v];
          if ((p - T_world_kf.translation()).norm() > radius_m) continue;
          points.push_back(T_kf_world * p + noise_m * Eigen::Vector3d(rng->Normal(), rng->Normal(), rng->Normal()));
        }
      }
    }
  }
  return points;
}

Pose3 KeyframePose(double x, double y, double z, double yaw_rad) {
  Pose3 T = RotZ(yaw_rad);
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

double AngleOf(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle(); }

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// VerifyLoop with its wall time printed.
LoopVerification TimedVerify(const char* label, const std::vector<Eigen::Vector3d>& source,
                             const std::vector<Eigen::Vector3d>& target, const Pose3& guess,
                             const LoopVerificationConfig& config = {}) {
  const auto t0 = std::chrono::steady_clock::now();
  const LoopVerification r = VerifyLoop(source, target, guess, config);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[%s] VerifyLoop %zu/%zu points (%zu/%zu downsampled): %.0f ms, %d iterations, converged %d, "
              "overlap %.3f, rmse %.4f m, accepted %d '%s'\n",
              label, source.size(), target.size(), r.num_source_points, r.num_target_points, ms, r.iterations,
              r.converged, r.overlap, r.fitness_rmse_m, r.accepted, r.reason.c_str());
  return r;
}

/// Translation [m] and rotation [rad] errors of an estimate.
std::pair<double, double> Errors(const Pose3& estimate, const Pose3& truth) {
  return {(estimate.translation() - truth.translation()).norm(),
          AngleOf(estimate.linear().transpose() * truth.linear())};
}

TEST(LoopVerificationConfig, ValidatesEveryField) {
  std::string error;
  EXPECT_TRUE(LoopVerificationConfig{}.Validate(&error)) << error;
  const auto fails_on = [](const char* field, auto mutate) {
    LoopVerificationConfig c;
    mutate(c);
    std::string e;
    return !c.Validate(&e) && e.find(field) != std::string::npos;
  };
  EXPECT_TRUE(fails_on("voxel_m", [](auto& c) { c.voxel_m = -0.1; }));
  EXPECT_TRUE(fails_on("max_correspondence_m", [](auto& c) { c.max_correspondence_m = 0.1; }));
  EXPECT_TRUE(fails_on("fine_correspondence_m", [](auto& c) { c.fine_correspondence_m = 0; }));
  EXPECT_TRUE(fails_on("max_iterations", [](auto& c) { c.max_iterations = 0; }));
  EXPECT_TRUE(fails_on("min_points", [](auto& c) { c.min_points = 5; }));
  EXPECT_TRUE(fails_on("min_overlap", [](auto& c) { c.min_overlap = 1.5; }));
  EXPECT_TRUE(fails_on("max_fitness_rmse_m", [](auto& c) { c.max_fitness_rmse_m = 0; }));
  EXPECT_TRUE(fails_on("structure_max_normal_z", [](auto& c) { c.structure_max_normal_z = 2; }));
}

TEST(LoopVerification, RecoversAKnownTransformFromAnOffGuess) {
  const std::vector<Box> hall = Hall(21);
  RandomStream rng(22, "verification-known-transform");
  // Source keyframe 1 m from the target one and turned by 30 deg; submaps of 12 m radius, 1 cm noise.
  const Pose3 T_w_t = KeyframePose(-3, 1, 1.5, 0.3);
  const Pose3 T_w_s = KeyframePose(-3 + 0.8, 1 + 0.6, 1.5, 0.3 + 30 * kDeg);
  const std::vector<Eigen::Vector3d> target = Submap(hall, T_w_t, 12, 0.01, &rng);
  const std::vector<Eigen::Vector3d> source = Submap(hall, T_w_s, 12, 0.01, &rng);
  const Pose3 T_t_s = T_w_t.inverse() * T_w_s;
  // The guess is off by 5 deg of yaw and 0.5 m.
  Pose3 guess = T_t_s * RotZ(5 * kDeg);
  guess.translation() += Eigen::Vector3d(0.3, -0.4, 0.0);
  const LoopVerification r = TimedVerify("known transform", source, target, guess);
  const auto [dt, dr] = Errors(r.T_target_source, T_t_s);
  const Eigen::Matrix<double, 6, 1> sigma = r.covariance.diagonal().cwiseSqrt();
  std::printf("error %.4f m %.4f deg; sigma t %.4f %.4f %.4f m, r %.4f %.4f %.4f deg\n", dt, dr / kDeg, sigma[0],
              sigma[1], sigma[2], sigma[3] / kDeg, sigma[4] / kDeg, sigma[5] / kDeg);
  EXPECT_TRUE(r.accepted) << r.reason;
  EXPECT_TRUE(r.converged);
  EXPECT_TRUE(r.reason.empty());
  EXPECT_LT(dt, 0.01);
  EXPECT_LT(dr, 0.05 * kDeg);
  EXPECT_GE(r.overlap, 0.8);
  EXPECT_LE(r.fitness_rmse_m, 0.12);
  // Symmetric positive definite covariance.
  EXPECT_LT((r.covariance - r.covariance.transpose()).norm(), 1e-12 * r.covariance.norm());
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6d>(r.covariance).eigenvalues()(0), 0.0);
}

TEST(LoopVerification, RejectsTwoDifferentPlaces) {
  RandomStream rng(23, "verification-different");
  const std::vector<Eigen::Vector3d> target = Submap(Hall(21), KeyframePose(-3, 1, 1.5, 0.3), 12, 0.01, &rng);
  const std::vector<Eigen::Vector3d> source = Submap(Hall(99, 30), KeyframePose(4, -2, 1.5, 1.1), 12, 0.01, &rng);
  const LoopVerification r = TimedVerify("different places", source, target, Pose3::Identity());
  EXPECT_FALSE(r.accepted);
  EXPECT_FALSE(r.reason.empty());
  EXPECT_LT(r.overlap, 0.5);
}

}  // namespace
}  // namespace rotolidar::loop
