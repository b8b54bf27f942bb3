#include "sim/truth/truth.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "sim/rig/base_motion.hpp"
#include "sim/truth/clock_truth.hpp"

namespace rotolidar::sim {
namespace {

namespace fs = std::filesystem;

class TruthTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("rotolidar_truth_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TruthLog MakeLog() {
  const ScriptedBaseMotion motion{ScriptedBaseMotionConfig{}};
  TruthLog log;
  log.base = SampleTrajectory(motion, 0.0, 2.0, 0.01);
  const Pose3 T_base_lidar = MakePose(Eigen::Vector3d(0.0, 0.0, 0.15), Eigen::Quaterniond::Identity());
  for (const StampedPose& p : log.base) {
    log.lidar.push_back({p.t_s, p.T_ref_body * T_base_lidar * RotZ(2.6 * p.t_s)});
    log.rotor.push_back({p.t_s, 2.6 * p.t_s + 1.0 / 3.0});
    log.imu_bias.push_back({p.t_s, Eigen::Vector3d(1e-3, -2e-4, 3.3e-5) * p.t_s,
                            Eigen::Vector3d(0.02, -0.01, 1.0 / 7.0)});
  }
  return log;
}

void ExpectSameTrajectory(const Trajectory& a, const Trajectory& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_s, b[i].t_s);  // shortest round-trip form: bit-exact
    EXPECT_EQ(a[i].T_ref_body.translation(), b[i].T_ref_body.translation());
    // Rotation -> quaternion -> rotation loses a few ulps only.
    EXPECT_LT((a[i].T_ref_body.linear() - b[i].T_ref_body.linear()).cwiseAbs().maxCoeff(), 1e-15 * 8);
  }
}

TEST_F(TruthTest, RoundTripsAllFourFiles) {
  const TruthLog log = MakeLog();
  const Status w = WriteTruth(dir_.string(), log);
  ASSERT_TRUE(w.ok) << w.message;
  for (const char* name : {"base.tum", "lidar.tum", "rotor.csv", "imu_bias.csv"})
    EXPECT_TRUE(fs::exists(dir_ / "truth" / name)) << name;
  TruthLog back;
  const Status r = ReadTruth(dir_.string(), &back);
  ASSERT_TRUE(r.ok) << r.message;
  ExpectSameTrajectory(log.base, back.base);
  ExpectSameTrajectory(log.lidar, back.lidar);
  ASSERT_EQ(back.rotor.size(), log.rotor.size());
  ASSERT_EQ(back.imu_bias.size(), log.imu_bias.size());
  for (size_t i = 0; i < log.rotor.size(); ++i) {
    EXPECT_EQ(back.rotor[i].t_s, log.rotor[i].t_s);
    EXPECT_EQ(back.rotor[i].theta_rad, log.rotor[i].theta_rad);
    EXPECT_EQ(back.imu_bias[i].gyro_bias_radps, log.imu_bias[i].gyro_bias_radps);
    EXPECT_EQ(back.imu_bias[i].accel_bias_mps2, log.imu_bias[i].accel_bias_mps2);
  }
}

// An independent, minimal TUM parser (what evo or a script would do): 8 numbers per non-comment line.
TEST_F(TruthTest, BaseTumReadsWithASimpleParser) {
  const TruthLog log = MakeLog();
  ASSERT_TRUE(WriteTruth(dir_.string(), log).ok);
  std::ifstream in(dir_ / "truth" / "base.tum");
  std::string line;
  size_t i = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    double t, x, y, z, qx, qy, qz, qw;
    ASSERT_TRUE(static_cast<bool>(ss >> t >> x >> y >> z >> qx >> qy >> qz >> qw)) << line;
    ASSERT_LT(i, log.base.size());
    const Pose3& T = log.base[i].T_ref_body;
    EXPECT_EQ(t, log.base[i].t_s);
    EXPECT_EQ(Eigen::Vector3d(x, y, z), T.translation());
    const Eigen::Quaterniond q(qw, qx, qy, qz);
    EXPECT_NEAR(q.norm(), 1.0, 1e-15);
    EXPECT_LT(Eigen::Quaterniond(T.linear()).angularDistance(q), 1e-7);  // acos near 1: ~sqrt(eps)
    ++i;
  }
  EXPECT_EQ(i, log.base.size());
}

TEST_F(TruthTest, ErrorsNameTheFile) {
  // A regular file where the recording directory should be: creating truth/ must fail, naming the path.
  fs::create_directories(dir_);
  const fs::path blocker = dir_ / "not_a_dir";
  std::ofstream(blocker) << "x";
  TruthWriter w;
  const Status s = w.Open(blocker.string());
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("not_a_dir"), std::string::npos) << s.message;
  EXPECT_FALSE(w.WriteBase(StampedPose{}).ok);
  EXPECT_FALSE(w.Close().ok);

  TruthLog out;
  const Status missing = ReadTruth((dir_ / "nowhere").string(), &out);
  EXPECT_FALSE(missing.ok);
  EXPECT_NE(missing.message.find("base.tum"), std::string::npos) << missing.message;
}

