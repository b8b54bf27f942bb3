// Geometric verification of loop candidates on synthetic submaps: points sampled on the surfaces of an indoor hall
// (walls, floor, ceiling, pillars, shelves), cut to a radius around a keyframe and expressed in its frame, as an
// accumulated keyframe submap would be (no occlusion: several scans fill the shadows).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Eigenvalues>

#include "core/loop/geometric_verification.hpp"
#include "core/loop/lidar_descriptor.hpp"
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
          points.push_back(T_kf_world * p + noise_m * Eigen::Vector3d{rng->Normal(), rng->Normal(), rng->Normal()});
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
  EXPECT_TRUE(fails_on("huber_m", [](auto& c) { c.huber_m = 0; }));
  EXPECT_TRUE(fails_on("normal_neighbours", [](auto& c) { c.normal_neighbours = 2; }));
  EXPECT_TRUE(fails_on("min_normal_share", [](auto& c) { c.min_normal_share = 0.5; }));
  EXPECT_TRUE(fails_on("coarse_voxel_m", [](auto& c) { c.coarse_voxel_m = -1; }));
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
  EXPECT_GT(r.normal_share, 0.03);  // a hall constrains every direction (measured 0.06)
  // 1 cm noise, ~4 points per 0.2 m voxel face, ~40 k voxels: measured 0.9 mm / 0.0025 deg; bounds leave 5x / 8x.
  EXPECT_LT(dt, 0.005);
  EXPECT_LT(dr, 0.02 * kDeg);
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
  EXPECT_LT(r.overlap, 0.5);  // measured 0.33
  // Why the gates count vertical structure only: with every point (floor and ceiling included) the two halls
  // "overlap" well beyond min_overlap.
  LoopVerificationConfig all_points;
  all_points.structure_max_normal_z = 1.0;
  const LoopVerification counted_all = TimedVerify("different places, all points", source, target,
                                                   Pose3::Identity(), all_points);
  EXPECT_GT(counted_all.overlap, 0.7);
}

TEST(LoopVerification, DescriptorYawIsAGoodEnoughGuess) {
  // Stage 2 as the estimator will run it: the descriptor's yaw (translation unknown: 0) seeds the verification.
  const std::vector<Box> hall = Hall(21);
  RandomStream rng(24, "verification-descriptor-guess");
  const Pose3 T_w_t = KeyframePose(5, -3, 1.5, -0.4);
  const Pose3 T_w_s = KeyframePose(5.6, -2.2, 1.5, -0.4 + 130 * kDeg);
  const std::vector<Eigen::Vector3d> target = Submap(hall, T_w_t, 12, 0.01, &rng);
  const std::vector<Eigen::Vector3d> source = Submap(hall, T_w_s, 12, 0.01, &rng);
  const auto to_float = [](const std::vector<Eigen::Vector3d>& points) {
    std::vector<Eigen::Vector3f> out;
    for (const auto& p : points) out.push_back(p.cast<float>());
    return out;
  };
  const DescriptorMatch match = DescriptorDistance(ComputeLidarDescriptor(to_float(source), LidarDescriptorConfig{}),
                                                   ComputeLidarDescriptor(to_float(target), LidarDescriptorConfig{}));
  const Pose3 T_t_s = T_w_t.inverse() * T_w_s;
  std::printf("descriptor distance %.3f, yaw %.1f deg (true %.1f)\n", match.distance, match.yaw_rad / kDeg,
              130.0);
  const LoopVerification r = TimedVerify("descriptor guess", source, target, RotZ(match.yaw_rad));
  const auto [dt, dr] = Errors(r.T_target_source, T_t_s);
  std::printf("error %.4f m %.4f deg\n", dt, dr / kDeg);
  EXPECT_TRUE(r.accepted) << r.reason;
  EXPECT_LT(dt, 0.005);  // measured 1.7 mm / 0.007 deg: the same optimum as from guesses near the truth
  EXPECT_LT(dr, 0.02 * kDeg);
}

TEST(LoopVerification, CovarianceIsLargeAlongACorridor) {
  // A featureless corridor along x: walls, floor and ceiling constrain y, z and the rotations, nothing fixes x.
  const std::vector<Box> corridor = {{{-40, -1.5, 0}, {40, -1.5, 3}},
                                     {{-40, 1.5, 0}, {40, 1.5, 3}},
                                     {{-40, -1.5, 0}, {40, 1.5, 0}},
                                     {{-40, -1.5, 3}, {40, 1.5, 3}}};
  RandomStream rng(25, "verification-corridor");
  const Pose3 T_w_t = KeyframePose(0, 0, 1.5, 0.0);
  const Pose3 T_w_s = KeyframePose(1.0, 0.2, 1.5, 10 * kDeg);
  const std::vector<Eigen::Vector3d> target = Submap(corridor, T_w_t, 12, 0.01, &rng);
  const std::vector<Eigen::Vector3d> source = Submap(corridor, T_w_s, 12, 0.01, &rng);
  const LoopVerification r = TimedVerify("corridor", source, target, T_w_t.inverse() * T_w_s);
  const Eigen::Matrix<double, 6, 1> sigma = r.covariance.diagonal().cwiseSqrt();
  std::printf("corridor: normal share %.5f, sigma t %.4f %.4f %.4f m, r %.4f %.4f %.4f deg\n", r.normal_share,
              sigma[0], sigma[1], sigma[2], sigma[3] / kDeg, sigma[4] / kDeg, sigma[5] / kDeg);
  // Rejected as degenerate (measured share 0.001 against a hall's 0.06), and the covariance, estimated anyway,
  // is largest along the corridor (measured 25x the across-corridor sigma).
  EXPECT_FALSE(r.accepted);
  EXPECT_NE(r.reason.find("degenerate"), std::string::npos) << r.reason;
  EXPECT_LT(r.normal_share, 0.01);
  ASSERT_TRUE(r.covariance_valid);
  EXPECT_GT(sigma[0], 10 * sigma[1]);
}

