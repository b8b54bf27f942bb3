// VLP-16 raw fields: serialize/parse round trip, malformed packets, position packets, the timestamp formula.
#include <gtest/gtest.h>

#include <cmath>

#include "core/wire/vlp16.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

Vlp16RawPacket RandomPacket(uint64_t seed) {
  RandomStream rng(seed, "vlp16-wire");
  Vlp16RawPacket p;
  for (auto& b : p.blocks) {
    b.azimuth_centideg = static_cast<uint16_t>(rng.NextU64() % 36000);
    for (int ch = 0; ch < 32; ++ch) {
      b.distance_2mm[ch] = static_cast<uint16_t>(rng.NextU64() & 0xFFFF);
      b.reflectivity[ch] = static_cast<uint8_t>(rng.NextU64() & 0xFF);
    }
  }
  p.timestamp_us = static_cast<uint32_t>(rng.NextU64() % kVlp16MicrosPerHour);
  p.return_mode = static_cast<uint8_t>(Vlp16ReturnMode::kDual);
  return p;
}

void ExpectEqual(const Vlp16RawPacket& a, const Vlp16RawPacket& b) {
  for (int i = 0; i < 12; ++i) {
    EXPECT_EQ(a.blocks[i].flag, b.blocks[i].flag) << "block " << i;
    EXPECT_EQ(a.blocks[i].azimuth_centideg, b.blocks[i].azimuth_centideg) << "block " << i;
    EXPECT_EQ(a.blocks[i].distance_2mm, b.blocks[i].distance_2mm) << "block " << i;
    EXPECT_EQ(a.blocks[i].reflectivity, b.blocks[i].reflectivity) << "block " << i;
  }
  EXPECT_EQ(a.timestamp_us, b.timestamp_us);
  EXPECT_EQ(a.return_mode, b.return_mode);
  EXPECT_EQ(a.product_id, b.product_id);
}

TEST(Vlp16Wire, SerializeParseRoundTripFieldByField) {
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const Vlp16RawPacket in = RandomPacket(seed);
    const std::vector<uint8_t> bytes = SerializeVlp16DataPacket(in);
    ASSERT_EQ(bytes.size(), kVlp16PacketBytes);
    EXPECT_EQ(bytes[0], 0xFF);  // the flag's wire bytes
    EXPECT_EQ(bytes[1], 0xEE);
    Vlp16RawPacket out;
    const Status s = ParseVlp16DataPacket(bytes.data(), bytes.size(), &out);
    ASSERT_TRUE(s.ok) << s.message;
    ExpectEqual(in, out);
    EXPECT_EQ(SerializeVlp16DataPacket(out), bytes);
  }
}

// Each corruption must be reported at its byte offset and name the field.
TEST(Vlp16Wire, MalformedPacketsNameOffsetAndField) {
  const std::vector<uint8_t> good = SerializeVlp16DataPacket(RandomPacket(7));
  Vlp16RawPacket out;
  struct Case {
    std::size_t offset;
    uint8_t value;
    std::string expect_offset, expect_field;
  };
  const Case cases[] = {{300, 0x00, "byte offset 300", "block 3 flag"},
                        {1101, 0xEF, "byte offset 1100", "block 11 flag"},
                        {203, 0x8D, "byte offset 202", "block 2 azimuth"},  // >= 0x8D00 = 36096
                        {1203, 0xF0, "byte offset 1200", "timestamp"},
                        {1204, 0x40, "byte offset 1204", "return mode"},
                        {1205, 0x21, "byte offset 1205", "product id"}};
  for (const Case& c : cases) {
    std::vector<uint8_t> bad = good;
    bad[c.offset] = c.value;
    const Status s = ParseVlp16DataPacket(bad.data(), bad.size(), &out);
    ASSERT_FALSE(s.ok) << "corruption at " << c.offset;
    EXPECT_NE(s.message.find(c.expect_offset), std::string::npos) << s.message;
    EXPECT_NE(s.message.find(c.expect_field), std::string::npos) << s.message;
  }
  const Status s = ParseVlp16DataPacket(good.data(), 1205, &out);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("size 1205"), std::string::npos) << s.message;
}

TEST(Vlp16Wire, PositionPacketRoundTrip) {
  const std::string nmea = "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A\r\n";
  const LidarPacket p = EncodeVlp16PositionPacket(12.345678, 2.0, 2, nmea);
  EXPECT_EQ(p.udp_port, kVlp16PositionPort);
  EXPECT_DOUBLE_EQ(p.t_capture_s, 12.345678);
  ASSERT_EQ(p.payload.size(), kVlp16PositionPacketBytes);
  Vlp16PositionPacket out;
  const Status s = ParseVlp16PositionPacket(p.payload.data(), p.payload.size(), &out);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(out.timestamp_us, 10345678u);
  EXPECT_EQ(out.pps_status, 2);
  EXPECT_EQ(out.nmea, nmea);
  std::vector<uint8_t> bad = p.payload;
  bad[202] = 9;
  const Status e = ParseVlp16PositionPacket(bad.data(), bad.size(), &out);
  ASSERT_FALSE(e.ok);
  EXPECT_NE(e.message.find("byte offset 202"), std::string::npos) << e.message;
}

