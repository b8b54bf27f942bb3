// Revolution splitting on a synthetic 2.5-revolution stream.
#include <gtest/gtest.h>

#include <cmath>

#include "core/wire/scan_splitter.hpp"

namespace rotolidar {
namespace {

// Points every 0.2 deg from `start_deg` for `total_deg` degrees, 1 ms apart, with a small interpolation back-step
// (-0.01 deg) every 10th point, as the decoder's last-block extrapolation can produce.
std::vector<LidarPoint> Stream(double start_deg, double total_deg) {
  std::vector<LidarPoint> points;
  const int n = static_cast<int>(std::lround(total_deg / 0.2));
  for (int i = 0; i < n; ++i) {
    LidarPoint p;
    const double az = (10.0 * start_deg + 2.0 * i - (i % 10 == 9 ? 2.1 : 0.0)) / 10.0;  // exact at crossings
    p.azimuth_deg = static_cast<float>(std::fmod(az, 360.0));
    p.t_s = 1e-3 * i;
    points.push_back(p);
  }
  return points;
}

TEST(RevolutionSplitter, TwoAndAHalfRevolutions) {
  const auto points = Stream(100.0, 900.0);  // 100 deg .. 1000 deg = 2.5 revolutions, 4500 points
  RevolutionSplitter splitter(0.0);
  std::vector<LidarScan> scans;
  splitter.Add(points, &scans);
  ASSERT_EQ(scans.size(), 2u);  // crossings at 360 and 720 deg
  EXPECT_EQ(splitter.crossings(), 2u);
  const std::optional<LidarScan> rest = splitter.Flush();
  ASSERT_TRUE(rest.has_value());
  EXPECT_EQ(scans[0].points.size(), 1300u);  // 100..360: leading partial
  EXPECT_EQ(scans[1].points.size(), 1800u);  // one full revolution
  EXPECT_EQ(rest->points.size(), 1400u);     // 0..280: trailing partial
  EXPECT_FALSE(splitter.Flush().has_value());
  std::size_t i = 0;
  for (const LidarScan* s : std::vector<const LidarScan*>{&scans[0], &scans[1], &*rest}) {
    EXPECT_DOUBLE_EQ(s->t_start_s, points[i].t_s);
    i += s->points.size();
    EXPECT_DOUBLE_EQ(s->t_end_s, points[i - 1].t_s);
    EXPECT_EQ(s->points.front().azimuth_deg, points[i - s->points.size()].azimuth_deg);
  }
  EXPECT_LT(scans[1].points.front().azimuth_deg, 0.5f);  // a scan starts at the cut
}

TEST(RevolutionSplitter, CutAngleAwayFromZero) {
  const auto points = Stream(100.0, 900.0);
  RevolutionSplitter splitter(-270.0);  // = 90 deg: crossings at 450 and 810 deg
  std::vector<LidarScan> scans;
  splitter.Add(points, &scans);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[0].points.size(), 1750u);  // 100..450
  EXPECT_EQ(scans[1].points.size(), 1800u);
  EXPECT_NEAR(scans[1].points.front().azimuth_deg, 90.0, 0.25);
  EXPECT_NEAR(scans[1].points.back().azimuth_deg, 89.8, 0.25);
}

}  // namespace
}  // namespace rotolidar
