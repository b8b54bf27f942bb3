// Data packets back in timestamp order: shuffles are undone, duplicates and late packets dropped, a corrupted
// stamp rejected, a real jump followed, the hour wrap passed; every case counted.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/util/rng.hpp"
#include "core/wire/packet_orderer.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar {
namespace {

constexpr double kPeriodUs = 1327.104;

LidarPacket Packet(uint32_t timestamp_us) {
  Vlp16RawPacket raw;
  raw.timestamp_us = timestamp_us % 3600000000u;
  LidarPacket p;
  p.payload = SerializeVlp16DataPacket(raw);
  return p;
}

uint32_t Stamp(const LidarPacket& p) {
  Vlp16RawPacket raw;
  EXPECT_TRUE(ParseVlp16DataPacket(p.payload.data(), p.payload.size(), &raw).ok);
  return raw.timestamp_us;
}

std::vector<uint32_t> Ordered(PacketOrderer* orderer, const std::vector<uint32_t>& stamps) {
  std::vector<LidarPacket> out;
  for (uint32_t s : stamps) orderer->Push(Packet(s), &out);
  orderer->Flush(&out);
  std::vector<uint32_t> got;
  for (const auto& p : out) got.push_back(Stamp(p));
  return got;
}

std::vector<uint32_t> Stream(uint32_t start_us, int n) {
  std::vector<uint32_t> s;
  for (int i = 0; i < n; ++i) s.push_back(start_us + static_cast<uint32_t>(i * kPeriodUs));
  return s;
}

TEST(PacketOrderer, ShufflesWithinTheWindowAreUndone) {
  const std::vector<uint32_t> in_order = Stream(1000000, 400);
  std::vector<uint32_t> shuffled = in_order;
  RandomStream rng(7, "test.shuffle");
  for (std::size_t start = 0; start < shuffled.size(); start += 20) {  // blocks of 20 packets (~27 ms)
    const std::size_t end = std::min(shuffled.size(), start + 20);
    for (std::size_t i = end - 1; i > start; --i) std::swap(shuffled[i], shuffled[start + rng.NextU64() % (i - start + 1)]);
  }
  PacketOrderer orderer;
  EXPECT_EQ(Ordered(&orderer, shuffled), in_order);
  EXPECT_GT(orderer.counts().reordered, 50u);
  EXPECT_EQ(orderer.counts().duplicate + orderer.counts().late + orderer.counts().wild, 0u);
}

TEST(PacketOrderer, DuplicatesAndLatePacketsAreDroppedAndCounted) {
  std::vector<uint32_t> in = Stream(2000000, 200);
  std::vector<uint32_t> fed = in;
  fed.insert(fed.begin() + 10, in[9]);     // sent twice, at once
  fed.insert(fed.begin() + 150, in[20]);   // again, long after it was released
  fed.insert(fed.begin() + 170, in[21] + 1);  // a stamp never seen, older than what was released: late
  PacketOrderer orderer;
  EXPECT_EQ(Ordered(&orderer, fed), in);
  EXPECT_EQ(orderer.counts().duplicate, 2u);
  EXPECT_EQ(orderer.counts().late, 1u);
}

TEST(PacketOrderer, ACorruptedStampIsWildButARealJumpIsFollowed) {
  std::vector<uint32_t> in = Stream(3000000, 100);
  std::vector<uint32_t> fed = in;
  fed[50] += 1u << 30;  // one flipped bit: +1073 s
  PacketOrderer orderer;
  std::vector<uint32_t> expected = in;
  expected.erase(expected.begin() + 50);
  EXPECT_EQ(Ordered(&orderer, fed), expected);
  EXPECT_EQ(orderer.counts().wild, 1u);

  // The sensor really jumps 5 s ahead (data missing): the stream follows once 3 packets agree.
  std::vector<uint32_t> jump = Stream(3000000, 50);
  const std::vector<uint32_t> after = Stream(8000000, 50);
  jump.insert(jump.end(), after.begin(), after.end());
  PacketOrderer follows;
  EXPECT_EQ(Ordered(&follows, jump), jump);
  EXPECT_EQ(follows.counts().wild, 0u);

  // The very first packet is the corrupt one: it is dropped, not the stream.
  std::vector<uint32_t> first_bad = Stream(3000000, 50);
  first_bad[0] += 1u << 30;
  PacketOrderer first;
  EXPECT_EQ(Ordered(&first, first_bad), std::vector<uint32_t>(first_bad.begin() + 1, first_bad.end()));
  EXPECT_EQ(first.counts().wild, 1u);
}

TEST(PacketOrderer, TheHourWrapIsNotAJump) {
  std::vector<uint32_t> in;
  for (int i = 0; i < 200; ++i)
    in.push_back(static_cast<uint32_t>((3599900000ull + static_cast<uint64_t>(i * kPeriodUs)) % 3600000000ull));
  std::swap(in[80], in[82]);  // a swap right at the wrap (3599.9 s + 75 periods)
  PacketOrderer orderer;
  std::vector<uint32_t> expected = in;
  std::swap(expected[80], expected[82]);
  EXPECT_EQ(Ordered(&orderer, in), expected);
  EXPECT_EQ(orderer.counts().wild + orderer.counts().late, 0u);
}

TEST(PacketOrderer, PositionPacketsPassStraightThrough) {
  PacketOrderer orderer;
  std::vector<LidarPacket> out;
  LidarPacket position;
  position.udp_port = kVlp16PositionPort;
  position.payload.assign(kVlp16PositionPacketBytes, 0);
  orderer.Push(Packet(5000000), &out);
  orderer.Push(position, &out);
  ASSERT_EQ(out.size(), 1u);  // the data packet is held for the window; the position packet is not
  EXPECT_EQ(out[0].udp_port, kVlp16PositionPort);
}

}  // namespace
}  // namespace rotolidar
