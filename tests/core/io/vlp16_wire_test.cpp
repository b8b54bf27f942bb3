// VLP-16 raw fields: serialize/parse round trip, malformed packets, position packets, the timestamp formula.
#include <gtest/gtest.h>

#include "core/io/vlp16.hpp"
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

}  // namespace
}  // namespace rotolidar
