// The rig-sample protocol: encode -> decode round trips, every malformed field named with its offset, sequence
// gaps seen as lost datagrams over loopback; the VLP-16 timestamp gap counter.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>

#include "core/wire/packet_gaps.hpp"
#include "core/wire/rig_udp.hpp"
#include "core/wire/udp_sender.hpp"

namespace rotolidar {
namespace {

RigSample Imu(double t, double k) {
  RigSample s;
  s.imu.t_s = t;
  s.imu.gyro_radps = Eigen::Vector3d(0.1 * k, -0.2, 1e-9);
  s.imu.accel_mps2 = Eigen::Vector3d(0.3, 9.80665, -k);
  return s;
}

RigSample Encoder(double t, uint32_t count) {
  RigSample s;
  s.type = RigSample::Type::kEncoder;
  s.encoder.t_s = t;
  s.encoder.count = count;
  return s;
}

TEST(RigProtocol, RoundTripKeepsEveryValue) {
  RigDatagram in;
  in.sequence = 0xFFFFFFFEu;
  for (int i = 0; i < 20; ++i) in.samples.push_back(i % 3 ? Imu(12.345 + 0.005 * i, i) : Encoder(12.3 + i * 1e-3, 4095 - i));
  std::vector<uint8_t> bytes;
  ASSERT_TRUE(EncodeRigDatagram(in, &bytes).ok);
  EXPECT_EQ(bytes.size(), 16u + 20u * 64u);
  RigDatagram out;
  const Status s = DecodeRigDatagram(bytes.data(), bytes.size(), &out);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(out.sequence, in.sequence);
  ASSERT_EQ(out.samples.size(), in.samples.size());
  for (std::size_t i = 0; i < in.samples.size(); ++i) {
    ASSERT_EQ(out.samples[i].type, in.samples[i].type);
    EXPECT_NEAR(out.samples[i].t_s(), in.samples[i].t_s(), 0.6e-9);  // rounded to the nanosecond
    if (in.samples[i].type == RigSample::Type::kImu) {
      EXPECT_EQ(out.samples[i].imu.gyro_radps, in.samples[i].imu.gyro_radps);  // float64 on the wire: exact
      EXPECT_EQ(out.samples[i].imu.accel_mps2, in.samples[i].imu.accel_mps2);
    } else {
      EXPECT_EQ(out.samples[i].encoder.count, in.samples[i].encoder.count);
    }
  }
}

TEST(RigProtocol, MalformedDatagramsNameOffsetAndField) {
  RigDatagram in;
  in.samples = {Imu(1.0, 1), Encoder(1.001, 7)};
  std::vector<uint8_t> good;
  ASSERT_TRUE(EncodeRigDatagram(in, &good).ok);
  RigDatagram out;
  auto expect_error = [&](std::vector<uint8_t> bytes, const std::string& needle) {
    const Status s = DecodeRigDatagram(bytes.data(), bytes.size(), &out);
    EXPECT_FALSE(s.ok) << needle;
    EXPECT_NE(s.message.find(needle), std::string::npos) << s.message;
  };
  auto with = [&](std::size_t at, uint8_t v) { auto b = good; b[at] = v; return b; };
  expect_error({good.begin(), good.begin() + 10}, "byte 0 (header)");
  expect_error(with(0, 'X'), "byte 0 (magic)");
  expect_error(with(4, 2), "byte 4 (version)");
  expect_error(with(5, 0), "byte 5 (record count)");
  expect_error(with(5, 3), "byte 0 (size)");
  expect_error(with(16 + 64, 9), "byte 80 (record type)");
  auto nan = good;
  const double bad = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(nan.data() + 16 + 40, &bad, 8);
  expect_error(nan, "byte 56 (accel)");
  std::vector<uint8_t> bytes;
  EXPECT_FALSE(EncodeRigDatagram(RigDatagram{}, &bytes).ok);  // no records
}

TEST(RigUdp, SequenceGapsAreLostDatagrams) {
  RigSourceConfig config;
  config.socket.bind_address = "127.0.0.1";
  RigSampleSource source;
  ASSERT_TRUE(source.Start(config).ok);
  RigSampleSender sender;
  ASSERT_TRUE(sender.Open("127.0.0.1", source.port()).ok);
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(sender.Add(Imu(0.005 * i, i)).ok);  // datagrams 0..9
  // Datagrams 10..12 "lost": encode them but never send; then 13 and 14 arrive.
  UdpPacketSender raw;
  ASSERT_TRUE(raw.Open("127.0.0.1", source.port()).ok);
  for (uint32_t seq : {13u, 14u, 5u}) {  // 5: a late duplicate
    RigDatagram d;
    d.sequence = seq;
    d.samples = {Encoder(0.1 + seq * 1e-3, seq)};
    LidarPacket p;
    ASSERT_TRUE(EncodeRigDatagram(d, &p.payload).ok);
    ASSERT_TRUE(raw.Send(p).ok);
  }
  LidarPacket junk;
  junk.payload.assign(20, 0);
  ASSERT_TRUE(raw.Send(junk).ok);
  std::vector<RigSample> got;
  for (int i = 0; i < 500 && got.size() < 13; ++i) source.PopAll(&got, 0.01);
  for (int i = 0; i < 100 && source.malformed() == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(got.size(), 13u);
  EXPECT_EQ(source.datagrams(), 13u);
  EXPECT_EQ(source.lost(), 3u);
  EXPECT_EQ(source.out_of_order(), 1u);
  EXPECT_EQ(source.malformed(), 1u);
  EXPECT_NE(source.last_error().find("magic"), std::string::npos) << source.last_error();
}

TEST(Vlp16Gaps, TimestampStepsCountMissingPackets) {
  Vlp16GapCounter gaps;
  const uint8_t strongest = 0x37, dual = 0x39;
  uint32_t t = 3599990000u;  // 10 ms before the hour wraps
  EXPECT_EQ(gaps.Add(t, strongest), 0u);
  t += 1327;
  EXPECT_EQ(gaps.Add(t, strongest), 0u);   // the normal step (1327 or 1328 us)
  EXPECT_EQ(gaps.Add(t + 3 * 1327, strongest), 2u);  // 3 periods: 2 packets never came
  t += 3 * 1327;
  EXPECT_EQ(gaps.Add(t - 1327, strongest), 0u);  // a late packet: out of order, not lost
  EXPECT_EQ(gaps.out_of_order(), 1u);
  const uint32_t wrapped = static_cast<uint32_t>((t + 2 * 1327ull) % 3600000000ull);  // across the hour
  EXPECT_EQ(gaps.Add(wrapped, strongest), 1u);
  EXPECT_EQ(gaps.Add(wrapped + 4 * 664, dual), 3u);  // dual mode: half the period
  EXPECT_EQ(gaps.lost(), 6u);
}

}  // namespace
}  // namespace rotolidar
