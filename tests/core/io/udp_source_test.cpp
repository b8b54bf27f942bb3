// UDP loopback: a tiny queue must count its drops; wrong-size datagrams are rejected.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/io/udp_source.hpp"
#include "core/io/vlp16.hpp"

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

}  // namespace
}  // namespace rotolidar
