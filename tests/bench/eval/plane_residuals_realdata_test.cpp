// The plane-residual measure on a real VLP-16 capture (vlp16_einride: 1000 raw payloads, a static sensor indoors)
// gives the numbers docs/lidar_model.md reports, and the twin with the fitted noise model (the typical preset)
// matches them within the fit's bar.
#include <gtest/gtest.h>

#include "bench/eval/plane_residuals.hpp"
#include "bench/eval/twin_capture.hpp"
#include "sim/lidar/lidar_realism.hpp"
#include "tests/common/test_data.hpp"

namespace rotolidar::bench {
namespace {

TEST(PlaneResidualsRealdata, EinrideCaptureGivesTheReportedNumbers) {
  ROTOLIDAR_REQUIRE_DATA(dir, "vlp16_einride");
  std::vector<LidarScan> scans;
  const Status loaded = LoadLidarRevolutions(dir + "/recording.bin", &scans);
  ASSERT_TRUE(loaded.ok) << loaded.message;
  EXPECT_EQ(scans.size(), 12u);  // 13 azimuth wraps: 12 full revolutions between them
  PlaneResidualResult r;
  const Status measured = MeasurePlaneResiduals(scans, PlaneResidualOptions{}, &r);
  ASSERT_TRUE(measured.ok) << measured.message;
  std::cout << "planes " << r.planes << ", points " << r.points.size() << ", median " << r.all.median_abs_m
            << ", p90 " << r.all.p90_abs_m << "\n";
  // Measured (docs/lidar_model.md, section 5): 52 planes, 119,093 points, median 19.0 mm, p90 73.1 mm. PCL's
  // RANSAC is seeded with a constant, so these are exact with this PCL; the bounds (+-10 %) leave room for
  // another PCL version's sampling, not for a change of the measure.
  EXPECT_NEAR(static_cast<double>(r.points.size()), 119093.0, 12000.0);
  EXPECT_NEAR(r.all.median_abs_m, 0.0190, 0.0019);
  EXPECT_NEAR(r.all.p90_abs_m, 0.0731, 0.0073);
  // The incidence dependence the fit relies on: near-normal points are 3x tighter than grazing ones.
  EXPECT_LT(r.by_incidence.front().median_abs_m * 2.5, r.by_incidence.back().median_abs_m);
}

// The twin with the fitted noise model in box_room (static, 2.5, 1.5, 1.0 m: walls 1.5..7.5 m away) agrees
// with the real capture's overall median and p90 within the 30 % bar the fit was made to (measured: ratios 1.00
// and 0.74).
TEST(PlaneResidualsRealdata, TwinWithTheFittedNoiseMatchesTheRealCapture) {
  ROTOLIDAR_REQUIRE_DATA(dir, "vlp16_einride");
  std::vector<LidarScan> real_scans, twin_scans;
  ASSERT_TRUE(LoadLidarRevolutions(dir + "/recording.bin", &real_scans).ok);
  TwinCaptureOptions t;
  t.scene = "box_room";
  t.T_world_lidar.translation() = Eigen::Vector3d(2.5, 1.5, 1.0);
  t.revolutions = 4;  // 4 of 13 for speed: the twin's median/p90 move < 2 % (4 vs 13 revolutions measured)
  sim::ApplyFittedVlp16Noise(&t.lidar);  // the noise alone (a range bias would be a plane offset here)
  const Status captured = CaptureTwinRevolutions(t, &twin_scans);
  ASSERT_TRUE(captured.ok) << captured.message;
  PlaneResidualResult real, twin;
  ASSERT_TRUE(MeasurePlaneResiduals(real_scans, PlaneResidualOptions{}, &real).ok);
  ASSERT_TRUE(MeasurePlaneResiduals(twin_scans, PlaneResidualOptions{}, &twin).ok);
  const double median_ratio = twin.all.median_abs_m / real.all.median_abs_m;
  const double p90_ratio = twin.all.p90_abs_m / real.all.p90_abs_m;
  std::cout << "twin / real: median " << median_ratio << ", p90 " << p90_ratio << "\n";
  EXPECT_NEAR(median_ratio, 1.0, 0.3);
  EXPECT_NEAR(p90_ratio, 1.0, 0.3);
}

}  // namespace
}  // namespace rotolidar::bench
