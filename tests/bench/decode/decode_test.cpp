// `decode` on a synthetic pcap: CSV and PLY agree with the decoder, foreign/malformed input is counted, --return
// and the range limits select rows.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "bench/decode/decode.hpp"
#include "core/wire/pcap.hpp"

namespace rotolidar::bench {
namespace {

// 0.35 s of a head spinning at 10 Hz from azimuth 300 deg (3.5 revolutions, 263 packets), every laser returning
// 5 m + 1 cm * laser with reflectivity 42.
std::vector<LidarPacket> SyntheticPackets() {
  Vlp16PacketEncoder encoder(Vlp16ReturnMode::kStrongest, 0.0);
  std::vector<LidarPacket> packets;
  Vlp16FiringSequence s;
  const int n = static_cast<int>(0.35 / kVlp16SequencePeriodS);
  for (int k = 0; k < n; ++k) {
    s.t_s = 1.0 + k * kVlp16SequencePeriodS;
    s.azimuth_centideg = static_cast<uint16_t>(std::lround(30000.0 + 360000.0 * (s.t_s - 1.0)) % 36000);
    for (int l = 0; l < 16; ++l) s.distance_2mm[l] = static_cast<uint16_t>(2500 + 5 * l);
    s.reflectivity.fill(42);
    if (auto p = encoder.Add(s)) packets.push_back(*p);
  }
  return packets;
}

std::string Prefix(const std::string& name) {
  return ::testing::TempDir() + "/rotolidar_decode_" + name + "_" + std::to_string(::getpid());
}

TEST(Decode, PcapToCsvAndPly) {
  const std::vector<LidarPacket> packets = SyntheticPackets();
  const std::string pcap = Prefix("in") + ".pcap";
  PcapWriter writer;
  ASSERT_TRUE(writer.Open(pcap).ok);
  for (std::size_t i = 0; i < packets.size(); ++i) {
    ASSERT_TRUE(writer.Write(packets[i]).ok);
    if (i == 100) {
      ASSERT_TRUE(writer.Write(EncodeVlp16PositionPacket(packets[i].t_capture_s, 0.0, 2, "$GPRMC")).ok);
    }
  }
  ASSERT_TRUE(writer.Close().ok);

  DecodeOptions options;
  options.input_path = pcap;
  options.output_prefix = Prefix("out");
  DecodeSummary summary;
  const Status s = RunDecode(options, &summary);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(summary.packets, packets.size());
  EXPECT_EQ(summary.position_packets, 1u);
  EXPECT_EQ(summary.points, packets.size() * 384);  // every channel returned, all inside 0.4..130 m
  EXPECT_EQ(summary.points_written, summary.points);
  // 300 deg + 0.35 s x 3600 deg/s = 1560 deg: cuts at 360, 720, 1080, 1440 -> 5 scans, 3 full revolutions.
  EXPECT_EQ(summary.scans, 5u);
  EXPECT_EQ(summary.full_revolutions, 3u);
  EXPECT_NEAR(summary.t_first_s, 1.0, 1e-6);

  std::ifstream csv(options.output_prefix + ".csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "x,y,z,intensity,ring,azimuth,return,time_s");
  std::size_t rows = 0;
  while (std::getline(csv, line)) {
    double x, y, z, intensity, azimuth, t;
    int ring, ret;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%d,%lf,%d,%lf", &x, &y, &z, &intensity, &ring, &azimuth,
                          &ret, &t), 8) << line;
    EXPECT_EQ(intensity, 42);
    EXPECT_EQ(ret, 0);
    ++rows;
    (void)ring, (void)azimuth, (void)t;
  }
  EXPECT_EQ(rows, summary.points);

  std::ifstream ply(options.output_prefix + ".ply", std::ios::binary);
  std::string header, l;
  while (std::getline(ply, l)) {
    header += l + "\n";
    if (l == "end_header") break;
  }
  EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(header.find("element vertex " + std::to_string(summary.points) + "\n"), std::string::npos);
  const auto body_start = ply.tellg();
  ply.seekg(0, std::ios::end);
  EXPECT_EQ(static_cast<std::size_t>(ply.tellg() - body_start), summary.points * 30);  // 4*4 + 1 + 4 + 1 + 8
}

TEST(Decode, OneRevolutionAndErrors) {
  const std::vector<LidarPacket> packets = SyntheticPackets();
  const std::string raw = Prefix("raw") + ".bin";
  {
    std::ofstream out(raw, std::ios::binary);
    for (const auto& p : packets) out.write(reinterpret_cast<const char*>(p.payload.data()), 1206);
  }
  DecodeOptions options;
  options.input_path = raw;
  options.raw = true;
  options.output_prefix = Prefix("rev");
  options.revolution = 2;
  DecodeSummary summary;
  ASSERT_TRUE(RunDecode(options, &summary).ok);
  // A full revolution: 0.1 s / 55.296 us = 1808.4 sequences x 16 returns.
  EXPECT_GT(summary.points_written, 1808u * 16 - 16);
  EXPECT_LT(summary.points_written, 1809u * 16 + 16);

  options.input_path = raw + ".missing";
  const Status s = RunDecode(options, &summary);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find(".missing"), std::string::npos);
  options.input_path = raw;
  options.decoder.max_range_m = 0.1;
  EXPECT_FALSE(RunDecode(options, &summary).ok);
  Vlp16ReturnFilter f;
  EXPECT_TRUE(ParseReturnFilter("last", &f));
  EXPECT_EQ(f, Vlp16ReturnFilter::kLast);
  EXPECT_FALSE(ParseReturnFilter("first", &f));
}

