#pragma once
// A synthetic rig stream for the fault tests: VLP-16 data packets (every laser at 5 m, 10 Hz head) with a
// position packet after every 50th, a 200 Hz IMU and a 500 Hz encoder, written through a FaultyWriter into a
// recording folder and read back with LoadRecording.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/recording.hpp"
#include "core/wire/vlp16.hpp"
#include "sim/faults/faults.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::sim::fault_test {

struct Inputs {
  std::vector<LidarPacket> packets;  ///< data and position packets in capture order
  std::vector<uint32_t> data_stamps;  ///< timestamp of each data packet, input order
  std::vector<double> data_capture_s;
  std::vector<ImuSample> imu;
  std::vector<EncoderSample> encoder;
};

inline uint32_t StampOf(const LidarPacket& p) {
  const uint8_t* b = p.payload.data() + 1200;
  return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
}

inline bool IsData(const LidarPacket& p) { return p.udp_port == kVlp16DataPort && p.payload.size() == 1206; }

/// `data_packets` data packets (1.327 ms apart) and the IMU and encoder over the same span.
inline Inputs MakeInputs(size_t data_packets, uint32_t counts_per_rev) {
  Inputs in;
  Vlp16PacketEncoder encoder(Vlp16ReturnMode::kStrongest, 0.0);
  for (size_t i = 0; in.data_stamps.size() < data_packets; ++i) {
    Vlp16FiringSequence seq;
    seq.t_s = 0.01 + double(i) * kVlp16SequencePeriodS;
    seq.azimuth_centideg = static_cast<uint16_t>((i * 20) % 36000);  // 10 Hz: 0.2 deg per sequence
    seq.distance_2mm.fill(2500);
    seq.reflectivity.fill(50);
    auto packet = encoder.Add(seq);
    if (!packet) continue;
    in.data_stamps.push_back(StampOf(*packet));
    in.data_capture_s.push_back(packet->t_capture_s);
    in.packets.push_back(*packet);
    if (in.data_stamps.size() % 50 == 0)
      in.packets.push_back(EncodeVlp16PositionPacket(packet->t_capture_s + 1e-5, 0.0, 0, ""));
  }
  const double span_s = in.data_capture_s.back();
  for (int k = 0; k * 0.005 <= span_s; ++k) {
    const double t = k * 0.005;
    in.imu.push_back({t, {2.0 * std::sin(t), 0.5, -0.2}, {0.0, 30.0 * std::cos(t), 9.81}});
  }
  for (int k = 0; k * 0.002 <= span_s; ++k)
    in.encoder.push_back({k * 0.002, static_cast<uint32_t>((k * 7) % counts_per_rev)});
  return in;
}

inline RigCalib TestCalib() { return DefaultSimConfig().TrueCalib(); }

/// Writes `in` through a FaultyWriter into a fresh <tmp>/<name> and returns the folder.
inline std::string WriteThrough(const std::string& name, const FaultConfig& config, uint64_t seed, const Inputs& in,
                                FaultTruth* truth = nullptr) {
  const std::string dir = (std::filesystem::temp_directory_path() / ("rotolidar_faults_" + name)).string();
  std::filesystem::remove_all(dir);
  RecordingWriter out;
  EXPECT_TRUE(out.Open(dir, TestCalib()).ok);
  FaultyWriter writer(config, seed, &out);
  for (const LidarPacket& p : in.packets) EXPECT_TRUE(writer.Write(p).ok);
  for (const ImuSample& s : in.imu) EXPECT_TRUE(writer.Write(s).ok);
  for (const EncoderSample& e : in.encoder) EXPECT_TRUE(writer.Write(e).ok);
  EXPECT_TRUE(writer.Close().ok);
  if (truth) *truth = writer.truth();
  return dir;
}

inline Recording Load(const std::string& dir) {
  Recording rec;
  const Status s = LoadRecording(dir, &rec);
  EXPECT_TRUE(s.ok) << s.message;
  return rec;
}

inline std::vector<LidarPacket> DataPackets(const Recording& rec) {
  std::vector<LidarPacket> data;
  for (const LidarPacket& p : rec.lidar_packets)
    if (IsData(p)) data.push_back(p);
  return data;
}

inline std::string FileBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

}  // namespace rotolidar::sim::fault_test