TEST(LoopVerification, ReportsBadInputs) {
  RandomStream rng(26, "verification-bad-inputs");
  const std::vector<Eigen::Vector3d> map = Submap(Hall(21), KeyframePose(0, 0, 1.5, 0), 8, 0.01, &rng, 0.05);
  const LoopVerification empty = VerifyLoop(std::vector<Eigen::Vector3d>{}, map, Pose3::Identity(), {});
  EXPECT_FALSE(empty.accepted);
  EXPECT_NE(empty.reason.find("too few points"), std::string::npos) << empty.reason;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Eigen::Vector3d> nans(500, Eigen::Vector3d(nan, 0, 0));
  const LoopVerification all_nan = VerifyLoop(nans, map, Pose3::Identity(), {});
  EXPECT_FALSE(all_nan.accepted);
  EXPECT_EQ(all_nan.num_source_points, 0u);
  LoopVerificationConfig bad;
  bad.min_overlap = -1;
  const LoopVerification invalid = VerifyLoop(map, map, Pose3::Identity(), bad);
  EXPECT_FALSE(invalid.accepted);
  EXPECT_NE(invalid.reason.find("min_overlap"), std::string::npos) << invalid.reason;
  Pose3 not_finite = Pose3::Identity();
  not_finite.translation().x() = nan;
  EXPECT_FALSE(VerifyLoop(map, map, not_finite, {}).accepted);
  // A 1 m flat square: 25 fine voxels, 9 coarse ones (too few for GICP's 20 neighbours): no crash, and rejected
  // (no vertical structure).
  std::vector<Eigen::Vector3d> square;
  for (int i = 0; i < 2000; ++i) square.push_back(Eigen::Vector3d{rng.Uniform(), rng.Uniform(), 0.0});
  LoopVerificationConfig few;
  few.min_points = 20;
  const LoopVerification flat = VerifyLoop(square, square, Pose3::Identity(), few);
  EXPECT_FALSE(flat.accepted);
  EXPECT_NE(flat.reason.find("structure"), std::string::npos) << flat.reason;
  // A submap against itself from the identity: accepted, exact.
  const LoopVerification self = VerifyLoop(map, map, Pose3::Identity(), {});
  EXPECT_TRUE(self.accepted) << self.reason;
  EXPECT_LT(Errors(self.T_target_source, Pose3::Identity()).first, 1e-4);
}

TEST(LoopVerification, PointToPlaneJacobianMatchesNumericDifferentiation) {
  RandomStream rng(27, "verification-jacobian");
  const auto random_vector = [&](double scale) -> Eigen::Vector3d {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = scale * rng.Normal();
    return v;
  };
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 T = MakePose(random_vector(3.0), Eigen::Quaterniond(ExpSO3(random_vector(1.0))));
    const Eigen::Vector3d p = random_vector(10.0), q = random_vector(10.0), n = random_vector(1.0).normalized();
    Eigen::Matrix<double, 6, 1> J;
    const double r = detail::PointToPlaneResidual(T, p, q, n, &J);
    EXPECT_NEAR(r, n.dot(T * p - q), 1e-9);
    // Central differences of r(T (+) xi), T (+) xi = (t + dt, Exp(dtheta) R).
    constexpr double kStep = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Pose3 plus = T, minus = T;
      Eigen::Matrix<double, 6, 1> xi = Eigen::Matrix<double, 6, 1>::Zero();
      xi[k] = kStep;
      plus.translation() += xi.head<3>();
      plus.linear() = ExpSO3(xi.tail<3>()) * T.linear();
      minus.translation() -= xi.head<3>();
      minus.linear() = ExpSO3(-xi.tail<3>()) * T.linear();
      const double numeric = (detail::PointToPlaneResidual(plus, p, q, n, nullptr) -
                              detail::PointToPlaneResidual(minus, p, q, n, nullptr)) / (2 * kStep);
      // Truncation O(step^2 |p|) ~ 1e-11, round-off ~ 1e-16 * 30 / 1e-6 ~ 3e-9.
      EXPECT_NEAR(J[k], numeric, 1e-7) << "trial " << trial << " coordinate " << k;
    }
  }
}

}  // namespace
}  // namespace rotolidar::loop
