// The curvature features on one real VLP-16 revolution (einride/vlp16-go, $ROTOLIDAR_DATA/vlp16_einride).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/features/curvature_features.hpp"
#include "core/wire/pcap.hpp"
#include "core/wire/scan_splitter.hpp"
#include "core/wire/vlp16.hpp"
#include "core/preprocess/filters.hpp"
#include "tests/common/test_data.hpp"
#include "tests/core/features/feature_test_util.hpp"

namespace rotolidar {
namespace {

using test::CountPerCell;
using test::SeedFeatureConfig;
using test::SameCloud;

// One indoor revolution, head static, so lidar = base frame. A failed read is fatal (ASSERT).
void RealScan(const std::string& dir, int index, std::vector<ScanPoint>* out) {
  std::vector<LidarPacket> packets;
  const Status read = ReadRawVlp16Payloads(dir + "/recording.bin", &packets);
  ASSERT_TRUE(read.ok) << read.message;
  Vlp16Decoder decoder{LidarIntrinsics(), Vlp16DecoderConfig()};
  std::vector<LidarPoint> points;
  for (const LidarPacket& packet : packets) EXPECT_TRUE(decoder.Decode(packet, &points).ok);
  RevolutionSplitter splitter(0.0);
  std::vector<LidarScan> scans;
  splitter.Add(points, &scans);
  ASSERT_GT(scans.size(), std::size_t(index));
  const LidarScan& scan = scans[index];
  out->clear();  // the head was static: lidar = base, no deskew
  for (const LidarPoint& lp : scan.points) out->push_back(ToScanPoint(lp, Eigen::Vector3d(lp.x_m, lp.y_m, lp.z_m)));
}

TEST(FeaturesRealData, EinrideRevolution) {
  ROTOLIDAR_REQUIRE_DATA(dir, "vlp16_einride");
  std::vector<ScanPoint> raw;
  ASSERT_NO_FATAL_FAILURE(RealScan(dir, 1, &raw));  // the first full revolution
  ASSERT_GT(raw.size(), 15000u);
  const PreprocessResult pre = Preprocess(raw, PreprocessConfig());
  EXPECT_EQ(pre.num_input, pre.points.size() + pre.removed_nonfinite + pre.removed_range + pre.removed_sor);
  // Measured: 1601 of 15,365 returns inside 0.8 m (the indoor scene's clutter), SOR then 124 (0.9 %; 245 with the
  // exact K = 20 search).
  EXPECT_LT(pre.removed_sor, pre.points.size() / 30);
  FeatureConfig config = SeedFeatureConfig();
  config.threads = 1;
  const FeatureResult one = ExtractFeatures(pre.points, 0.0, config);
  config.threads = 4;
  const FeatureResult four = ExtractFeatures(pre.points, 0.0, config);
  EXPECT_TRUE(one.labels == four.labels);
  EXPECT_TRUE(SameCloud(one.features.edge, four.features.edge));
  EXPECT_TRUE(SameCloud(one.features.less_flat, four.features.less_flat));
  // Measured 226 edges, 428 planar, 305 less sharp, 693 less flat (10,476 before the 0.2 m voxels).
  EXPECT_GT(one.stats.num_edge, 100u);
  EXPECT_GT(one.stats.num_planar, 200u);
  using L = FeatureLabel;
  for (const L label : {L::kEdge, L::kPlanar})
    for (const auto& kv : CountPerCell(pre.points, one, {label}, 12)) EXPECT_LE(kv.second, 4);
  for (const auto& p : one.features.planar) EXPECT_LT(p.intensity, config.planar_threshold);
  for (const auto& p : one.features.edge) EXPECT_GT(p.intensity, config.edge_threshold);
  // The range_sigma_m default: indoors most windows lie on planes, where c is noise, c ~ |N(0, 1.05 sigma / r)|.
  // The 10 % and 25 % quantiles of c * r then give sigma = q / (1.05 * {0.126, 0.319}); measured 1.06 and 0.98 cm.
  std::vector<double> cr;
  for (std::size_t i = 0; i < pre.points.size(); ++i)
    if (!std::isnan(one.curvature[i])) cr.push_back(one.curvature[i] * pre.points[i].range_m);
  std::sort(cr.begin(), cr.end());
  const double sigma_10 = cr[cr.size() / 10] / (1.049 * 0.126), sigma_25 = cr[cr.size() / 4] / (1.049 * 0.319);
  EXPECT_NEAR(sigma_10, 0.01, 0.002);
  EXPECT_NEAR(sigma_25, 0.01, 0.002);
}

}  // namespace
}  // namespace rotolidar
