// The realism presets: each one validates, ideal is the plain defaults, a config's keys override single sources
// after the preset, the resolved config reads back to the same config, and every preset is deterministic:
// the same seed writes the same bytes, another seed does not.
#include "sim/realism.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <yaml-cpp/yaml.h>

#include "core/io/recording.hpp"
#include "core/wire/vlp16.hpp"
#include "sim/sim_config.hpp"
#include "sim/sim_runner.hpp"

namespace rotolidar::sim {
namespace {

namespace fs = std::filesystem;

std::string Emitted(const SimConfig& c) {
  YAML::Emitter out;
  EmitSimConfig(out, c);
  return out.c_str();
}

const Realism kAll[] = {Realism::kIdeal, Realism::kTypical, Realism::kHarsh};

TEST(Realism, EveryPresetValidates) {
  for (Realism r : kAll) {
    std::string why;
    EXPECT_TRUE(PresetSimConfig(r).Validate(&why)) << why;
    EXPECT_EQ(PresetSimConfig(r).realism, r);
  }
}

TEST(Realism, IdealIsThePlainDefault) {
  EXPECT_EQ(Emitted(PresetSimConfig(Realism::kIdeal)), Emitted(DefaultSimConfig()));
  // And applying ideal over another preset restores it.
  SimConfig c = PresetSimConfig(Realism::kHarsh);
  ApplyRealism(Realism::kIdeal, &c);
  EXPECT_EQ(Emitted(c), Emitted(DefaultSimConfig()));
}

TEST(Realism, PresetsDifferAndGrow) {
  const SimConfig t = PresetSimConfig(Realism::kTypical), h = PresetSimConfig(Realism::kHarsh);
  EXPECT_NE(Emitted(t), Emitted(DefaultSimConfig()));
  EXPECT_GT(t.clocks.camera_offset_s, 0.0);
  EXPECT_GT(h.clocks.camera_offset_s, t.clocks.camera_offset_s);
  EXPECT_GT(h.imu.errors.gyro_scale_sigma, t.imu.errors.gyro_scale_sigma);
  EXPECT_GT(h.lidar.rpm_jitter_frac, t.lidar.rpm_jitter_frac);
  EXPECT_TRUE(t.rig_errors.Enabled());
  EXPECT_FALSE(PresetSimConfig(Realism::kIdeal).rig_errors.Enabled());
  EXPECT_TRUE(t.clocks.lidar_pps_synced);
  EXPECT_FALSE(h.clocks.lidar_pps_synced);
}

TEST(Realism, FileKeysOverrideThePreset) {
  SimConfig c = DefaultSimConfig();
  // Key order in the file does not matter: the preset is applied first.
  const Status s = ParseSimConfig("mem.yaml", YAML::Load("clocks: {camera_offset_s: 0.0125}\nrealism: harsh"), &c);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(c.realism, Realism::kHarsh);
  EXPECT_EQ(c.clocks.camera_offset_s, 0.0125);
  EXPECT_EQ(c.imu.errors.gyro_scale_sigma, PresetSimConfig(Realism::kHarsh).imu.errors.gyro_scale_sigma);
}

TEST(Realism, UnknownWordNamesTheChoices) {
  SimConfig c = DefaultSimConfig();
  const Status s = ParseSimConfig("mem.yaml", YAML::Load("realism: rough"), &c);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("realism"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("typical"), std::string::npos) << s.message;
}

TEST(Realism, ResolvedConfigReadsBackTheSame) {
  for (Realism r : kAll) {
    SimConfig c = PresetSimConfig(r);
    c.clocks.encoder_offset_s = 0.0042;  // a single source set after the preset survives the round trip
    SimConfig back = DefaultSimConfig();
    const Status s = ParseSimConfig("mem.yaml", YAML::Load(Emitted(c)), &back);
    ASSERT_TRUE(s.ok) << s.message;
    // The sections the presets govern (the rig model's quaternions may move in their last bit through text).
    const YAML::Node a = YAML::Load(Emitted(c)), b = YAML::Load(Emitted(back));
    for (const char* key : {"realism", "clocks", "imu", "lidar", "rig_errors"})
      EXPECT_EQ(YAML::Dump(b[key]), YAML::Dump(a[key])) << key;
  }
}

/// Every file of a recording folder, by relative path, with its bytes.
std::map<std::string, std::string> Files(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    files[fs::relative(e.path(), dir).string()] = bytes.str();
  }
  return files;
}

std::map<std::string, std::string> Record(Realism r, uint64_t seed, const std::string& name) {
  SimConfig c = PresetSimConfig(r);
  c.scene = "lab", c.carrier_from_scene = true, c.camera.enabled = false;
  c.duration_s = 1.0, c.seed = seed;
  const fs::path dir = fs::temp_directory_path() / ("rotolidar_realism_" + name);
  fs::remove_all(dir);
  SimSummary summary;
  const Status s = RunSimulation(c, dir.string(), &summary);
  EXPECT_TRUE(s.ok) << s.message;
  return Files(dir);
}

TEST(Realism, SameSeedSameBytesWithEveryPreset) {
  for (Realism r : kAll) {
    const std::string w = EnumWords(static_cast<Realism*>(nullptr))[int(r)].first;
    const auto a = Record(r, 7, w + "_a"), b = Record(r, 7, w + "_b"), c = Record(r, 8, w + "_c");
    ASSERT_FALSE(a.empty());
    EXPECT_EQ(a, b) << w;
    EXPECT_NE(a.at("lidar.pcap"), c.at("lidar.pcap")) << w;
  }
}

// The position packets carry the head's time-sync evidence: typical's PPS-synced head (clock reading UTC at the
// default epoch) reports PPS locked with a $GPRMC fix (status A), harsh's free-running head no PPS and no fix.
TEST(Realism, PpsStatusFollowsTheHeadsClock) {
  for (Realism r : {Realism::kTypical, Realism::kHarsh}) {
    const std::string w = EnumWords(static_cast<Realism*>(nullptr))[int(r)].first;
    Record(r, 3, w + "_pps");
    Recording rec;
    const Status s = LoadRecording((fs::temp_directory_path() / ("rotolidar_realism_" + w + "_pps")).string(), &rec);
    ASSERT_TRUE(s) << s.message;
    size_t positions = 0;
    for (const LidarPacket& p : rec.lidar_packets) {
      if (p.udp_port != 8308) continue;
      Vlp16PositionPacket pos;
      ASSERT_TRUE(ParseVlp16PositionPacket(p.payload.data(), p.payload.size(), &pos));
      ++positions;
      EXPECT_EQ(pos.pps_status, r == Realism::kTypical ? 2 : 0) << w;
      EXPECT_EQ(pos.nmea.substr(0, 17).find(",A,") != std::string::npos, r == Realism::kTypical) << pos.nmea;
    }
    EXPECT_GT(positions, 40u) << w;  // 53.8 Hz over 1 s
  }
}

}  // namespace
}  // namespace rotolidar::sim
