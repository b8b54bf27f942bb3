// Encoder -> decoder round trips on synthetic firing sequences, and hour-rollover unwrapping.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/io/vlp16.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

constexpr double kSpinHz = 10.0;
constexpr double kDegPerS = 360.0 * kSpinHz;

struct Commanded {  // what the synthetic head measured, per (sequence, laser, return)
  double t_s, azimuth_deg, range_m;
  uint8_t reflectivity, laser, return_type;
};

// Sequences of a head spinning at 10 Hz from azimuth 350 deg (so the stream wraps through 0), random ranges
// 0.5..90 m, every 7th return missing (distance 0) and every 11th inside the 0.4 m blind zone.
std::vector<Vlp16FiringSequence> MakeSequences(int n, double t0_s, std::vector<Commanded>* truth,
                                               Vlp16ReturnMode mode) {
  RandomStream rng(42, "vlp16-codec");
  std::vector<Vlp16FiringSequence> seqs(n);
  int counter = 0;
  for (int k = 0; k < n; ++k) {
    Vlp16FiringSequence& s = seqs[k];
    s.t_s = t0_s + k * kVlp16SequencePeriodS;
    const double az0 = std::fmod(350.0 + kDegPerS * (s.t_s - t0_s), 360.0);
    s.azimuth_centideg = static_cast<uint16_t>(std::lround(az0 * 100.0) % 36000);
    for (int l = 0; l < 16; ++l) {
      for (int r = 0; r < (mode == Vlp16ReturnMode::kDual ? 2 : 1); ++r) {
        ++counter;
        uint16_t d = static_cast<uint16_t>(std::lround((0.5 + 89.5 * rng.Uniform()) / kVlp16DistanceUnitM));
        if (counter % 7 == 0) d = 0;
        if (counter % 11 == 0) d = 150;  // 0.3 m
        const uint8_t refl = static_cast<uint8_t>(rng.NextU64() % 256);
        (r == 0 ? s.distance_2mm : s.distance2_2mm)[l] = d;
        (r == 0 ? s.reflectivity : s.reflectivity2)[l] = refl;
        if (d == 0 || d == 150) continue;
        const double t = s.t_s + l * kVlp16FiringPeriodS;
        const uint8_t type = mode == Vlp16ReturnMode::kDual ? (r == 0 ? 1 : 0) : (mode == Vlp16ReturnMode::kLast);
        truth->push_back({t, std::fmod(350.0 + kDegPerS * (t - t0_s), 360.0), d * kVlp16DistanceUnitM, refl,
                          static_cast<uint8_t>(l), type});
      }
    }
  }
  return seqs;
}

std::vector<LidarPoint> EncodeDecode(const std::vector<Vlp16FiringSequence>& seqs, Vlp16ReturnMode mode,
                                     double offset_s, Vlp16ReturnFilter filter, int* packets) {
  Vlp16PacketEncoder encoder(mode, offset_s);
  Vlp16DecoderConfig config;
  config.lidar_clock_offset_s = offset_s;
  config.return_filter = filter;
  Vlp16Decoder decoder(LidarIntrinsics(), config);
  std::vector<LidarPoint> points;
  *packets = 0;
  double last_capture = -1e9;
  for (const auto& s : seqs) {
    const std::optional<LidarPacket> p = encoder.Add(s);
    if (!p) continue;
    ++*packets;
    EXPECT_EQ(p->payload.size(), kVlp16PacketBytes);
    EXPECT_GT(p->t_capture_s, last_capture);
    EXPECT_NEAR(p->t_capture_s, s.t_s + 15 * kVlp16FiringPeriodS + kVlp16TransmitLatencyS, 1e-12);
    last_capture = p->t_capture_s;
    const Status st = decoder.Decode(*p, &points);
    EXPECT_TRUE(st.ok) << st.message;
  }
  return points;
}

// Points come out in the order truth was generated (firing order; dual: last then strongest per laser).
void ExpectMatchesTruth(const std::vector<LidarPoint>& points, const std::vector<Commanded>& truth) {
  ASSERT_EQ(points.size(), truth.size());
  const LidarIntrinsics intr;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const LidarPoint& p = points[i];
    const Commanded& c = truth[i];
    ASSERT_EQ(p.laser_id, c.laser) << i;
    EXPECT_EQ(p.return_type, c.return_type) << i;
    EXPECT_EQ(p.intensity, c.reflectivity) << i;
    EXPECT_EQ(p.ring, static_cast<int>(std::lround((intr.elevation_deg[c.laser] + 15.0) / 2.0))) << i;
    // The timestamp is floored to 1 us: decoded firing times are at most 1 us early.
    EXPECT_LT(std::abs(p.t_s - c.t_s), 1e-6) << i;
    const Eigen::Vector3d origin = Vlp16RayOrigin(intr.vertical_offset_m[c.laser]);
    const Eigen::Vector3d v = Eigen::Vector3d(p.x_m, p.y_m, p.z_m) - origin;
    // Range: exact 2 mm code, only float storage of the point (< 1e-5 m at 90 m) adds error.
    EXPECT_NEAR(v.norm(), c.range_m, 2e-5) << i;
    // Direction: block azimuths carry 0.005 deg rounding, the interpolated step at most 0.01 deg * 0.81 more.
    const Eigen::Vector3d expected =
        Vlp16RayDirection(intr.elevation_deg[c.laser] * M_PI / 180.0, c.azimuth_deg * M_PI / 180.0);
    const double angle_deg = std::acos(std::min(1.0, v.normalized().dot(expected))) * 180.0 / M_PI;
    EXPECT_LT(angle_deg, 0.015) << i;
    const double daz = std::remainder(p.azimuth_deg - c.azimuth_deg, 360.0);
    EXPECT_LT(std::abs(daz), 0.015) << i;
  }
}

