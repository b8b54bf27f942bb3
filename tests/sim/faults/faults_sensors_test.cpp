// The encoder and IMU faults on a synthetic stream through the FaultyWriter (frozen encoder, IMU dropouts and
// saturation, each over exactly its interval), the `faults:` YAML section (round trip, unknown keys, validation
// naming the field), truth/faults.yaml, and the runner end to end (off: no trace of the faults in the outputs).
// Statistical bound as in faults_lidar_test.cpp: a binomial count within +-5 sigma.
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "sim/sim_runner.hpp"
#include "tests/sim/faults/fault_test_stream.hpp"

namespace rotolidar::sim {
namespace {

using namespace fault_test;
namespace fs = std::filesystem;

const Inputs& SharedInputs() {
  static const Inputs in = MakeInputs(6000, TestCalib().encoder.counts_per_rev);  // 8 s
  return in;
}

TEST(SensorFaults, FrozenEncoderRepeatsTheLastCountOverExactlyTheInterval) {
  // Samples every 2 ms at k * 0.002 s: the interval's ends lie half a period from any sample, so exactly
  // samples 1001..1750 are frozen at sample 1000's count.
  FaultConfig c;
  c.encoder_freeze = {2.0005, 1.5};
  FaultTruth truth;
  const Inputs& in = SharedInputs();
  const Recording rec = Load(WriteThrough("encoder", c, 1, in, &truth));
  ASSERT_EQ(rec.encoder.size(), in.encoder.size());  // samples keep coming, on time
  for (size_t i = 0; i < in.encoder.size(); ++i) {
    EXPECT_NEAR(rec.encoder[i].t_s, in.encoder[i].t_s, 1e-9);  // the CSV's precision
    const bool frozen = i >= 1001 && i <= 1750;
    EXPECT_EQ(rec.encoder[i].count, frozen ? in.encoder[1000].count : in.encoder[i].count) << in.encoder[i].t_s;
  }
  EXPECT_EQ(truth.encoder.frozen_samples, 750u);
  EXPECT_EQ(truth.encoder.frozen_count, in.encoder[1000].count);
  EXPECT_EQ(truth.encoder.frozen_interval_s[0], in.encoder[1001].t_s);
  EXPECT_EQ(truth.encoder.frozen_interval_s[1], in.encoder[1750].t_s);
}

TEST(SensorFaults, ImuDropoutRemovesExactlyTheInterval) {
  FaultConfig c;
  c.imu_dropout = {3.0025, 0.5, 0.0};  // samples at k * 5 ms: exactly 601..700 fall inside
  FaultTruth truth;
  const Inputs& in = SharedInputs();
  const Recording rec = Load(WriteThrough("imu_dropout", c, 1, in, &truth));
  ASSERT_EQ(rec.imu.size(), in.imu.size() - 100);
  EXPECT_EQ(truth.imu.dropped_interval, 100u);
  EXPECT_EQ(truth.imu.dropped_interval_s[0], in.imu[601].t_s);
  EXPECT_EQ(truth.imu.dropped_interval_s[1], in.imu[700].t_s);
  for (size_t i = 0; i < rec.imu.size(); ++i) {
    const size_t source = i <= 600 ? i : i + 100;  // the samples after the gap, shifted by the 100 dropped
    EXPECT_NEAR(rec.imu[i].t_s, in.imu[source].t_s, 1e-9) << i;
  }
}

TEST(SensorFaults, ImuRandomDropoutDropsItsShare) {
  FaultConfig c;
  c.imu_dropout.probability = 0.1;
  FaultTruth truth;
  const Inputs& in = SharedInputs();
  const Recording rec = Load(WriteThrough("imu_random", c, 1, in, &truth));
  const double n = double(in.imu.size()), p = 0.1;
  EXPECT_NEAR(double(truth.imu.dropped_random), n * p, 5.0 * std::sqrt(n * p * (1 - p)));
  EXPECT_EQ(rec.imu.size(), in.imu.size() - truth.imu.dropped_random);
}

TEST(SensorFaults, SaturationClipsEachAxis) {
  FaultConfig c;
  c.imu_saturation = {1.5, 25.0};
  FaultTruth truth;
  const Inputs& in = SharedInputs();
  const Recording rec = Load(WriteThrough("saturation", c, 1, in, &truth));
  ASSERT_EQ(rec.imu.size(), in.imu.size());
  size_t clipped = 0;
  for (size_t i = 0; i < in.imu.size(); ++i) {
    const Eigen::Vector3d g = in.imu[i].gyro_radps.cwiseMax(-1.5).cwiseMin(1.5);
    const Eigen::Vector3d a = in.imu[i].accel_mps2.cwiseMax(-25.0).cwiseMin(25.0);
    EXPECT_LT((rec.imu[i].gyro_radps - g).norm(), 1e-9) << in.imu[i].t_s;
    EXPECT_LT((rec.imu[i].accel_mps2 - a).norm(), 1e-9) << in.imu[i].t_s;
    clipped += g != in.imu[i].gyro_radps || a != in.imu[i].accel_mps2;
  }
  EXPECT_GT(clipped, 0u);
  EXPECT_EQ(truth.imu.saturated_samples, clipped);
}

TEST(FaultYaml, RoundTripUnknownKeysAndValidation) {
  SimConfig config = DefaultSimConfig();
  const YAML::Node node = YAML::Load(
      "faults:\n  lidar_loss: {probability: 0.01, burst_rate_hz: 0.5, burst_length_packets: 40}\n"
      "  lidar_reorder: {probability: 0.02}\n  encoder_freeze: {start_s: 3, duration_s: 1}\n"
      "  imu_saturation: {gyro_range_radps: 4.3}\n");
  const Status parsed = ParseSimConfig("t.yaml", node, &config);
  ASSERT_TRUE(parsed.ok) << parsed.message;
  EXPECT_EQ(config.faults.lidar_loss.burst_length_packets, 40);
  EXPECT_EQ(config.faults.lidar_reorder.max_distance_packets, 8);  // the default
  EXPECT_EQ(config.faults.encoder_freeze.duration_s, 1.0);
  // The resolved config writes the section (it is on); the section reads back to the same values.
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  EmitSimConfig(out, config);
  const YAML::Node emitted_config = YAML::Load(out.c_str());
  ASSERT_TRUE(emitted_config["faults"]);
  FaultConfig again;
  const Status reparsed = ParseFaultConfig("again.yaml", emitted_config["faults"], &again);
  ASSERT_TRUE(reparsed.ok) << reparsed.message;
  const auto emitted = [](const FaultConfig& f) {
    YAML::Emitter e;
    e.SetDoublePrecision(17);
    EmitFaultConfig(e, f);
    return std::string(e.c_str());
  };
  EXPECT_EQ(emitted(again), emitted(config.faults));
  EXPECT_EQ(again.lidar_loss.burst_rate_hz, 0.5);
  YAML::Emitter plain;
  EmitSimConfig(plain, DefaultSimConfig());
  EXPECT_EQ(std::string(plain.c_str()).find("faults"), std::string::npos);  // off: not written

  const Status unknown = ParseSimConfig("t.yaml", YAML::Load("faults:\n  lidar_loss: {prob: 0.1}\n"), &config);
  EXPECT_FALSE(unknown.ok);
  EXPECT_NE(unknown.message.find("t.yaml:2"), std::string::npos) << unknown.message;
  EXPECT_NE(unknown.message.find("prob"), std::string::npos) << unknown.message;
  const Status top = ParseSimConfig("t.yaml", YAML::Load("faults: {packet_loss: 0.1}"), &config);
  EXPECT_FALSE(top.ok);
  EXPECT_NE(top.message.find("packet_loss"), std::string::npos) << top.message;
  for (const char* bad : {"faults: {lidar_loss: {probability: 1.0}}", "faults: {lidar_reorder: {max_distance_packets: 0}}",
                          "faults: {imu_dropout: {duration_s: -1}}"}) {
    const Status s = ParseSimConfig("t.yaml", YAML::Load(bad), &config);
    EXPECT_FALSE(s.ok) << bad;
    EXPECT_NE(s.message.find("faults."), std::string::npos) << s.message;
  }
  std::string why;
  SimConfig invalid = DefaultSimConfig();
  invalid.faults.imu_saturation.accel_range_mps2 = std::nan("");
  EXPECT_FALSE(invalid.Validate(&why));
  EXPECT_NE(why.find("faults.imu_saturation.accel_range_mps2"), std::string::npos) << why;
}

TEST(FaultYaml, TruthFileReadsBack) {
  FaultTruth truth;
  truth.config.lidar_loss.burst_rate_hz = 0.5;
  truth.lidar.lost_burst = 40;
  truth.lidar.bursts = {{1.25, 1.3, 40.0}};
  truth.encoder.frozen_count = 1234;
  truth.imu.dropped_interval_s = {3.0, 3.495};
  const fs::path dir = fs::temp_directory_path() / "rotolidar_faults_truth";
  fs::remove_all(dir);
  fs::create_directories(dir / "truth");
  ASSERT_TRUE(WriteFaultTruth(dir.string(), truth).ok);
  FaultTruth back;
  const Status s = ReadFaultTruth(dir.string(), &back);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(back.lidar.lost_burst, 40u);
  ASSERT_EQ(back.lidar.bursts.size(), 1u);
  EXPECT_EQ(back.lidar.bursts[0][1], 1.3);
  EXPECT_EQ(back.encoder.frozen_count, 1234u);
  EXPECT_EQ(back.imu.dropped_interval_s[1], 3.495);
  EXPECT_EQ(back.config.lidar_loss.burst_rate_hz, 0.5);
}

// Through the runner: faults on write truth/faults.yaml and the section in sim_config.yaml, and leave the truth
// channel as it was; off, neither appears.
TEST(FaultRunner, WritesFaultTruthAndLeavesTheTruthChannelAlone) {
  SimConfig config = DefaultSimConfig();
  config.duration_s = 1.0;
  config.camera.enabled = false;
  config.seed = 5;
  const fs::path root = fs::temp_directory_path() / "rotolidar_faults_runner";
  fs::remove_all(root);
  SimSummary summary;
  ASSERT_TRUE(RunSimulation(config, (root / "off").string(), &summary).ok);
  SimConfig on = config;
  on.faults.lidar_loss.probability = 0.1;
  on.faults.imu_dropout = {0.4025, 0.2, 0.0};  // half a period from any IMU sample
  ASSERT_TRUE(RunSimulation(on, (root / "on").string(), &summary).ok);
  EXPECT_FALSE(fs::exists(root / "off/truth/faults.yaml"));
  EXPECT_EQ(FileBytes((root / "off/sim_config.yaml").string()).find("faults"), std::string::npos);
  EXPECT_NE(FileBytes((root / "on/sim_config.yaml").string()).find("faults"), std::string::npos);
  FaultTruth truth;
  ASSERT_TRUE(ReadFaultTruth((root / "on").string(), &truth).ok);
  EXPECT_GT(truth.lidar.lost_random, 0u);
  EXPECT_EQ(truth.imu.dropped_interval, 40u);  // 0.2 s at 200 Hz
  // The summary counts what reached the recording, not what the sim generated.
  EXPECT_EQ(truth.lidar.data_packets_out, summary.lidar_packets);
  EXPECT_EQ(truth.lidar.data_packets_in - truth.lidar.lost_random, summary.lidar_packets);
  EXPECT_EQ(truth.imu.samples_in - truth.imu.dropped_interval - truth.imu.dropped_random, summary.imu_samples);
  for (const char* f : {"truth/base.tum", "truth/lidar.tum", "truth/rotor.csv", "truth/imu_bias.csv", "calib.yaml"})
    EXPECT_EQ(FileBytes((root / "off" / f).string()), FileBytes((root / "on" / f).string())) << f;
  EXPECT_NE(FileBytes((root / "off/lidar.pcap").string()), FileBytes((root / "on/lidar.pcap").string()));
}

}  // namespace
}  // namespace rotolidar::sim