/// Reads the CSV rows: (range from the lidar origin ignoring the laser's vertical offset, return).
std::vector<std::pair<double, int>> ReadRows(const std::string& csv_path) {
  std::ifstream csv(csv_path);
  std::string line;
  std::getline(csv, line);
  std::vector<std::pair<double, int>> rows;
  while (std::getline(csv, line)) {
    double x, y, z, intensity, azimuth, t;
    int ring, ret;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%d,%lf,%d,%lf", &x, &y, &z, &intensity, &ring, &azimuth, &ret,
                    &t) == 8) {
      rows.emplace_back(std::hypot(x, y) / std::cos((2.0 * ring - 15.0) * M_PI / 180.0), ret);
    }
  }
  return rows;
}

/// Writes 12 x 20 dual-return firing sequences, all like `s` (azimuth stepping 0.2 deg), as a pcap at `path`.
void WriteDualPcap(const std::string& path, Vlp16FiringSequence s) {
  Vlp16PacketEncoder encoder(Vlp16ReturnMode::kDual, 0.0);
  PcapWriter writer;
  ASSERT_TRUE(writer.Open(path).ok);
  for (int k = 0; k < 12 * 20; ++k) {
    s.t_s = k * kVlp16SequencePeriodS;
    s.azimuth_centideg = static_cast<uint16_t>((k * 20) % 36000);
    if (auto p = encoder.Add(s)) {
      ASSERT_TRUE(writer.Write(*p).ok);
    }
  }
  ASSERT_TRUE(writer.Close().ok);
}

// Dual-return packets whose last return (even blocks) is at 5 m and strongest (odd blocks) at 2 m: --return and
// the range limits select the rows.
TEST(Decode, ReturnSelectionAndRangeLimitsInDualMode) {
  const std::string pcap = Prefix("dual") + ".pcap";
  Vlp16FiringSequence s;
  s.distance_2mm.fill(2500);   // last: 5 m
  s.distance2_2mm.fill(1000);  // strongest: 2 m
  s.reflectivity.fill(10);
  s.reflectivity2.fill(80);
  ASSERT_NO_FATAL_FAILURE(WriteDualPcap(pcap, s));
  const std::size_t per_return = 12 * 20 * 16;
  struct Case {
    Vlp16ReturnFilter filter;
    double min_range_m;
    std::size_t rows_2m, rows_5m;
  };
  for (const Case& c : {Case{Vlp16ReturnFilter::kAll, 0.4, per_return, per_return},
                        Case{Vlp16ReturnFilter::kLast, 0.4, 0, per_return},
                        Case{Vlp16ReturnFilter::kStrongest, 0.4, per_return, 0},
                        Case{Vlp16ReturnFilter::kAll, 3.0, 0, per_return}}) {
    DecodeOptions options;
    options.input_path = pcap;
    options.output_prefix = Prefix("dual_out");
    options.decoder.return_filter = c.filter;
    options.decoder.min_range_m = c.min_range_m;
    DecodeSummary summary;
    ASSERT_TRUE(RunDecode(options, &summary).ok);
    std::size_t rows_2m = 0, rows_5m = 0;
    for (const auto& [range_m, ret] : ReadRows(options.output_prefix + ".csv")) {
      const bool near = std::abs(range_m - 2.0) < 0.02, far = std::abs(range_m - 5.0) < 0.02;  // + laser offset
      ASSERT_TRUE(near || far) << range_m;
      EXPECT_EQ(ret, near ? 0 : 1);  // 0 = strongest (odd blocks), 1 = last (even blocks)
      ++(near ? rows_2m : rows_5m);
    }
    EXPECT_EQ(rows_2m, c.rows_2m) << "filter " << int(c.filter) << " min " << c.min_range_m;
    EXPECT_EQ(rows_5m, c.rows_5m) << "filter " << int(c.filter) << " min " << c.min_range_m;
  }
}