TEST(Vlp16Wire, TimestampIsMicrosecondsPastTheHour) {
  EXPECT_EQ(Vlp16TimestampUs(0.0, 0.0), 0u);
  EXPECT_EQ(Vlp16TimestampUs(0.001327, 0.0), 1327u);  // whole microseconds survive rounding
  EXPECT_EQ(Vlp16TimestampUs(1.0000019, 0.0), 1000001u);
  EXPECT_EQ(Vlp16TimestampUs(3600.5, 0.0), 500000u);
  EXPECT_EQ(Vlp16TimestampUs(0.0, 0.25), 3599750000u);  // before the offset: wraps into the previous hour
  EXPECT_EQ(Vlp16TimestampUs(10.0, -7200.0 + 5.0), 5000000u);
}

// The worked example of the NMEA 0183 reference (RMC): 22:54:46 UTC on 19 Nov 1994, checksum 0x68.
TEST(Vlp16Wire, GprmcParsesAReferenceSentence) {
  double utc_s = 0.0;
  const std::string ref = "$GPRMC,225446,A,4916.45,N,12311.12,W,000.5,054.7,191194,020.3,E*68";
  const Status s = ParseGprmcUtc(ref + "\r\n", &utc_s);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_DOUBLE_EQ(utc_s, 785285686.0);  // Python: calendar.timegm((1994, 11, 19, 22, 54, 46))
  std::string bad = ref;
  bad[bad.size() - 1] = '9';
  const Status e = ParseGprmcUtc(bad, &utc_s);
  ASSERT_FALSE(e.ok);
  EXPECT_NE(e.message.find("checksum"), std::string::npos) << e.message;
  const Status d = ParseGprmcUtc("$GPRMC,225446,A,4916.45,N,12311.12,W,000.5,054.7,191394,020.3,E", &utc_s);
  ASSERT_FALSE(d.ok);
  EXPECT_NE(d.message.find("field 9"), std::string::npos) << d.message;
}

TEST(Vlp16Wire, GprmcFormatParseRoundTripAcrossDates) {
  // A leap day, 1999/2000, both ends of the 2-digit year window (1980..2079); fractions of a second drop.
  for (double utc_s : {1709211600.0 + 3599.75, 946684799.5, 315532800.0, 3471292799.0}) {
    const std::string sentence = FormatGprmc(utc_s, true, -33.8568, 151.2153);
    ASSERT_EQ(sentence.substr(0, 7), "$GPRMC,");
    ASSERT_EQ(sentence.substr(sentence.size() - 2), "\r\n");
    double back = -1.0;
    const Status s = ParseGprmcUtc(sentence, &back);
    ASSERT_TRUE(s.ok) << s.message << " in " << sentence;
    EXPECT_DOUBLE_EQ(back, std::floor(utc_s)) << sentence;
  }
  EXPECT_NE(FormatGprmc(0.0, true, -33.8568, 151.2153).find(",3351.4080,S,15112.9180,E,"), std::string::npos);
  EXPECT_NE(FormatGprmc(0.0, false, 0.0, 0.0).find(",V,"), std::string::npos);
  EXPECT_EQ(UnixDaysFromCivil(2024, 2, 29), 19782);  // Python: date(2024,2,29) - date(1970,1,1)
}

// With PPS locked the sensor clock is UTC past the hour: the decoder recovers the hour from the RMC sentence, also
// when the sentence (up to a second old) still names the previous hour.
TEST(Vlp16Wire, DecoderFindsTheUtcHourFromPositionPackets) {
  Vlp16Decoder decoder(LidarIntrinsics{}, Vlp16DecoderConfig{});
  std::vector<LidarPoint> points;
  EXPECT_FALSE(decoder.hour_start_unix_s().has_value());
  const double hour = 1709211600.0;  // 2024-02-29 13:00:00 UTC
  // Sensor at 13:00:00.300; the last sentence is for 12:59:59.
  LidarPacket p = EncodeVlp16PositionPacket(0.3, 0.0, 2, FormatGprmc(hour - 1.0, true, 0.0, 0.0));
  ASSERT_TRUE(decoder.Decode(p, &points).ok);
  ASSERT_TRUE(decoder.hour_start_unix_s().has_value());
  EXPECT_DOUBLE_EQ(*decoder.hour_start_unix_s(), hour);
  EXPECT_TRUE(points.empty());
  // Not locked: no claim about UTC (the previous locked value stays).
  Vlp16Decoder unlocked(LidarIntrinsics{}, Vlp16DecoderConfig{});
  p = EncodeVlp16PositionPacket(0.3, 0.0, 1, FormatGprmc(hour, true, 0.0, 0.0));
  ASSERT_TRUE(unlocked.Decode(p, &points).ok);
  EXPECT_FALSE(unlocked.hour_start_unix_s().has_value());
  ASSERT_TRUE(unlocked.last_position().has_value());
  EXPECT_EQ(unlocked.last_position()->pps_status, 1);
}

}  // namespace
}  // namespace rotolidar
