// Encoder -> decoder round trips on synthetic firing sequences, and hour-rollover unwrapping.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/wire/vlp16.hpp"
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

// One dual-return packet (12 sequences) through the codec's serializer. Per firing: lasers 0..7 carry one echo
// in both blocks (identical distance and reflectivity: the strongest was also the last), lasers 8..11 two echoes
// (last 5 m / reflectivity 10, strongest 2 m / 80), lasers 12..13 the same distance with different
// reflectivities (not a duplicate: two points), lasers 14..15 no return.
LidarPacket DualPacketWithDuplicates() {
  Vlp16PacketEncoder encoder(Vlp16ReturnMode::kDual, 0.0);
  Vlp16FiringSequence s;
  for (int l = 0; l < 16; ++l) {
    const bool same = l < 8, two = l >= 8 && l < 12, reflect_only = l == 12 || l == 13;
    s.distance_2mm[l] = same ? 3000 : two ? 2500 : reflect_only ? 4000 : 0;
    s.reflectivity[l] = same ? 50 : two ? 10 : reflect_only ? 30 : 0;
    s.distance2_2mm[l] = same ? 3000 : two ? 1000 : reflect_only ? 4000 : 0;
    s.reflectivity2[l] = same ? 50 : two ? 80 : reflect_only ? 31 : 0;
  }
  for (int k = 0;; ++k) {
    s.t_s = 2.0 + k * kVlp16SequencePeriodS;
    s.azimuth_centideg = static_cast<uint16_t>(k * 20);
    if (std::optional<LidarPacket> p = encoder.Add(s)) return *p;
  }
}

std::vector<LidarPoint> DecodeDual(const LidarPacket& packet, bool keep_both, Vlp16ReturnFilter filter,
                                   std::size_t* merged) {
  Vlp16DecoderConfig config;
  config.keep_duplicate_dual_returns = keep_both;
  config.return_filter = filter;
  Vlp16Decoder decoder(LidarIntrinsics(), config);
  std::vector<LidarPoint> points;
  EXPECT_TRUE(decoder.Decode(packet, &points).ok);
  *merged = decoder.merged_dual_duplicates();
  return points;
}

TEST(Vlp16Codec, DualDuplicateReturnsBecomeOnePointFlaggedBoth) {
  const LidarPacket packet = DualPacketWithDuplicates();
  std::size_t merged = 0;
  const std::vector<LidarPoint> points = DecodeDual(packet, false, Vlp16ReturnFilter::kAll, &merged);
  // Per firing: 8 merged + 4 x 2 + 2 x 2 = 20 points; 12 firings.
  ASSERT_EQ(points.size(), 12u * 20);
  EXPECT_EQ(merged, 12u * 8);
  std::size_t both = 0;
  for (const LidarPoint& p : points) {
    const bool duplicate_laser = p.laser_id < 8;
    EXPECT_EQ(p.return_type == kReturnStrongestAndLast, duplicate_laser) << int(p.laser_id);
    // 3000 x 2 mm from the laser's origin, which sits < 12 mm off the lidar origin
    if (duplicate_laser) {
      EXPECT_NEAR(Eigen::Vector3f(p.x_m, p.y_m, p.z_m).norm(), 6.0, 0.02);
    }
    both += p.return_type == kReturnStrongestAndLast;
  }
  EXPECT_EQ(both, merged);

  // Keep both: the two copies come back (last, then strongest), nothing merged; points + merged above = this.
  std::size_t merged_keep = 0;
  const std::vector<LidarPoint> kept = DecodeDual(packet, true, Vlp16ReturnFilter::kAll, &merged_keep);
  EXPECT_EQ(kept.size(), 12u * 28);
  EXPECT_EQ(merged_keep, 0u);
  EXPECT_EQ(kept.size(), points.size() + merged);
  for (const LidarPoint& p : kept) EXPECT_NE(p.return_type, kReturnStrongestAndLast);
  ASSERT_EQ(kept[0].laser_id, 0);
  EXPECT_EQ(kept[0].return_type, kReturnLast);
  EXPECT_EQ(kept[1].laser_id, 0);
  EXPECT_EQ(kept[1].return_type, kReturnStrongest);
  EXPECT_EQ(kept[0].x_m, kept[1].x_m);

  // One echo a firing: the merged point passes either filter (8 + 4 + 2 per firing), as one copy did before.
  for (Vlp16ReturnFilter filter : {Vlp16ReturnFilter::kStrongest, Vlp16ReturnFilter::kLast}) {
    std::size_t m = 0, m_keep = 0;
    EXPECT_EQ(DecodeDual(packet, false, filter, &m).size(), 12u * 14);
    EXPECT_EQ(DecodeDual(packet, true, filter, &m_keep).size(), 12u * 14);
    EXPECT_EQ(m, 12u * 8);
  }
  EXPECT_TRUE(Vlp16ReturnSelected(Vlp16ReturnFilter::kLast, kReturnStrongestAndLast));
  EXPECT_FALSE(Vlp16ReturnSelected(Vlp16ReturnFilter::kLast, kReturnStrongest));
  EXPECT_FALSE(Vlp16ReturnSelected(Vlp16ReturnFilter::kStrongest, kReturnLast));
}

// The head's clock passes the top of the hour mid-stream: rig times must continue smoothly.
// A free-running head's clock: the packet stamp at rig time t reads t - offset + D * 1e-6 * t. Against the same
// encoder without drift it differs by D * 1e-6 * t (D us per s), to the 1 us the wire holds; at two times.
TEST(Vlp16Codec, ClockDriftMovesPacketStampsLinearly) {
  const double offset_s = 0.25, drift_ppm = 80.0;
  for (const double t0 : {10.0, 1000.0}) {
    Vlp16PacketEncoder plain(Vlp16ReturnMode::kStrongest, offset_s);
    Vlp16PacketEncoder drifting(Vlp16ReturnMode::kStrongest, offset_s, drift_ppm);
    std::optional<LidarPacket> a, b;
    for (int i = 0; i < plain.SequencesPerPacket(); ++i) {
      Vlp16FiringSequence s;
      s.t_s = t0 + i * 55.296e-6;
      a = plain.Add(s);
      b = drifting.Add(s);
    }
    ASSERT_TRUE(a && b);
    EXPECT_EQ(a->t_capture_s, b->t_capture_s);  // the host's capture time does not follow the sensor clock
    Vlp16RawPacket ra, rb;
    ASSERT_TRUE(ParseVlp16DataPacket(a->payload.data(), a->payload.size(), &ra).ok);
    ASSERT_TRUE(ParseVlp16DataPacket(b->payload.data(), b->payload.size(), &rb).ok);
    const double gained_us = double(rb.timestamp_us) - double(ra.timestamp_us);
    EXPECT_NEAR(gained_us, drift_ppm * t0, 1.0) << "t0 " << t0;  // 800 us at 10 s, 80000 us at 1000 s
    EXPECT_NEAR(double(rb.timestamp_us), std::floor((t0 - offset_s + drift_ppm * 1e-6 * t0) * 1e6), 1.0);
  }
}

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