// Dual-return packets whose two blocks carry the same echo (5 m, reflectivity 40) for lasers 0..9 and two echoes
// (last 5 m, strongest 2 m) for lasers 10..15: the duplicates are one row each (return 2), counted in the summary;
// keep_duplicate_dual_returns brings the second copy back.
TEST(Decode, DualDuplicatesAreOneRowAndCounted) {
  const std::string pcap = Prefix("dual_dup") + ".pcap";
  Vlp16FiringSequence s;
  s.distance_2mm.fill(2500);
  s.reflectivity.fill(40);
  for (int l = 0; l < 16; ++l) {
    s.distance2_2mm[l] = l < 10 ? 2500 : 1000;
    s.reflectivity2[l] = l < 10 ? 40 : 90;
  }
  ASSERT_NO_FATAL_FAILURE(WriteDualPcap(pcap, s));
  const std::size_t firings = 12 * 20;
  DecodeOptions options;
  options.input_path = pcap;
  options.output_prefix = Prefix("dual_dup_out");
  DecodeSummary summary;
  ASSERT_TRUE(RunDecode(options, &summary).ok);
  EXPECT_EQ(summary.points, firings * (10 + 6 * 2));
  EXPECT_EQ(summary.merged_dual_duplicates, firings * 10);
  std::size_t both = 0;
  for (const auto& [range_m, ret] : ReadRows(options.output_prefix + ".csv")) {
    if (ret != 2) continue;
    ++both;
    EXPECT_NEAR(range_m, 5.0, 0.02);
  }
  EXPECT_EQ(both, firings * 10);
  std::ostringstream printed;
  PrintDecodeSummary(summary, printed);
  EXPECT_NE(printed.str().find("dual duplicates   " + std::to_string(firings * 10)), std::string::npos)
      << printed.str();

  options.decoder.keep_duplicate_dual_returns = true;
  ASSERT_TRUE(RunDecode(options, &summary).ok);
  EXPECT_EQ(summary.points, firings * 16 * 2);
  EXPECT_EQ(summary.merged_dual_duplicates, 0u);
}

/// Runs decode on `input` and returns the error (the test fails if the run succeeds).
std::string DecodeError(const std::string& input, bool raw, double max_range_m = 130.0, int revolution = -1) {
  DecodeOptions options;
  options.input_path = input;
  options.raw = raw;
  options.output_prefix = Prefix("fail_out");
  options.decoder.max_range_m = max_range_m;
  options.revolution = revolution;
  DecodeSummary summary;
  const Status s = RunDecode(options, &summary);
  EXPECT_FALSE(s.ok) << input << " decoded " << summary.points << " points";
  return s.message;
}

// No run ends well with zero points: each cause has its message.
TEST(Decode, ZeroPointsIsAnErrorSayingWhy) {
  const std::string foreign = Prefix("foreign") + ".pcap";
  PcapWriter writer;
  ASSERT_TRUE(writer.Open(foreign).ok);
  for (int i = 0; i < 5; ++i) {
    LidarPacket p;
    p.t_capture_s = 0.01 * i;
    p.udp_port = i == 0 ? 7503 : 7502;
    p.payload.assign(i == 0 ? 48 : 12608, 7);
    ASSERT_TRUE(writer.Write(p).ok);
  }
  ASSERT_TRUE(writer.Close().ok);
  EXPECT_EQ(DecodeError(foreign, false), foreign + ": no VLP-16 data packets (1206-byte payloads on UDP port 2368): "
                                                   "saw 5 UDP packets: port 7502 x 4 (payload 12608 B), port 7503 x "
                                                   "1 (payload 48 B)");

  const std::string header_only = Prefix("header_only") + ".pcap";
  ASSERT_TRUE(writer.Open(header_only).ok);
  ASSERT_TRUE(writer.Close().ok);
  EXPECT_NE(DecodeError(header_only, false).find("saw no packets (the file holds a pcap header only)"),
            std::string::npos);

  const std::string empty_raw = Prefix("empty") + ".bin";
  std::ofstream(empty_raw, std::ios::binary).close();
  EXPECT_EQ(DecodeError(empty_raw, true), empty_raw + ": empty file: no 1206-byte payloads");

  const std::string random_raw = Prefix("random") + ".bin";
  {
    std::ofstream out(random_raw, std::ios::binary);
    uint32_t x = 12345;
    for (int i = 0; i < 3 * 1206; ++i) out.put(char((x = x * 1664525u + 1013904223u) >> 24));
  }
  const std::string random_error = DecodeError(random_raw, true);
  EXPECT_NE(random_error.find("no decodable VLP-16 data packet; 3 malformed (first: "), std::string::npos)
      << random_error;

  // Valid packets whose returns (5 m .. 5.15 m) all lie beyond max_range_m; a revolution past the last scan.
  const std::string good = Prefix("good") + ".pcap";
  ASSERT_TRUE(writer.Open(good).ok);
  for (const LidarPacket& p : SyntheticPackets()) ASSERT_TRUE(writer.Write(p).ok);
  ASSERT_TRUE(writer.Close().ok);
  const std::string range_error = DecodeError(good, false, 1.0);
  EXPECT_NE(range_error.find("263 data packets gave 0 points inside the range limits"), std::string::npos)
      << range_error;
  const std::string revolution_error = DecodeError(good, false, 130.0, 9);
  EXPECT_NE(revolution_error.find("revolution 9 not found: the input has 5 scans"), std::string::npos)
      << revolution_error;
}

}  // namespace
}  // namespace rotolidar::bench
