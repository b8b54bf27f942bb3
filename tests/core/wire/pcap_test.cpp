// pcap write -> read round trips, the frame headers a real sensor sends, malformed and foreign frames, raw files.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>

#include <unistd.h>

#include "core/wire/pcap.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar {
namespace {

std::string TempPath(const std::string& name) {
  return ::testing::TempDir() + "/rotolidar_" + name + "_" + std::to_string(::getpid());
}

std::vector<uint8_t> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<LidarPacket> SomePackets() {
  Vlp16PacketEncoder encoder(Vlp16ReturnMode::kStrongest, 0.0);
  std::vector<LidarPacket> packets;
  Vlp16FiringSequence s;
  for (int k = 0; packets.size() < 6; ++k) {
    s.t_s = 3.0000004 + k * kVlp16SequencePeriodS;
    s.azimuth_centideg = static_cast<uint16_t>((k * 20) % 36000);
    for (int l = 0; l < 16; ++l) s.distance_2mm[l] = static_cast<uint16_t>(1000 + 37 * k + l);
    if (auto p = encoder.Add(s)) packets.push_back(*p);
  }
  packets.push_back(EncodeVlp16PositionPacket(3.01, 0.0, 2, "$GPRMC,000000,A*00"));
  return packets;
}

TEST(Pcap, WriteReadRoundTripIsByteIdentical) {
  const std::string path = TempPath("roundtrip.pcap");
  const double epoch = 1700000000.0;
  const std::vector<LidarPacket> packets = SomePackets();
  PcapWriter writer;
  ASSERT_TRUE(writer.Open(path, epoch).ok);
  for (const auto& p : packets) ASSERT_TRUE(writer.Write(p).ok);
  ASSERT_TRUE(writer.Close().ok);

  PcapReader reader;
  ASSERT_TRUE(reader.Open(path, epoch).ok);
  LidarPacket got;
  Status status;
  std::size_t i = 0;
  while (reader.Next(&got, &status)) {
    ASSERT_LT(i, packets.size());
    EXPECT_EQ(got.payload, packets[i].payload) << i;
    EXPECT_EQ(got.udp_port, packets[i].udp_port) << i;
    // Microsecond records: rounding costs <= 0.5 us, the double at 1.7e9 s adds ~2.4e-7 s.
    EXPECT_NEAR(got.t_capture_s, packets[i].t_capture_s, 1e-6) << i;
    ++i;
  }
  EXPECT_TRUE(status.ok) << status.message;
  EXPECT_EQ(i, packets.size());
  EXPECT_EQ(reader.skipped(), 0u);
  std::remove(path.c_str());
}

// The frames look like a real VLP-16's: Wireshark/VeloView see UDP from 192.168.1.201 with a valid IPv4 checksum.
TEST(Pcap, FramesCarryRealSensorHeaders) {
  const std::string path = TempPath("headers.pcap");
  PcapWriter writer;
  ASSERT_TRUE(writer.Open(path).ok);
  const auto packets = SomePackets();
  ASSERT_TRUE(writer.Write(packets.front()).ok);
  ASSERT_TRUE(writer.Write(packets.back()).ok);
  ASSERT_TRUE(writer.Close().ok);
  const std::vector<uint8_t> bytes = ReadFile(path);
  ASSERT_EQ(bytes.size(), 24u + 2 * 16 + 2 * 42 + 1206 + 512);
  std::size_t rec = 24;
  for (uint16_t port : {2368, 8308}) {
    const uint8_t* f = bytes.data() + rec + 16;
    EXPECT_EQ(f[12], 0x08);  // IPv4 ethertype
    EXPECT_EQ(f[13], 0x00);
    const uint8_t* ip = f + 14;
    EXPECT_EQ(ip[0], 0x45);
    EXPECT_EQ(ip[9], 17);
    EXPECT_EQ(Ipv4HeaderChecksum(ip, 20), 0);  // a valid header sums to zero
    EXPECT_EQ(ip[12], 192);
    EXPECT_EQ(ip[15], 201);
    EXPECT_EQ(ip[16] & ip[17] & ip[18] & ip[19], 0xFF);
    EXPECT_EQ((ip[20] << 8) | ip[21], port);
    EXPECT_EQ((ip[22] << 8) | ip[23], port);
    rec += 16 + 42 + (port == 2368 ? 1206 : 512);
  }
  std::remove(path.c_str());
}

// A classic pcap written by hand: VLP frames, foreign traffic and one malformed VLP frame.
void AppendRecord(std::vector<uint8_t>* file, const std::vector<uint8_t>& frame) {
  uint32_t hdr[4] = {1, 0, static_cast<uint32_t>(frame.size()), static_cast<uint32_t>(frame.size())};
  const auto* h = reinterpret_cast<const uint8_t*>(hdr);
  file->insert(file->end(), h, h + 16);
  file->insert(file->end(), frame.begin(), frame.end());
}

std::vector<uint8_t> UdpFrame(uint16_t ethertype, uint8_t protocol, uint16_t port, std::size_t payload) {
  std::vector<uint8_t> f(42 + payload, 0);
  f[12] = ethertype >> 8;
  f[13] = ethertype & 0xFF;
  f[14] = 0x45;
  f[16] = (20 + 8 + payload) >> 8;
  f[17] = (20 + 8 + payload) & 0xFF;
  f[23] = protocol;
  f[36] = port >> 8;
  f[37] = port & 0xFF;
  f[38] = (8 + payload) >> 8;
  f[39] = (8 + payload) & 0xFF;
  return f;
}

TEST(Pcap, ForeignTrafficSkippedMalformedReportedWithRecordAndOffset) {
  const uint32_t global[6] = {0xa1b2c3d4, 0x00040002, 0, 0, 65535, 1};
  std::vector<uint8_t> file(reinterpret_cast<const uint8_t*>(global), reinterpret_cast<const uint8_t*>(global) + 24);
  AppendRecord(&file, UdpFrame(0x0800, 17, 2368, 1206));  // 0: data
  AppendRecord(&file, UdpFrame(0x0806, 0, 0, 28));         // 1: ARP, skipped
  AppendRecord(&file, UdpFrame(0x0800, 17, 53, 40));       // 2: DNS, skipped
  AppendRecord(&file, UdpFrame(0x0800, 6, 2368, 100));     // 3: TCP, skipped
  AppendRecord(&file, UdpFrame(0x0800, 17, 2368, 1000));   // 4: malformed: wrong payload size
  std::vector<uint8_t> truncated = UdpFrame(0x0800, 17, 8308, 512);
  truncated.resize(300);
  AppendRecord(&file, truncated);                           // 5: malformed: IPv4 length > captured bytes
  AppendRecord(&file, UdpFrame(0x0800, 17, 8308, 512));   // 6: position
  const std::string path = TempPath("mixed.pcap");
  {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(file.data()), static_cast<std::streamsize>(file.size()));
  }
  PcapReader reader;
  ASSERT_TRUE(reader.Open(path).ok);
  LidarPacket p;
  Status s;
  ASSERT_TRUE(reader.Next(&p, &s));
  EXPECT_EQ(p.udp_port, 2368);
  EXPECT_EQ(p.payload.size(), 1206u);
  ASSERT_FALSE(reader.Next(&p, &s));
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("record 4"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("frame byte offset 42"), std::string::npos) << s.message;
  ASSERT_FALSE(reader.Next(&p, &s));
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("record 5"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("frame byte offset 16"), std::string::npos) << s.message;
  ASSERT_TRUE(reader.Next(&p, &s)) << s.message;
  EXPECT_EQ(p.udp_port, 8308);
  EXPECT_FALSE(reader.Next(&p, &s));
  EXPECT_TRUE(s.ok);
  EXPECT_EQ(reader.skipped(), 3u);
  EXPECT_EQ(reader.records(), 7u);
  // The census counts every UDP datagram by port and size, malformed VLP-16 ones included (record 5's UDP
  // header says 512 bytes although the capture is cut), and the rest as other frames (ARP, TCP).
  const PcapTraffic& t = reader.traffic();
  EXPECT_EQ(t.records, 7u);
  EXPECT_EQ(t.other_frames, 2u);
  EXPECT_EQ(t.vlp16_data, 1u);
  EXPECT_EQ(t.udp, (std::map<std::pair<uint16_t, std::size_t>, std::size_t>{
                       {{53, 40}, 1}, {{2368, 1000}, 1}, {{2368, 1206}, 1}, {{8308, 512}, 2}}));
  EXPECT_EQ(t.Describe(), "5 UDP packets: port 8308 x 2 (payload 512 B), port 53 x 1 (payload 40 B), port 2368 x 1 "
                          "(payload 1000 B), port 2368 x 1 (payload 1206 B); 2 other frames (not UDP over IPv4)");
  std::remove(path.c_str());
}

