// Recording folder: write -> read round trip, and errors that name the file, line and field.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "core/io/calib_yaml.hpp"
#include "core/wire/pcap.hpp"
#include "core/io/recording.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar {
namespace {

namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rotolidar_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir.string();
}

RigCalib TestCalib() {
  RigCalib c;
  c.T_base_motor = MakePose({0.1, 0.2, 0.3}, Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized())));
  c.motor_speed_radps = 2.6;
  c.encoder.counts_per_rev = 16384;
  c.imu.gyro_noise_density = 1.7e-4;
  c.camera.k1 = -0.1;
  return c;
}

/// Writes a small recording: 2 packets, 5 IMU samples, 5 encoder samples, 1 camera frame.
void WriteSmallRecording(const std::string& dir, const RigCalib& calib) {
  RecordingWriter writer;
  ASSERT_TRUE(writer.Open(dir, calib).ok);
  Vlp16PacketEncoder encoder(Vlp16ReturnMode::kStrongest, 0.0);
  for (int k = 0; k < 48; ++k) {
    Vlp16FiringSequence seq;
    seq.t_s = 0.001 + k * kVlp16SequencePeriodS;
    seq.azimuth_centideg = uint16_t((k * 20) % 36000);
    seq.distance_2mm.fill(uint16_t(1000 + k));
    seq.reflectivity.fill(uint8_t(k));
    if (auto packet = encoder.Add(seq)) {
      ASSERT_TRUE(writer.Write(*packet).ok);
    }
  }
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(writer.Write(ImuSample{0.005 * i, {0.1 * i, 0.2, 0.3}, {0.0, 0.0, 9.81 + i}}).ok);
    ASSERT_TRUE(writer.Write(EncoderSample{0.001 * i, uint32_t(100 * i)}).ok);
  }
  CameraFrame frame;
  frame.t_s = 0.01;
  frame.image = cv::Mat(4, 6, CV_8UC3, cv::Scalar(10, 20, 30));
  ASSERT_TRUE(writer.Write(frame).ok);
  ASSERT_TRUE(writer.Close().ok);
}

TEST(Recording, WriteReadRoundTrip) {
  const std::string dir = TempDir("roundtrip");
  const RigCalib calib = TestCalib();
  WriteSmallRecording(dir, calib);
  Recording rec;
  const Status s = LoadRecording(dir, &rec);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_TRUE(rec.calib.T_base_motor.isApprox(calib.T_base_motor, 1e-12));
  EXPECT_EQ(rec.calib.encoder.counts_per_rev, 16384u);
  EXPECT_DOUBLE_EQ(rec.calib.imu.gyro_noise_density, 1.7e-4);
  EXPECT_DOUBLE_EQ(rec.calib.camera.k1, -0.1);
  ASSERT_EQ(rec.lidar_packets.size(), 2u);
  EXPECT_EQ(rec.lidar_packets[0].payload.size(), kVlp16PacketBytes);
  ASSERT_EQ(rec.imu.size(), 5u);
  EXPECT_DOUBLE_EQ(rec.imu[3].accel_mps2.z(), 12.81);
  EXPECT_NEAR(rec.imu[3].t_s, 0.015, 1e-12);
  ASSERT_EQ(rec.encoder.size(), 5u);
  EXPECT_EQ(rec.encoder[4].count, 400u);
  ASSERT_EQ(rec.camera.size(), 1u);
  CameraFrame frame;
  ASSERT_TRUE(LoadCameraFrame(rec.camera[0], &frame).ok);
  EXPECT_EQ(frame.image.at<cv::Vec3b>(2, 3), cv::Vec3b(10, 20, 30));
}

TEST(Recording, EpochMapsPcapTimesToTheRigClock) {
  const std::string dir = TempDir("epoch");
  RigCalib calib = TestCalib();
  calib.epoch_unix_s = 1.7e9;  // a real logger's start time
  WriteSmallRecording(dir, calib);
  Recording rec;
  ASSERT_TRUE(LoadRecording(dir, &rec).ok);
  ASSERT_EQ(rec.lidar_packets.size(), 2u);
  // The first packet's last firing is at 0.001 + 23 * 55.296 us = 2.27 ms; capture adds the 16th laser's offset
  // and the encoder's fixed 0.1 ms transmit latency: in rig time (not Unix seconds), within microseconds.
  EXPECT_GT(rec.lidar_packets[0].t_capture_s, 0.002);
  EXPECT_LT(rec.lidar_packets[0].t_capture_s, 0.003);
}

TEST(Recording, BrokenImuLineIsNamed) {
  const std::string dir = TempDir("broken_imu");
  WriteSmallRecording(dir, TestCalib());
  std::ofstream(dir + "/imu.csv", std::ios::app) << "0.5,1,2,x3,4,5,6\n";
  Recording rec;
  const Status s = LoadRecording(dir, &rec);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("imu.csv:7:"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("gyro_z_radps"), std::string::npos) << s.message;
}