TEST_F(TruthTest, MalformedLinesReportFileLineAndField) {
  ASSERT_TRUE(WriteTruth(dir_.string(), MakeLog()).ok);
  const fs::path rotor = dir_ / "truth" / "rotor.csv";
  { std::ofstream(rotor, std::ios::app) << "1.5,abc\n"; }
  TruthLog out;
  Status s = ReadTruth(dir_.string(), &out);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("rotor.csv:203"), std::string::npos) << s.message;  // header + 201 rows + bad
  EXPECT_NE(s.message.find("theta_rad"), std::string::npos) << s.message;

  const fs::path tum = dir_ / "bad.tum";
  { std::ofstream(tum) << "# comment\n0 1 2 3 0 0 0 1\n1 2 3\n"; }
  Trajectory traj;
  s = ReadTum(tum.string(), &traj);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("bad.tum:3"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("8 fields"), std::string::npos) << s.message;
}

// truth/clocks.yaml reads back every clock bit for bit (17 significant digits).
TEST_F(TruthTest, ClockTruthRoundTrips) {
  fs::create_directories(dir_ / "truth");
  ClockTruth c;
  c.lidar = {-0.1234567890123, 17.25};
  c.lidar_pps_synced = false;
  c.imu = {0.0035, -3.3};
  c.encoder = {1e-4, 0.0};
  c.camera = {-0.02, 99.9};
  c.lidar_capture = {2e-5, 1.5e-4};
  ASSERT_TRUE(WriteClockTruth(dir_.string(), c).ok);
  ClockTruth back;
  const Status s = ReadClockTruth(dir_.string(), &back);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(back.lidar.offset_s, c.lidar.offset_s);
  EXPECT_EQ(back.lidar.drift_ppm, c.lidar.drift_ppm);
  EXPECT_FALSE(back.lidar_pps_synced);
  EXPECT_EQ(back.imu.drift_ppm, c.imu.drift_ppm);
  EXPECT_EQ(back.encoder.offset_s, c.encoder.offset_s);
  EXPECT_EQ(back.camera.drift_ppm, c.camera.drift_ppm);
  EXPECT_EQ(back.lidar_capture.latency_s, c.lidar_capture.latency_s);
  EXPECT_EQ(back.lidar_capture.jitter_scale_s, c.lidar_capture.jitter_scale_s);
  EXPECT_FALSE(ReadClockTruth((dir_ / "missing").string(), &back).ok);
}

// truth/dynamic_hits.csv: every field back bit for bit (shortest round-trip form), the object index exact.
TEST_F(TruthTest, DynamicHitsRoundTrip) {
  TruthLog log = MakeLog();
  for (int i = 0; i < 50; ++i)
    log.dynamic_hits.push_back({0.1 + i / 7.0, i % 3, Eigen::Vector3d(1.0 / 3.0 + i, -2.5e-3 * i, 0.1 * i + 1e-9)});
  ASSERT_TRUE(WriteTruth(dir_.string(), log).ok);
  TruthLog back;
  const Status r = ReadTruth(dir_.string(), &back);
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_EQ(back.dynamic_hits.size(), log.dynamic_hits.size());
  for (size_t i = 0; i < log.dynamic_hits.size(); ++i) {
    EXPECT_EQ(back.dynamic_hits[i].t_s, log.dynamic_hits[i].t_s);
    EXPECT_EQ(back.dynamic_hits[i].object_id, log.dynamic_hits[i].object_id);
    EXPECT_EQ(back.dynamic_hits[i].p_world, log.dynamic_hits[i].p_world);
  }
  std::vector<DynamicHitSample> alone;
  ASSERT_TRUE(ReadDynamicHits(dir_.string(), &alone).ok);
  EXPECT_EQ(alone.size(), log.dynamic_hits.size());
}

// No hits: the file is there with its header only; a recording without the file (older) reads as no hits.
TEST_F(TruthTest, DynamicHitsHeaderOnlyAndMissingFileReadAsEmpty) {
  ASSERT_TRUE(WriteTruth(dir_.string(), MakeLog()).ok);
  const fs::path path = dir_ / "truth" / "dynamic_hits.csv";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "t_s,object_id,x_m,y_m,z_m\n");
  TruthLog back;
  ASSERT_TRUE(ReadTruth(dir_.string(), &back).ok);
  EXPECT_TRUE(back.dynamic_hits.empty());
  fs::remove(path);
  back.dynamic_hits.push_back({});
  const Status r = ReadTruth(dir_.string(), &back);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_TRUE(back.dynamic_hits.empty());
}

TEST_F(TruthTest, DynamicHitsBadLinesNameFileLineAndField) {
  TruthLog log = MakeLog();
  log.dynamic_hits = {{0.5, 0, Eigen::Vector3d(1, 2, 3)}, {0.6, 1, Eigen::Vector3d(4, 5, 6)}};
  const fs::path path = dir_ / "truth" / "dynamic_hits.csv";
  const std::pair<const char*, const char*> cases[] = {
      {"0.7,0,1,2,x\n", "z_m"}, {"0.7,1.5,1,2,3\n", "object_id"}, {"0.7,-1,1,2,3\n", "object_id"},
      {"0.7,0,1,2\n", "5 fields"}};
  for (const auto& [bad_line, field] : cases) {
    ASSERT_TRUE(WriteTruth(dir_.string(), log).ok);
    { std::ofstream(path, std::ios::app) << bad_line; }
    TruthLog out;
    const Status s = ReadTruth(dir_.string(), &out);
    ASSERT_FALSE(s.ok) << bad_line;
    EXPECT_NE(s.message.find("dynamic_hits.csv:4"), std::string::npos) << s.message;  // header + 2 rows + bad
    EXPECT_NE(s.message.find(field), std::string::npos) << s.message;
  }
}

}  // namespace
}  // namespace rotolidar::sim
