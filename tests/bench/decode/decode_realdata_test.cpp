// `decode` on the real einride VLP-16 recording; writes one revolution to <TempDir>/vlp16_rev.{csv,ply}.
#include <gtest/gtest.h>

#include <cstdlib>
#include <iostream>

#include "bench/decode/decode.hpp"
#include "tests/common/test_data.hpp"

namespace rotolidar::bench {
namespace {

TEST(DecodeRealData, EinrideRecordingOneRevolution) {
  ROTOLIDAR_REQUIRE_DATA(dir, "vlp16_einride");
  DecodeOptions options;
  options.input_path = dir + "/recording.bin";
  options.raw = true;
  options.output_prefix = ::testing::TempDir() + "/vlp16_rev";
  options.revolution = 1;  // the first full revolution (scan 0 is the partial 103..360 deg)
  DecodeSummary summary;
  const Status s = RunDecode(options, &summary);
  ASSERT_TRUE(s.ok) << s.message;
  PrintDecodeSummary(summary, std::cout);
  // Numbers measured by core_wire_vlp16_realdata_test (same decoder, all ranges 0.50..12.34 m pass 0.4..130 m).
  EXPECT_EQ(summary.packets, 1000u);
  EXPECT_EQ(summary.points, 203034u);
  EXPECT_EQ(summary.scans, 14u);  // 13 crossings of azimuth 0 + the trailing partial
  EXPECT_EQ(summary.full_revolutions, 12u);
  EXPECT_GT(summary.points_written, 15000u);
  EXPECT_LT(summary.points_written, 15600u);
  EXPECT_EQ(summary.malformed, 0u);
}

}  // namespace
}  // namespace rotolidar::bench