TEST(Recording, NanAndInfinityAreRejectedWithFileLineAndColumn) {
  for (const char* bad : {"nan", "inf", "-INF", "NaN"}) {
    const std::string dir = TempDir(std::string("nan_imu_") + bad);
    WriteSmallRecording(dir, TestCalib());
    std::ofstream(dir + "/imu.csv", std::ios::app) << "0.5,1,2,3,4," << bad << ",6\n";
    Recording rec;
    const Status s = LoadRecording(dir, &rec);
    ASSERT_FALSE(s.ok) << bad;
    EXPECT_NE(s.message.find("imu.csv:7: column 6 ('accel_y_mps2'): not a finite number"), std::string::npos)
        << s.message;
  }
}

TEST(Recording, EncoderCountOutOfRangeIsNamed) {
  const std::string dir = TempDir("broken_encoder");
  WriteSmallRecording(dir, TestCalib());
  std::ofstream(dir + "/encoder.csv", std::ios::app) << "0.5,20000\n";
  Recording rec;
  const Status s = LoadRecording(dir, &rec);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("encoder.csv:7:"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("count"), std::string::npos) << s.message;
}

TEST(Recording, NonIncreasingTimeIsNamed) {
  const std::string dir = TempDir("time_order");
  WriteSmallRecording(dir, TestCalib());
  std::ofstream(dir + "/encoder.csv", std::ios::app) << "0.0001,5\n";
  Recording rec;
  const Status s = LoadRecording(dir, &rec);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("does not increase"), std::string::npos) << s.message;
}

// A lidar.pcap of another sensor (Ouster-like: lidar data on UDP 7502, IMU on 7503) with a position packet that
// looks like a VLP-16's: no data packet, so no points; loading names what the capture holds.
/// Every packet a source gives, copied.
std::vector<LidarPacket> Drain(const Recording& rec, Status* status) {
  LidarPacketSource source;
  *status = source.Open(rec);
  std::vector<LidarPacket> out;
  while (const LidarPacket* p = source.Next()) out.push_back(*p);
  if (status->ok) *status = source.status();
  EXPECT_EQ(source.count(), out.size());
  return out;
}

TEST(Recording, StreamedPacketsAreTheSameAsPacketsInMemory) {
  const std::string dir = TempDir("streamed");
  RigCalib calib = TestCalib();
  calib.epoch_unix_s = 1.7e9;
  WriteSmallRecording(dir, calib);
  Recording in_memory, streamed;
  ASSERT_TRUE(LoadRecording(dir, &in_memory).ok);
  const Status loaded = LoadRecording(dir, PacketLoading::kStreamed, &streamed);
  ASSERT_TRUE(loaded.ok) << loaded.message;
  EXPECT_TRUE(streamed.lidar_packets.empty());  // left on disk
  EXPECT_TRUE(streamed.lidar_packets_streamed);
  EXPECT_EQ(streamed.imu.size(), in_memory.imu.size());
  EXPECT_EQ(streamed.encoder.size(), in_memory.encoder.size());
  Status a, b;
  const std::vector<LidarPacket> from_memory = Drain(in_memory, &a), from_disk = Drain(streamed, &b);
  ASSERT_TRUE(a.ok && b.ok) << a.message << b.message;
  ASSERT_EQ(from_memory.size(), 2u);
  ASSERT_EQ(from_disk.size(), from_memory.size());
  for (size_t i = 0; i < from_disk.size(); ++i) {
    EXPECT_EQ(from_disk[i].t_capture_s, from_memory[i].t_capture_s);  // the same epoch applied
    EXPECT_EQ(from_disk[i].udp_port, from_memory[i].udp_port);
    EXPECT_EQ(from_disk[i].payload, from_memory[i].payload);
  }
}

TEST(Recording, AStreamedMalformedRecordGivesLoadRecordingsError) {
  const std::string dir = TempDir("streamed_bad");
  WriteSmallRecording(dir, TestCalib());
  Recording good;
  ASSERT_TRUE(LoadRecording(dir, &good).ok);
  PcapWriter pcap;  // the two good packets, then a data-port datagram of the wrong size
  ASSERT_TRUE(pcap.Open(dir + "/lidar.pcap").ok);
  for (const LidarPacket& p : good.lidar_packets) ASSERT_TRUE(pcap.Write(p).ok);
  LidarPacket bad;
  bad.t_capture_s = 0.01;
  bad.payload.assign(100, 0);
  ASSERT_TRUE(pcap.Write(bad).ok);
  ASSERT_TRUE(pcap.Close().ok);

  Recording in_memory, streamed;
  const Status whole = LoadRecording(dir, &in_memory);
  ASSERT_FALSE(whole.ok);
  EXPECT_NE(whole.message.find(dir + "/lidar.pcap: record 2: "), std::string::npos) << whole.message;
  ASSERT_TRUE(LoadRecording(dir, PacketLoading::kStreamed, &streamed).ok);  // only opened so far
  Status status;
  EXPECT_EQ(Drain(streamed, &status).size(), 2u);  // what came before the bad record
  EXPECT_FALSE(status.ok);
  EXPECT_EQ(status.message, whole.message);
}

