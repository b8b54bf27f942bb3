#include "sim/sensors/sensor_clock.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "sim/sim_config.hpp"

namespace rotolidar::sim {
namespace {

TEST(SensorClock, DefaultLeavesStampsUntouched) {
  const SensorClock clock;
  for (double t : {0.0, 1e-7, 0.5, 19.999, 3600.25}) EXPECT_EQ(clock.Stamp(t), t);
}

TEST(SensorClock, OffsetMovesStampsByExactlyIt) {
  const SensorClock clock{0.0125, 0.0};
  for (double t : {0.0, 1.0, 17.3, 1000.0}) EXPECT_EQ(clock.Stamp(t), t + 0.0125);
}

// A drift of D ppm gains D microseconds per second of rig time: D * 1e-6 * t at time t (closed form), checked
// at two times so a constant error cannot pass for a drift. Doubles at t <= 1e3 s resolve ~1e-13 s.
TEST(SensorClock, DriftGrowsLinearlyWithTime) {
  const double drift_ppm = 50.0;
  const SensorClock clock{0.0, drift_ppm};
  EXPECT_NEAR(clock.Stamp(10.0) - 10.0, 50e-6 * 10.0, 1e-13);    // 0.5 ms after 10 s
  EXPECT_NEAR(clock.Stamp(600.0) - 600.0, 50e-6 * 600.0, 1e-12);  // 30 ms after 10 min
  const SensorClock both{-0.002, -20.0};
  EXPECT_NEAR(both.Stamp(100.0) - 100.0, -0.002 - 20e-6 * 100.0, 1e-13);
}

TEST(SensorClock, ValidateNamesTheField) {
  std::string why;
  EXPECT_TRUE((SensorClock{1.0, -1000.0}.Validate("clocks.camera", &why)));
  EXPECT_FALSE((SensorClock{1.5, 0.0}.Validate("clocks.camera", &why)));
  EXPECT_NE(why.find("clocks.camera_offset_s"), std::string::npos) << why;
  EXPECT_FALSE((SensorClock{0.0, 1001.0}.Validate("clocks.camera", &why)));
  EXPECT_NE(why.find("clocks.camera_drift_ppm"), std::string::npos) << why;
  EXPECT_FALSE((SensorClock{0.0, std::nan("")}.Validate("clocks.camera", &why)));
  CaptureJitterConfig jitter{0.0, 0.02};
  EXPECT_FALSE(jitter.Validate("clocks.lidar_capture", &why));
  EXPECT_NE(why.find("clocks.lidar_capture_jitter_scale_s"), std::string::npos) << why;
  jitter = {-1e-6, 0.0};
  EXPECT_FALSE(jitter.Validate("clocks.lidar_capture", &why));
  EXPECT_NE(why.find("clocks.lidar_capture_latency_s"), std::string::npos) << why;
}

/// Capture times of `n` packets arriving every `period_s` through a CaptureJitter.
std::vector<double> Captures(const CaptureJitterConfig& config, uint64_t seed, int n, double period_s) {
  CaptureJitter jitter(config, seed);
  std::vector<double> out;
  for (int i = 0; i < n; ++i) out.push_back(jitter.Apply(i * period_s));
  return out;
}

constexpr double kDataPacketPeriodS = 1.0 / 753.5;  // VLP-16 single-return data packet rate (manual)

TEST(CaptureJitter, DisabledIsIdentity) {
  CaptureJitter jitter(CaptureJitterConfig{}, 7);
  for (double t : {0.3, 0.1, 2.0}) EXPECT_EQ(jitter.Apply(t), t);  // not even clamped: nothing changes
}

// Exponential delay of mean s: the sample mean of N delays has standard deviation s / sqrt(N). N = 200000,
// s = 100 us: 0.22 us; the bound is 5 of those (1.1 us). The order clamp could only add delay when one packet's
// draw exceeds the next one's by a whole period (1.33 ms = 13 s): probability exp(-13.3) ~ 2e-6 per packet,
// adding < 1 ms * 2e-6 to the mean: negligible against the bound.
TEST(CaptureJitter, MeanDelayIsLatencyPlusScale) {
  const CaptureJitterConfig config{50e-6, 100e-6};
  const int n = 200000;
  const std::vector<double> t = Captures(config, 1, n, kDataPacketPeriodS);
  double sum = 0.0, min_delay = 1.0;
  for (int i = 0; i < n; ++i) {
    const double delay = t[i] - i * kDataPacketPeriodS;
    sum += delay;
    min_delay = std::min(min_delay, delay);
  }
  EXPECT_NEAR(sum / n, 150e-6, 5 * 100e-6 / std::sqrt(double(n)));
  EXPECT_GE(min_delay, 50e-6 - 1e-12);  // the delay is never below the constant latency
}

// Packets 1 us apart with 1 ms of jitter: without the clamp most neighbours would swap.
TEST(CaptureJitter, NeverReordersPackets) {
  const CaptureJitterConfig config{0.0, 1e-3};
  const std::vector<double> t = Captures(config, 3, 50000, 1e-6);
  for (size_t i = 1; i < t.size(); ++i) ASSERT_GE(t[i], t[i - 1]) << "packet " << i;
  for (size_t i = 0; i < t.size(); ++i) ASSERT_GE(t[i], i * 1e-6) << "captured before it arrived: " << i;
}

TEST(CaptureJitter, SameSeedSameTimesOtherSeedDiffers) {
  const CaptureJitterConfig config{20e-6, 80e-6};
  const std::vector<double> a = Captures(config, 42, 1000, kDataPacketPeriodS);
  EXPECT_EQ(a, Captures(config, 42, 1000, kDataPacketPeriodS));
  EXPECT_NE(a, Captures(config, 43, 1000, kDataPacketPeriodS));
}

/// ParseSimConfig of a YAML text over the defaults; the Status message on failure.
Status ParseClocks(const std::string& text, SimConfig* c) {
  *c = DefaultSimConfig();
  return ParseSimConfig("mem.yaml", YAML::Load(text), c);
}

TEST(ClockConfig, DefaultsAreOffAndValid) {
  const SimConfig c = DefaultSimConfig();
  const ClockTruth t = c.TrueClocks();
  for (const SensorClock& k : {t.lidar, t.imu, t.encoder, t.camera}) {
    EXPECT_EQ(k.offset_s, 0.0);
    EXPECT_EQ(k.drift_ppm, 0.0);
    EXPECT_FALSE(std::signbit(k.offset_s));  // written as 0, not -0
  }
  EXPECT_TRUE(t.lidar_pps_synced);
  EXPECT_FALSE(t.lidar_capture.enabled());
}

// The PPS disciplines the head: its drift applies only when free-running. calib.yaml keeps the nominal offset.
TEST(ClockConfig, PpsSyncGatesTheLidarDrift) {
  SimConfig c;
  Status s = ParseClocks("clocks: {lidar_offset_s: 0.01, lidar_drift_ppm: 25}", &c);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(c.TrueClocks().lidar.drift_ppm, 0.0);
  EXPECT_EQ(c.TrueClocks().lidar.offset_s, -0.01);  // stamp = t - lidar_offset_s
  s = ParseClocks("clocks: {lidar_offset_s: 0.01, lidar_drift_ppm: 25, lidar_pps_synced: false}", &c);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(c.TrueClocks().lidar.drift_ppm, 25.0);
  EXPECT_EQ(c.TrueCalib().lidar_clock_offset_s, 0.01);  // what the owner believes: the offset, no drift
}

TEST(ClockConfig, YamlErrorsNameTheField) {
  SimConfig c;
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"clocks: {lidar_drift_ppm: 2000}", "clocks.lidar_drift_ppm"},
      {"clocks: {encoder_offset_s: -1.5}", "clocks.encoder_offset_s"},
      {"clocks: {camera_drift_ppm: .nan}", "clocks.camera_drift_ppm"},
      {"clocks: {lidar_capture_jitter_scale_s: 0.02}", "clocks.lidar_capture_jitter_scale_s"},
      {"clocks: {lidar_capture_latency_s: -0.001}", "clocks.lidar_capture_latency_s"},
      {"imu: {imu_clock_drift_ppm: -1001}", "imu_clock_drift_ppm"}};
  for (const auto& [text, field] : bad) {
    const Status s = ParseClocks(text, &c);
    EXPECT_FALSE(s.ok) << text;
    EXPECT_NE(s.message.find(field), std::string::npos) << s.message;
  }
}

}  // namespace
}  // namespace rotolidar::sim
