// Per-point deskew error (bench/metrics/deskew_error.hpp) on a synthetic truth and synthetic scan reports with a
// known injected error.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "bench/metrics/deskew_error.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::bench {
namespace {

// Motions for which linear + slerp interpolation between 1 kHz samples is exact: constant velocity and a constant
// rotation rate about a fixed axis.
Pose3 BaseAt(double t) {
  return MakePose(Eigen::Vector3d(1.0 + 1.2 * t, -0.5 + 0.3 * t, 1.5),
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.4 * t, Eigen::Vector3d::UnitZ())));
}
Pose3 LidarAt(double t) {
  return MakePose(Eigen::Vector3d(1.1 + 1.2 * t, -0.5 + 0.3 * t, 1.6 + 0.05 * t),
                  Eigen::Quaterniond(Eigen::AngleAxisd(2.6 * t, Eigen::Vector3d(1, 1, 0).normalized())));
}

DeskewTruth SyntheticTruth(double duration_s) {
  DeskewTruth truth;
  for (int k = 0; k <= int(std::lround(duration_s * 1000.0)); ++k) {
    truth.T_world_base.push_back({k * 1e-3, BaseAt(k * 1e-3)});
    truth.T_world_lidar.push_back({k * 1e-3, LidarAt(k * 1e-3)});
  }
  return truth;
}

// One report of n points fired over [t0, t0 + 0.1) s (times between the truth's samples), deskewed exactly and
// then displaced by errors_m[i] along a random direction.
ScanReport SyntheticReport(double t0, const std::vector<float>& errors_m, uint64_t seed) {
  RandomStream rng(seed, "deskew_error_test.points");
  ScanReport r;
  r.t_start_s = t0;
  r.t_end_s = t0 + 0.1;
  r.num_points = errors_m.size();
  const Pose3 T_base_world = BaseAt(t0).inverse();
  for (std::size_t i = 0; i < errors_m.size(); ++i) {
    LidarPoint lp;
    lp.t_s = t0 + 0.1 * (double(i) + 0.37) / double(errors_m.size());
    lp.x_m = float(10.0 * rng.Uniform() - 5.0), lp.y_m = float(10.0 * rng.Uniform() - 5.0);
    lp.z_m = float(2.0 * rng.Uniform() - 1.0);
    const Eigen::Vector3d p_true = T_base_world * LidarAt(lp.t_s) * Eigen::Vector3d(lp.x_m, lp.y_m, lp.z_m);
    const Eigen::Vector3d dir = Eigen::Vector3d{rng.Normal(), rng.Normal(), rng.Normal()}.normalized();
    r.deskew_source.push_back(lp);
    r.deskewed_base.push_back((p_true + double(errors_m[i]) * dir).cast<float>());
  }
  return r;
}

TEST(SummarizeErrors, NearestRankQuantiles) {
  std::vector<float> e;
  for (int i = 1; i <= 100; ++i) e.push_back(0.001f * float(101 - i));  // 1..100 mm, reversed
  const ErrorStats s = SummarizeErrors(e);
  EXPECT_EQ(s.count, 100u);
  EXPECT_NEAR(s.median_m, 0.0505, 1e-6);  // mean of the 50th and 51st
  EXPECT_NEAR(s.p90_m, 0.090, 1e-6);
  EXPECT_NEAR(s.p95_m, 0.095, 1e-6);
  EXPECT_NEAR(s.max_m, 0.100, 1e-6);
  EXPECT_NEAR(s.mean_m, 0.0505, 1e-6);
  EXPECT_NEAR(s.rmse_m, std::sqrt(338350.0 / 100.0) * 1e-3, 1e-6);  // sum of k^2, k = 1..100, is 338,350
  EXPECT_EQ(SummarizeErrors({}).count, 0u);
}

// Injected errors of 1..1000 x 0.01 mm (0.01..10 mm) in two scans: the statistics are those of the injected list,
// up to float rounding of positions ~5 m from the base (~1 um).
TEST(EvaluateDeskew, RecoversInjectedErrors) {
  const DeskewTruth truth = SyntheticTruth(2.0);
  std::vector<float> injected;
  for (int i = 1; i <= 1000; ++i) injected.push_back(1e-5f * float(i));
  std::vector<float> first(injected.begin(), injected.begin() + 500), second(injected.begin() + 500, injected.end());
  std::vector<ScanReport> reports = {SyntheticReport(0.5, first, 1), SyntheticReport(1.3, second, 2)};
  DeskewErrorResult result;
  ASSERT_TRUE(EvaluateDeskew(truth, reports, &result));
  const ErrorStats want = SummarizeErrors(injected);
  EXPECT_EQ(result.all.count, 1000u);
  EXPECT_NEAR(result.all.median_m, want.median_m, 2e-6);
  EXPECT_NEAR(result.all.p90_m, want.p90_m, 2e-6);
  EXPECT_NEAR(result.all.p95_m, want.p95_m, 2e-6);
  EXPECT_NEAR(result.all.rmse_m, want.rmse_m, 2e-6);
  EXPECT_NEAR(result.all.max_m, want.max_m, 2e-6);
  ASSERT_EQ(result.per_scan.size(), 2u);
  EXPECT_NEAR(result.per_scan[0].median_m, SummarizeErrors(first).median_m, 2e-6);
  EXPECT_NEAR(result.per_scan[1].max_m, 0.010, 2e-6);
  EXPECT_EQ(result.num_not_deskewed, 0u);
  EXPECT_EQ(result.num_outside_truth, 0u);
}

// A zero error stays zero: the formula needs no alignment between the estimator's world and truth's.
TEST(EvaluateDeskew, ExactDeskewGivesZeroAndSkipsNanAndOutsideTruth) {
  const DeskewTruth truth = SyntheticTruth(1.0);
  ScanReport r = SyntheticReport(0.2, std::vector<float>(300, 0.f), 3);
  r.deskewed_base[7] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  r.deskew_source[8].t_s = 5.0;  // after the truth ends
  DeskewErrorResult result;
  ASSERT_TRUE(EvaluateDeskew(truth, {r}, &result));
  EXPECT_EQ(result.all.count, 298u);
  EXPECT_LT(result.all.max_m, 2e-6);
  EXPECT_EQ(result.num_not_deskewed, 1u);
  EXPECT_EQ(result.num_outside_truth, 1u);

  ScanReport late = SyntheticReport(3.0, std::vector<float>(10, 0.f), 4);  // scan start outside the truth
  ASSERT_TRUE(EvaluateDeskew(truth, {late}, &result));
  EXPECT_EQ(result.all.count, 0u);
  EXPECT_EQ(result.num_outside_truth, 10u);
}

TEST(EvaluateDeskew, MissingDeskewDataIsAnError) {
  const DeskewTruth truth = SyntheticTruth(1.0);
  ScanReport r = SyntheticReport(0.2, std::vector<float>(5, 0.f), 5);
  r.deskewed_base.pop_back();
  DeskewErrorResult result;
  const Status s = EvaluateDeskew(truth, {r}, &result);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message.find("t = 0.2"), std::string::npos) << s.message;
  ScanReport empty;
  empty.num_points = 100;  // decoded points but nothing kept: keep_deskewed was off
  EXPECT_FALSE(EvaluateDeskew(truth, {empty}, &result));
}

}  // namespace
}  // namespace rotolidar::bench