class Vlp16CodecModes : public ::testing::TestWithParam<Vlp16ReturnMode> {};

TEST_P(Vlp16CodecModes, EncoderDecoderRoundTrip) {
  const Vlp16ReturnMode mode = GetParam();
  std::vector<Commanded> truth;
  const auto seqs = MakeSequences(24 * 40 + 5, 12.3456789, &truth, mode);  // 5 left in an unfinished packet
  int packets = 0;
  const auto points = EncodeDecode(seqs, mode, -1.5, Vlp16ReturnFilter::kAll, &packets);
  const int per_packet = mode == Vlp16ReturnMode::kDual ? 12 : 24;
  EXPECT_EQ(packets, (24 * 40 + 5) / per_packet);
  const double t_end = seqs[packets * per_packet - 1].t_s + 4e-5;  // its last firing, not the next
  truth.erase(std::remove_if(truth.begin(), truth.end(), [&](const Commanded& c) { return c.t_s > t_end; }),
              truth.end());
  ExpectMatchesTruth(points, truth);
  for (std::size_t i = 1; i < points.size(); ++i) ASSERT_LE(points[i - 1].t_s, points[i].t_s) << i;
}

INSTANTIATE_TEST_SUITE_P(Modes, Vlp16CodecModes,
                         ::testing::Values(Vlp16ReturnMode::kStrongest, Vlp16ReturnMode::kLast,
                                           Vlp16ReturnMode::kDual));

TEST(Vlp16Codec, DualReturnFilterKeepsOneReturn) {
  std::vector<Commanded> truth;
  const auto seqs = MakeSequences(24, 1.0, &truth, Vlp16ReturnMode::kDual);
  int packets = 0;
  for (auto filter : {Vlp16ReturnFilter::kStrongest, Vlp16ReturnFilter::kLast}) {
    const auto points = EncodeDecode(seqs, Vlp16ReturnMode::kDual, 0.0, filter, &packets);
    std::vector<Commanded> kept;
    for (const auto& c : truth) {
      if ((c.return_type == 0) == (filter == Vlp16ReturnFilter::kStrongest)) kept.push_back(c);
    }
    ExpectMatchesTruth(points, kept);
  }
}

// The head's clock passes the top of the hour mid-stream: rig times must continue smoothly.
TEST(Vlp16Codec, HourRolloverIsUnwrapped) {
  const double offset_s = -3599.99;  // rig t = 0 is 10 ms before the top of the hour
  std::vector<Commanded> truth;
  const auto seqs = MakeSequences(24 * 20, 0.0, &truth, Vlp16ReturnMode::kStrongest);
  int packets = 0;
  const auto points = EncodeDecode(seqs, Vlp16ReturnMode::kStrongest, offset_s, Vlp16ReturnFilter::kAll, &packets);
  ASSERT_GT(seqs.back().t_s, 0.02);  // the stream crosses the hour (at rig t = 0.01 s)
  ExpectMatchesTruth(points, truth);

  Vlp16DecoderConfig config;
  Vlp16Decoder decoder(LidarIntrinsics(), config);
  EXPECT_DOUBLE_EQ(decoder.UnwrapToRigTime(3599999000u), 3599.999);
  EXPECT_DOUBLE_EQ(decoder.UnwrapToRigTime(1000u), 3600.001);       // next hour
  EXPECT_DOUBLE_EQ(decoder.UnwrapToRigTime(3599999500u), 3599.9995);  // late packet from the previous hour
  EXPECT_DOUBLE_EQ(decoder.UnwrapToRigTime(2000u), 3600.002);
}

TEST(Vlp16Codec, ConfigValidateAndBadPackets) {
  Vlp16DecoderConfig config;
  std::string error;
  EXPECT_TRUE(config.Validate(&error));
  config.max_range_m = 0.1;
  EXPECT_FALSE(config.Validate(&error));
  EXPECT_NE(error.find("max_range_m"), std::string::npos);

  Vlp16Decoder decoder{LidarIntrinsics(), Vlp16DecoderConfig()};
  std::vector<LidarPoint> points;
  LidarPacket short_packet;
  short_packet.payload.assign(1000, 0);
  const Status s = decoder.Decode(short_packet, &points);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("size 1000"), std::string::npos) << s.message;
  EXPECT_TRUE(points.empty());
  const LidarPacket pos = EncodeVlp16PositionPacket(5.0, 0.0, 2, "$GPRMC,x");
  EXPECT_TRUE(decoder.Decode(pos, &points).ok);
  EXPECT_TRUE(points.empty());
  ASSERT_TRUE(decoder.last_position().has_value());
  EXPECT_EQ(decoder.last_position()->timestamp_us, 5000000u);
}

}  // namespace
}  // namespace rotolidar