TEST(Recording, StreamingAMissingPcapFailsAtLoad) {
  const std::string dir = TempDir("streamed_missing");
  WriteSmallRecording(dir, TestCalib());
  fs::remove(dir + "/lidar.pcap");
  Recording rec;
  const Status s = LoadRecording(dir, PacketLoading::kStreamed, &rec);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find(dir + "/lidar.pcap"), std::string::npos) << s.message;
}

TEST(Recording, LidarPcapWithoutVlp16DataNamesWhatItHolds) {
  const std::string dir = TempDir("foreign_pcap");
  WriteSmallRecording(dir, TestCalib());
  PcapWriter pcap;
  ASSERT_TRUE(pcap.Open(dir + "/lidar.pcap").ok);
  for (int i = 0; i < 4; ++i) {
    LidarPacket p;
    p.t_capture_s = 0.001 * (i + 1);
    p.udp_port = i == 3 ? 7503 : 7502;
    p.payload.assign(i == 3 ? 48 : 12608, 0);
    ASSERT_TRUE(pcap.Write(p).ok);
  }
  ASSERT_TRUE(pcap.Write(EncodeVlp16PositionPacket(0.005, 0.0, 2, "$GPRMC")).ok);
  ASSERT_TRUE(pcap.Close().ok);
  Recording rec;
  const Status s = LoadRecording(dir, &rec);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find(dir + "/lidar.pcap: no VLP-16 data packets"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("port 7502 x 3 (payload 12608 B), port 7503 x 1 (payload 48 B), port 8308 x 1 (payload "
                           "512 B)"),
            std::string::npos)
      << s.message;
  // Streamed, the same error comes at the end of the packets (the position packet is a packet).
  Recording streamed;
  ASSERT_TRUE(LoadRecording(dir, PacketLoading::kStreamed, &streamed).ok);
  Status status;
  EXPECT_EQ(Drain(streamed, &status).size(), 1u);
  EXPECT_EQ(status.message, s.message);
}

TEST(CalibYaml, UnknownKeyIsAnErrorWithLine) {
  const std::string dir = TempDir("calib_unknown");
  fs::create_directories(dir);
  const std::string path = dir + "/calib.yaml";
  ASSERT_TRUE(SaveCalibYaml(path, TestCalib()).ok);
  std::ofstream(path, std::ios::app) << "motor_sped_radps: 3\n";
  RigCalib calib;
  const Status s = LoadCalibYaml(path, &calib);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("unknown key 'motor_sped_radps'"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("calib.yaml:"), std::string::npos) << s.message;
}

TEST(CalibYaml, WrongTypeNamesFieldAndLine) {
  const std::string dir = TempDir("calib_type");
  fs::create_directories(dir);
  const std::string path = dir + "/calib.yaml";
  std::ofstream(path) << "format_version: 1\nimu:\n  rate_hz: fast\n";
  RigCalib calib;
  const Status s = LoadCalibYaml(path, &calib);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("calib.yaml:3:"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("rate_hz"), std::string::npos) << s.message;
}

TEST(CalibYaml, NanOrInfinityInAnyNumberIsNamed) {
  const std::string dir = TempDir("calib_nan");
  fs::create_directories(dir);
  const std::string path = dir + "/calib.yaml";
  for (const std::string& text : {std::string("format_version: 1\nmotor_speed_radps: .nan\n"),
                                  std::string("format_version: 1\nT_base_imu:\n  translation_m: [0, .inf, 0]\n")}) {
    std::ofstream(path) << text;
    RigCalib calib;
    const Status s = LoadCalibYaml(path, &calib);
    ASSERT_FALSE(s.ok) << text;
    EXPECT_NE(s.message.find("calib.yaml:"), std::string::npos) << s.message;
    EXPECT_NE(s.message.find("not a finite number"), std::string::npos) << s.message;
  }
}

TEST(CalibYaml, ImuTimeOffsetRoundTripsAndIsBounded) {
  const std::string dir = TempDir("calib_imu_offset");
  fs::create_directories(dir);
  const std::string path = dir + "/calib.yaml";
  RigCalib calib = TestCalib();
  calib.imu_time_offset_s = 0.0123456789;
  ASSERT_TRUE(SaveCalibYaml(path, calib).ok);
  RigCalib back;
  ASSERT_TRUE(LoadCalibYaml(path, &back).ok);
  EXPECT_EQ(back.imu_time_offset_s, calib.imu_time_offset_s);  // 17 digits: exact
  std::ofstream(path) << "format_version: 1\nimu_time_offset_s: 2.5\n";
  const Status s = LoadCalibYaml(path, &back);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("imu_time_offset_s"), std::string::npos) << s.message;
}

TEST(CalibYaml, MissingFormatVersionIsAnError) {
  const std::string dir = TempDir("calib_version");
  fs::create_directories(dir);
  std::ofstream(dir + "/calib.yaml") << "motor_speed_radps: 1.0\n";
  RigCalib calib;
  EXPECT_FALSE(LoadCalibYaml(dir + "/calib.yaml", &calib).ok);
}

}  // namespace
}  // namespace rotolidar
