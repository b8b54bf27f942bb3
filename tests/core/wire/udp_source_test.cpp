// UDP loopback: a tiny queue must count its drops; wrong-size datagrams are rejected; the sender routes data
// and position packets to their ports and paces them.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/wire/udp_source.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar {
namespace {

LidarPacket Numbered(int i, std::size_t size = kVlp16PacketBytes) {
  LidarPacket p;
  p.t_capture_s = 1e-3 * i;
  p.payload.assign(size, static_cast<uint8_t>(i));
  return p;
}

// Waits (no timing assertion) until the receiver has accounted for `n` datagrams, or 10 s passed.
void WaitForAccounted(const UdpPacketSource& source, std::size_t n) {
  for (int i = 0; i < 1000; ++i) {
    if (source.received() + source.dropped() + source.rejected() >= n) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

TEST(UdpLoopback, TinyQueueCountsDrops) {
  UdpSourceConfig config;
  config.bind_address = "127.0.0.1";
  config.port = 0;  // any free port
  config.queue_capacity = 3;
  UdpPacketSource source;
  const Status started = source.Start(config);
  ASSERT_TRUE(started.ok) << started.message;
  ASSERT_NE(source.port(), 0);

  UdpPacketSender sender;
  ASSERT_TRUE(sender.Open("127.0.0.1", source.port()).ok);
  std::vector<LidarPacket> packets;
  for (int i = 0; i < 20; ++i) packets.push_back(Numbered(i));
  packets.push_back(Numbered(99, 100));  // wrong size
  packets.push_back(Numbered(98, kVlp16PositionPacketBytes));
  // 22 datagrams (~26 kB) fit the default socket buffer: the kernel drops none, the queue drops the rest.
  ASSERT_TRUE(sender.SendAll(packets, 0.0).ok);
  WaitForAccounted(source, packets.size());
  EXPECT_EQ(source.received(), 3u);
  EXPECT_EQ(source.dropped(), 18u);  // 17 data + 1 position packet
  EXPECT_EQ(source.rejected(), 1u);

  LidarPacket got;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(source.Pop(&got, 1.0));
    EXPECT_EQ(got.payload, packets[i].payload);  // FIFO: the first three survive
    EXPECT_EQ(got.udp_port, kVlp16DataPort);
  }
  EXPECT_FALSE(source.Pop(&got, 0.05));
  source.Stop();
  EXPECT_FALSE(source.Pop(&got, 0.05));
}

TEST(UdpLoopback, PacedSendArrivesInOrder) {
  UdpSourceConfig config;
  config.bind_address = "127.0.0.1";
  config.port = 0;
  config.queue_capacity = 64;
  UdpPacketSource source;
  ASSERT_TRUE(source.Start(config).ok);
  UdpPacketSender sender;
  ASSERT_TRUE(sender.Open("127.0.0.1", source.port()).ok);
  std::vector<LidarPacket> packets;
  for (int i = 0; i < 10; ++i) packets.push_back(Numbered(i));
  packets.push_back(Numbered(10, kVlp16PositionPacketBytes));
  ASSERT_TRUE(sender.SendAll(packets, 10.0).ok);  // 10 ms of data at 10x: ~1 ms
  LidarPacket got;
  double last_t = -1.0;
  for (const auto& sent : packets) {
    ASSERT_TRUE(source.Pop(&got, 5.0));
    EXPECT_EQ(got.payload, sent.payload);
    EXPECT_GE(got.t_capture_s, last_t);
    last_t = got.t_capture_s;
  }
  EXPECT_EQ(got.udp_port, kVlp16PositionPort);
  EXPECT_EQ(source.dropped(), 0u);
}

TEST(UdpLoopback, BadConfigAndAddress) {
  UdpPacketSource source;
  UdpSourceConfig config;
  config.queue_capacity = 0;
  EXPECT_FALSE(source.Start(config).ok);
  config.queue_capacity = 1;
  config.bind_address = "not-an-ip";
  const Status s = source.Start(config);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("not-an-ip"), std::string::npos);
  UdpPacketSender sender;
  EXPECT_FALSE(sender.Send(Numbered(0)).ok);
}

// The sensor sends data and position packets to two ports; the sender routes by LidarPacket::udp_port.
TEST(UdpLoopback, SenderRoutesPositionPacketsToTheirPort) {
  UdpSourceConfig config;
  config.bind_address = "127.0.0.1";
  config.port = 0;
  UdpPacketSource data, position;
  ASSERT_TRUE(data.Start(config).ok);
  ASSERT_TRUE(position.Start(config).ok);
  UdpSenderConfig sender_config;
  sender_config.data_port = data.port();
  sender_config.position_port = position.port();
  UdpPacketSender sender;
  ASSERT_TRUE(sender.Open(sender_config).ok);
  std::vector<LidarPacket> packets;
  for (int i = 0; i < 12; ++i) {
    packets.push_back(i % 4 == 3 ? Numbered(i, kVlp16PositionPacketBytes) : Numbered(i));
    if (i % 4 == 3) packets.back().udp_port = kVlp16PositionPort;
  }
  ASSERT_TRUE(sender.SendAll(packets, 0.0).ok);
  EXPECT_EQ(sender.sent(), packets.size());
  WaitForAccounted(data, 9);
  WaitForAccounted(position, 3);
  EXPECT_EQ(data.received(), 9u);
  EXPECT_EQ(position.received(), 3u);
  LidarPacket got;
  for (const LidarPacket& sent : packets) {
    UdpPacketSource& source = sent.udp_port == kVlp16PositionPort ? position : data;
    ASSERT_TRUE(source.Pop(&got, 1.0));
    EXPECT_EQ(got.payload, sent.payload);  // each port keeps its order
  }
}

// Pacing arithmetic (no clock): packet due times after the first scale with 1 / rate.
TEST(PacketPacer, DueTimesScaleWithRate) {
  PacketPacer pacer(10.0);
  EXPECT_EQ(pacer.DueAfterFirstS(7.0), 0.0);  // nothing started yet
  EXPECT_EQ(pacer.WaitUntilDue(5.0), 0.0);    // the first packet leaves at once
  EXPECT_DOUBLE_EQ(pacer.DueAfterFirstS(6.0), 0.1);
  EXPECT_NEAR(pacer.DueAfterFirstS(5.001327), 0.0001327, 1e-15);  // 5.001327 - 5 is inexact in binary
  EXPECT_EQ(pacer.DueAfterFirstS(4.0), 0.0);  // capture times going backwards: due at once
  PacketPacer fast(0.0);
  fast.WaitUntilDue(5.0);
  EXPECT_EQ(fast.DueAfterFirstS(100.0), 0.0);
}

TEST(UdpSenderConfig, ValidateNamesTheField) {
  std::string error;
  EXPECT_TRUE(UdpSenderConfig{}.Validate(&error)) << error;
  UdpSenderConfig c;
  c.host = "localhost";  // names are not resolved: IPv4 literals only
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("host"), std::string::npos) << error;
  c = UdpSenderConfig{};
  c.position_port = 0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("position_port"), std::string::npos) << error;
  UdpPacketSender sender;
  EXPECT_FALSE(sender.Open(c).ok);
}

}  // namespace
}  // namespace rotolidar
