// The live merger puts packets and rig samples into the order `rotolidar slam` feeds a recording, maps host
// arrival times onto the rig clock, waits for the samples (but not forever) and refuses samples that come late.
#include <gtest/gtest.h>

#include "bench/live/live_merger.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench {
namespace {

constexpr double kPeriodS = 1327.104e-6;
// Capture time of a packet whose first firing is at t_s, as the twin stamps it (core/wire/vlp16.hpp).
constexpr double kSendDelayS = kPeriodS - 55.296e-6 + 15 * kVlp16FiringPeriodS + kVlp16TransmitLatencyS;

LidarPacket DataPacket(double first_firing_s, double host_s) {
  Vlp16RawPacket raw;
  raw.timestamp_us = static_cast<uint32_t>(std::llround(first_firing_s * 1e6));
  LidarPacket p;
  p.payload = SerializeVlp16DataPacket(raw);
  p.t_capture_s = host_s;
  return p;
}

RigSample Imu(double t) {
  RigSample s;
  s.imu.t_s = t;
  return s;
}

RigSample Encoder(double t) {
  RigSample s;
  s.type = RigSample::Type::kEncoder;
  s.encoder.t_s = t;
  return s;
}

std::vector<LiveItem::Kind> Kinds(const std::vector<LiveItem>& items) {
  std::vector<LiveItem::Kind> k;
  for (const auto& i : items) k.push_back(i.kind);
  return k;
}

TEST(LiveMerger, SamplesBeforeTheirPacketAndRigClockCaptureTimes) {
  LiveMerger merger(LiveMergerConfig{});
  const double host0 = 5000.0;  // the host's steady clock has nothing to do with the rig clock
  // Packet 0 fired at rig 1.000 s; packet 1 one period later, and the network held it 0.3 ms longer.
  merger.AddPacket(DataPacket(1.0, host0));
  merger.AddPacket(DataPacket(1.0 + kPeriodS, host0 + kPeriodS + 0.0003));
  for (double t : {0.999, 1.0005, 1.0015, 1.0020, 1.0031}) merger.AddSample(Imu(t));
  merger.AddSample(Encoder(1.0031));  // the samples have reached 1.0031 > both capture times
  std::vector<LiveItem> out;
  merger.Release(host0 + 0.002, &out);
  using K = LiveItem::Kind;
  // Rig captures from the packets' own timestamps, as the twin stamps them: 1.0 + send delay (~1.41 ms), then
  // one period later (~2.74 ms), whatever the network did.
  ASSERT_EQ(Kinds(out), (std::vector<K>{K::kImu, K::kImu, K::kPacket, K::kImu, K::kImu, K::kPacket}));
  EXPECT_NEAR(out[2].packet.t_capture_s, 1.0 + kSendDelayS, 1e-6);  // the timestamp counts whole microseconds
  EXPECT_NEAR(out[5].packet.t_capture_s, 1.0 + kSendDelayS + kPeriodS, 1e-6);
  EXPECT_EQ(merger.counts().hold_timeouts, 0u);
  // With no packet left, samples go once they are hold_s old on the rig clock.
  out.clear();
  merger.Release(host0 + 0.002 + 0.25 + 0.01, &out);
  EXPECT_EQ(Kinds(out), (std::vector<K>{K::kImu, K::kEncoder}));
}

TEST(LiveMerger, APacketWaitsForTheSamplesButNotForever) {
  LiveMergerConfig config;
  config.hold_s = 0.1;
  LiveMerger merger(config);
  merger.AddSample(Imu(1.0));
  merger.AddPacket(DataPacket(1.0, 100.0));  // capture 1.0014: the IMU has only reached 1.0
  std::vector<LiveItem> out;
  merger.Release(100.05, &out);
  EXPECT_TRUE(out.empty());  // held
  merger.AddSample(Imu(1.002));
  merger.Release(100.06, &out);
  ASSERT_EQ(out.size(), 2u);  // the sample at 1.0; 1.002 stays for the next packet
  EXPECT_EQ(out[1].kind, LiveItem::Kind::kPacket);
  out.clear();
  merger.AddPacket(DataPacket(1.0 + kPeriodS, 100.0 + kPeriodS));
  merger.Release(100.0 + kPeriodS + 0.05, &out);
  EXPECT_TRUE(out.empty());  // capture 1.0027 > 1.002: waits
  merger.Release(100.0 + kPeriodS + 0.11, &out);  // the IMU went silent: after hold_s the packet goes anyway
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(merger.counts().hold_timeouts, 1u);
  // A sample older than one already released cannot join the recording (its CSV is strictly increasing).
  merger.AddSample(Imu(1.0015));
  merger.AddSample(Imu(1.002));  // a duplicate
  out.clear();
  merger.ReleaseAll(&out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(merger.counts().late_samples, 2u);
}

TEST(LiveMerger, PositionPacketsFollowTheDataPacketsAndTimesNeverPrecedeTheEpoch) {
  LiveMergerConfig config;
  config.min_capture_s = 0.0;  // epoch_unix_s = 0: a pcap cannot hold negative rig times
  LiveMerger merger(config);
  LidarPacket position;
  position.udp_port = kVlp16PositionPort;
  position.payload.assign(kVlp16PositionPacketBytes, 0);
  position.t_capture_s = 50.0;  // host time; before any data packet: held
  merger.AddPacket(position);
  std::vector<LiveItem> out;
  merger.Release(50.001, &out);
  EXPECT_TRUE(out.empty());
  merger.AddPacket(DataPacket(0.0, 50.002));  // fired at rig 0: capture 1.41 ms; arrived 2 ms after the position
  position.t_capture_s = 50.0025;
  merger.AddPacket(position);
  merger.ReleaseAll(&out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].packet.t_capture_s, 0.0);  // 1.41 ms - 2 ms would be negative: held at the epoch
  EXPECT_NEAR(out[1].packet.t_capture_s, kSendDelayS, 1e-9);
  EXPECT_NEAR(out[2].packet.t_capture_s, kSendDelayS + 0.0005, 1e-9);  // the data packet + 0.5 ms of host time
}

}  // namespace
}  // namespace rotolidar::bench
