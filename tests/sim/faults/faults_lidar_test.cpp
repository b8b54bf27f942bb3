// The LiDAR faults on a synthetic packet stream through the FaultyWriter, read back from the pcap: the share of
// packets lost / duplicated / swapped, bursts of consecutive losses, blinded packets that decode to no points,
// what the core's gap counter and packet orderer see, and determinism.
//
// Statistical bounds: every random fault is a sequence of independent Bernoulli draws (one per data packet), so
// the count of hits over N packets is binomial with mean N p and sigma sqrt(N p (1 - p)); the tests allow
// +-5 sigma (a false failure has probability < 1e-6 for any seed: the bound does not depend on the seed chosen).
#include <algorithm>
#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "core/wire/packet_gaps.hpp"
#include "core/wire/packet_orderer.hpp"
#include "tests/sim/faults/fault_test_stream.hpp"

namespace rotolidar::sim {
namespace {

using namespace fault_test;

constexpr size_t kPackets = 20000;  // 26.5 s of a single-return VLP-16

const Inputs& SharedInputs() {
  static const Inputs in = MakeInputs(kPackets, TestCalib().encoder.counts_per_rev);
  return in;
}

void ExpectBinomial(size_t hits, double n, double p, const char* what) {
  const double mean = n * p, sigma = std::sqrt(n * p * (1.0 - p));
  EXPECT_NEAR(double(hits), mean, 5.0 * sigma) << what << ": mean " << mean << ", sigma " << sigma;
}

/// Data packets of the input that are missing from the output between its first and last packet: what a gap
/// counter can see (losses before the first or after the last written packet leave no gap).
size_t MissingBetween(const Inputs& in, const std::vector<LidarPacket>& out) {
  std::set<uint32_t> written;
  for (const LidarPacket& p : out) written.insert(StampOf(p));
  size_t missing = 0;
  for (uint32_t s : in.data_stamps) missing += s > *written.begin() && s < *written.rbegin() && !written.count(s);
  return missing;
}

TEST(LidarFaults, OffWritesTheSameBytes) {
  const Inputs& in = SharedInputs();
  const std::string plain = WriteThrough("off", FaultConfig{}, 1, in);
  // The same stream straight into a RecordingWriter.
  const std::string direct = plain + "_direct";
  std::filesystem::remove_all(direct);
  RecordingWriter out;
  ASSERT_TRUE(out.Open(direct, TestCalib()).ok);
  for (const LidarPacket& p : in.packets) ASSERT_TRUE(out.Write(p).ok);
  for (const ImuSample& s : in.imu) ASSERT_TRUE(out.Write(s).ok);
  for (const EncoderSample& e : in.encoder) ASSERT_TRUE(out.Write(e).ok);
  ASSERT_TRUE(out.Close().ok);
  for (const char* f : {"lidar.pcap", "imu.csv", "encoder.csv", "calib.yaml"})
    EXPECT_EQ(FileBytes(plain + "/" + f), FileBytes(direct + "/" + f)) << f;
}

TEST(LidarFaults, RandomLossDropsItsShareAndTheGapCounterSeesIt) {
  FaultConfig c;
  c.lidar_loss.probability = 0.05;
  FaultTruth truth;
  const Inputs& in = SharedInputs();
  const Recording rec = Load(WriteThrough("loss", c, 1, in, &truth));
  const std::vector<LidarPacket> data = DataPackets(rec);
  ExpectBinomial(truth.lidar.lost_random, kPackets, 0.05, "lost");
  EXPECT_EQ(truth.lidar.lost_burst, 0u);
  EXPECT_EQ(data.size(), kPackets - truth.lidar.lost_random);
  EXPECT_EQ(truth.lidar.data_packets_out, data.size());
  EXPECT_EQ(rec.lidar_packets.size() - data.size(), kPackets / 50);  // position packets all pass
  Vlp16GapCounter gaps;
  for (const LidarPacket& p : data) gaps.Add(StampOf(p), p.payload[1204]);
  EXPECT_EQ(gaps.lost(), MissingBetween(in, data));
  EXPECT_GE(gaps.lost() + 3, truth.lidar.lost_random);  // at most a few lost at the very ends
}

TEST(LidarFaults, BurstsDropConsecutivePackets) {
  FaultConfig c;
  c.lidar_loss.burst_rate_hz = 2.0;
  c.lidar_loss.burst_length_packets = 20;
  FaultTruth truth;
  const Inputs& in = SharedInputs();
  const Recording rec = Load(WriteThrough("bursts", c, 1, in, &truth));
  const std::vector<LidarPacket> data = DataPackets(rec);
  // Bursts are a Poisson process: count ~ Poisson(rate * span), sigma = sqrt(mean); +-5 sigma. Bursts that
  // start inside another merge with it (rate * 20 packets * 1.33 ms = 5 % of them), so the bound is wide enough.
  const double mean = 2.0 * in.data_capture_s.back();
  EXPECT_NEAR(double(truth.lidar.bursts.size()), mean, 5.0 * std::sqrt(mean));
  size_t dropped = 0;
  std::set<uint32_t> written;
  for (const LidarPacket& p : data) written.insert(StampOf(p));
  for (const auto& b : truth.lidar.bursts) {
    EXPECT_GE(b[2], 20.0);  // a whole burst (or more, when one started inside it)
    size_t inside = 0;
    for (size_t i = 0; i < in.data_stamps.size(); ++i)
      if (in.data_capture_s[i] >= b[0] && in.data_capture_s[i] <= b[1]) {
        EXPECT_FALSE(written.count(in.data_stamps[i])) << "burst at " << b[0] << " s let a packet through";
        ++inside;
      }
    EXPECT_EQ(double(inside), b[2]);  // consecutive: every packet between its first and last was dropped
    dropped += inside;
  }
  EXPECT_EQ(dropped, truth.lidar.lost_burst);
  EXPECT_EQ(data.size(), kPackets - truth.lidar.lost_burst);
}

TEST(LidarFaults, DuplicatesAreCountedByThePacketOrderer) {
  FaultConfig c;
  c.lidar_duplicate.probability = 0.02;
  FaultTruth truth;
  const Recording rec = Load(WriteThrough("duplicate", c, 1, SharedInputs(), &truth));
  const std::vector<LidarPacket> data = DataPackets(rec);
  ExpectBinomial(truth.lidar.duplicated, kPackets, 0.02, "duplicated");
  EXPECT_EQ(data.size(), kPackets + truth.lidar.duplicated);
  PacketOrderer orderer;
  std::vector<LidarPacket> released;
  for (const LidarPacket& p : data) orderer.Push(p, &released);
  orderer.Flush(&released);
  EXPECT_EQ(orderer.counts().duplicate, truth.lidar.duplicated);
  EXPECT_EQ(orderer.counts().reordered, 0u);
  EXPECT_EQ(released.size(), kPackets);
}

TEST(LidarFaults, SwapsAreReorderedBackByThePacketOrderer) {
  FaultConfig c;
  c.lidar_reorder.probability = 0.01;
  c.lidar_reorder.max_distance_packets = 8;
  FaultTruth truth;
  const Inputs& in = SharedInputs();
  const Recording rec = Load(WriteThrough("reorder", c, 1, in, &truth));
  const std::vector<LidarPacket> data = DataPackets(rec);
  ASSERT_EQ(data.size(), kPackets);
  // A pending swap holds its next k packets (k uniform in 1..8, mean 4.5), which cannot start one: the expected
  // number is N p / (1 + 4.5 p) = 191; the count is close to binomial over the eligible packets (+-5 sigma).
  const double eligible = kPackets / (1.0 + 4.5 * 0.01);
  ExpectBinomial(truth.lidar.swaps, eligible, 0.01, "swaps");
  // A swap of distance k puts k packets after a newer one: the mean of k over ~190 swaps, +-5 sigma of it
  // (sigma of k = sqrt(63 / 12) = 2.29).
  const double mean_k = double(truth.lidar.arrived_after_newer) / double(truth.lidar.swaps);
  EXPECT_NEAR(mean_k, 4.5, 5.0 * 2.29 / std::sqrt(double(truth.lidar.swaps)));
  // Capture times stay in order; the orderer restores the timestamp order and counts what the truth says.
  for (size_t i = 1; i < rec.lidar_packets.size(); ++i)
    EXPECT_GE(rec.lidar_packets[i].t_capture_s, rec.lidar_packets[i - 1].t_capture_s);
  PacketOrderer orderer;
  std::vector<LidarPacket> released;
  for (const LidarPacket& p : data) orderer.Push(p, &released);
  orderer.Flush(&released);
  EXPECT_EQ(orderer.counts().reordered, truth.lidar.arrived_after_newer);
  EXPECT_EQ(orderer.counts().duplicate + orderer.counts().late + orderer.counts().wild, 0u);
  ASSERT_EQ(released.size(), kPackets);
  for (size_t i = 0; i < kPackets; ++i) EXPECT_EQ(StampOf(released[i]), in.data_stamps[i]) << i;
}

TEST(LidarFaults, BlindPacketsDecodeToNoPoints) {
  FaultConfig c;
  c.lidar_blind = {5.0, 2.0};
  FaultTruth truth;
  const Inputs& in = SharedInputs();
  const Recording rec = Load(WriteThrough("blind", c, 1, in, &truth));
  const std::vector<LidarPacket> data = DataPackets(rec);
  ASSERT_EQ(data.size(), kPackets);
  Vlp16Decoder decoder(rec.calib.lidar, Vlp16DecoderConfig{});
  size_t blind = 0;
  for (size_t i = 0; i < data.size(); ++i) {
    std::vector<LidarPoint> points;
    ASSERT_TRUE(decoder.Decode(data[i], &points).ok);
    const bool inside = in.data_capture_s[i] >= 5.0 && in.data_capture_s[i] < 7.0;
    EXPECT_EQ(points.size(), inside ? 0u : 384u) << "packet " << i << " at " << in.data_capture_s[i] << " s";
    EXPECT_EQ(StampOf(data[i]), in.data_stamps[i]);  // still comes, on time
    blind += inside;
  }
  EXPECT_EQ(truth.lidar.blinded, blind);
  EXPECT_NEAR(double(blind), 2.0 / 1.327104e-3, 1.0);
  EXPECT_GE(truth.lidar.blinded_interval_s[0], 5.0);
  EXPECT_LT(truth.lidar.blinded_interval_s[1], 7.0);
}

FaultConfig Everything() {
  FaultConfig c;
  c.lidar_loss = {0.01, 1.0, 15};
  c.lidar_duplicate.probability = 0.01;
  c.lidar_reorder = {0.01, 8};
  c.lidar_blind = {3.0, 1.0};
  c.encoder_freeze = {4.0, 0.5};
  c.imu_dropout = {6.0, 0.3, 0.01};
  c.imu_saturation = {1.5, 25.0};
  return c;
}

TEST(LidarFaults, SameSeedSameBytesOtherSeedOtherBytes) {
  const Inputs& in = SharedInputs();
  const std::string a = WriteThrough("seed_a", Everything(), 7, in);
  const std::string b = WriteThrough("seed_b", Everything(), 7, in);
  const std::string other = WriteThrough("seed_c", Everything(), 8, in);
  for (const char* f : {"lidar.pcap", "imu.csv", "encoder.csv"})
    EXPECT_EQ(FileBytes(a + "/" + f), FileBytes(b + "/" + f)) << f;
  EXPECT_NE(FileBytes(a + "/lidar.pcap"), FileBytes(other + "/lidar.pcap"));
  EXPECT_NE(FileBytes(a + "/imu.csv"), FileBytes(other + "/imu.csv"));
}

TEST(LidarFaults, EachFaultKeepsItsOwnDraws) {
  // Turning the duplicates on does not change which packets the random loss drops (own stream, one draw per
  // input packet): the lost stamps are the same with and without it.
  const Inputs& in = SharedInputs();
  FaultConfig loss;
  loss.lidar_loss.probability = 0.05;
  FaultConfig both = loss;
  both.lidar_duplicate.probability = 0.3;
  const auto lost = [&](const FaultConfig& c, const char* name) {
    std::set<uint32_t> written, missing;
    for (const LidarPacket& p : DataPackets(Load(WriteThrough(name, c, 3, in)))) written.insert(StampOf(p));
    for (uint32_t s : in.data_stamps)
      if (!written.count(s)) missing.insert(s);
    return missing;
  };
  EXPECT_EQ(lost(loss, "own_a"), lost(both, "own_b"));
}

}  // namespace
}  // namespace rotolidar::sim