// An Ouster-like capture (lidar data on UDP 7502, IMU on 7503) holds no VLP-16 data: the error names the file, what
// was expected, and the ports and payload sizes that were there. A pcap with only its file header says so.
TEST(Pcap, NoVlp16DataNamesThePortsAndSizesSeen) {
  const std::string path = TempPath("ouster.pcap");
  PcapWriter writer;
  ASSERT_TRUE(writer.Open(path).ok);
  for (int i = 0; i < 10; ++i) {
    LidarPacket p;
    p.t_capture_s = 0.01 * i;
    p.udp_port = i == 4 ? 7503 : 7502;
    p.payload.assign(i == 4 ? 48 : 12608, uint8_t(i));
    ASSERT_TRUE(writer.Write(p).ok);
  }
  ASSERT_TRUE(writer.Close().ok);
  PcapReader reader;
  ASSERT_TRUE(reader.Open(path).ok);
  LidarPacket p;
  Status s;
  EXPECT_FALSE(reader.Next(&p, &s));
  EXPECT_TRUE(s.ok);  // foreign traffic is skipped, not malformed
  EXPECT_EQ(reader.traffic().vlp16_data, 0u);
  EXPECT_EQ(reader.NoVlp16DataError().message,
            path + ": no VLP-16 data packets (1206-byte payloads on UDP port 2368): saw 10 UDP packets: port 7502 x 9 "
                   "(payload 12608 B), port 7503 x 1 (payload 48 B)");

  ASSERT_TRUE(writer.Open(path).ok);  // header only
  ASSERT_TRUE(writer.Close().ok);
  ASSERT_TRUE(reader.Open(path).ok);
  EXPECT_FALSE(reader.Next(&p, &s));
  EXPECT_TRUE(s.ok);
  EXPECT_EQ(reader.NoVlp16DataError().message,
            path + ": no VLP-16 data packets (1206-byte payloads on UDP port 2368): saw no packets (the file holds a "
                   "pcap header only)");
  std::remove(path.c_str());
}

TEST(Pcap, RawPayloadFile) {
  const std::string path = TempPath("raw.bin");
  const auto packets = SomePackets();
  {
    std::ofstream out(path, std::ios::binary);
    for (int i = 0; i < 3; ++i) {
      out.write(reinterpret_cast<const char*>(packets[i].payload.data()), 1206);
    }
  }
  std::vector<LidarPacket> got;
  ASSERT_TRUE(ReadRawVlp16Payloads(path, &got).ok);
  ASSERT_EQ(got.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(got[i].payload, packets[i].payload);
  {
    std::ofstream out(path, std::ios::binary | std::ios::app);
    out.write("abc", 3);
  }
  const Status s = ReadRawVlp16Payloads(path, &got);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("byte offset 3618"), std::string::npos) << s.message;
  EXPECT_EQ(got.size(), 3u);  // untouched on failure
  EXPECT_FALSE(ReadRawVlp16Payloads(path + ".missing", &got).ok);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace rotolidar
