// The IMU of a KITTI sequence folder: calib_imu_to_velo.txt (KITTI raw's format) read and written bit-exactly,
// strict errors naming file, line and key, and OpenKittiSequence picking up imu.csv only with its calibration.
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/io/kitti.hpp"
#include "core/io/recording.hpp"

namespace rotolidar {
namespace {

namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  const std::string dir = testing::TempDir() + "/rotolidar_kitti_imu_" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

/// KITTI raw's file for 2011_10_03 as shipped (7-digit exponent notation).
constexpr const char* kKittiImuToVelo =
    "calib_time: 25-May-2012 16:47:16\n"
    "R: 9.999976e-01 7.553071e-04 -2.035826e-03 -7.854027e-04 9.998898e-01 -1.482298e-02 2.024406e-03 "
    "1.482454e-02 9.998881e-01\n"
    "T: -8.086759e-01 3.195559e-01 -7.997231e-01\n";

TEST(KittiImuIo, KittiRawFileReadsAndRoundTripsBitExactly) {
  const std::string dir = TempDir("roundtrip");
  WriteText(dir + "/calib_imu_to_velo.txt", kKittiImuToVelo);
  KittiImuCalib c;
  const Status s = ReadKittiImuCalib(dir + "/calib_imu_to_velo.txt", &c);
  ASSERT_TRUE(s) << s.message;
  EXPECT_EQ(c.calib_time, "25-May-2012 16:47:16");
  EXPECT_EQ(c.T_velo_imu.linear()(1, 2), -1.482298e-02);  // row-major R
  EXPECT_EQ(c.T_velo_imu.translation(), Eigen::Vector3d(-8.086759e-01, 3.195559e-01, -7.997231e-01));
  // p_velo = R p_imu + T: the IMU's origin lies at T in the Velodyne frame.
  EXPECT_EQ(c.T_velo_imu * Eigen::Vector3d::Zero(), c.T_velo_imu.translation());
  ASSERT_TRUE(WriteKittiImuCalib(dir + "/again.txt", c));
  KittiImuCalib back;
  ASSERT_TRUE(ReadKittiImuCalib(dir + "/again.txt", &back));
  EXPECT_EQ(back.calib_time, c.calib_time);
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k)
      EXPECT_TRUE(SameBits(back.T_velo_imu.matrix()(r, k), c.T_velo_imu.matrix()(r, k))) << r << "," << k;
}

TEST(KittiImuIo, MalformedFilesNameLineAndKey) {
  const std::string dir = TempDir("bad");
  const std::string path = dir + "/calib_imu_to_velo.txt";
  const auto error_of = [&](const std::string& text) {
    WriteText(path, text);
    KittiImuCalib c;
    c.calib_time = "untouched";
    const Status s = ReadKittiImuCalib(path, &c);
    EXPECT_FALSE(s);
    EXPECT_EQ(c.calib_time, "untouched");  // the output is left alone on failure
    return s.message;
  };
  EXPECT_NE(error_of("R: 1 0 0 0 1 0 0 0 1\n").find(path + ": key 'T' missing"), std::string::npos);
  EXPECT_NE(error_of("T: 1 2 3\n").find("key 'R' missing"), std::string::npos);
  EXPECT_NE(error_of("R: 1 0 0 0 1 0 0 0 1\nT: 1 2\n").find(path + ":2:"), std::string::npos);
  EXPECT_NE(error_of("R: 1 0 0 0 1 0 0 0 1\nT: 1 2 x\n").find(path + ":2:"), std::string::npos);
  EXPECT_NE(error_of("R: 2 0 0 0 1 0 0 0 1\nT: 1 2 3\n").find(path + ":1:"), std::string::npos);  // not a rotation
  EXPECT_NE(error_of("R: 1 0 0 0 1 0 0 0 1\nR: 1 0 0 0 1 0 0 0 1\n").find("given twice"), std::string::npos);
  EXPECT_NE(error_of("Q: 1\n").find("unknown key 'Q:'"), std::string::npos);
}

TEST(KittiImuIo, SequenceReadsImuOnlyWithItsCalibration) {
  KittiDatasetLayout layout;
  layout.root = TempDir("dataset");
  ASSERT_TRUE(CreateKittiDatasetFolders(layout, false));
  ASSERT_TRUE(WriteKittiBin(layout.BinPath(0), {KittiPoint{1.f, 2.f, 3.f, 0.5f}}));
  ASSERT_TRUE(WriteKittiCalib(layout.CalibPath(), KittiCalib()));
  KittiSequencePaths paths;
  paths.dir = layout.SequenceDir();
  KittiSequence seq;
  ASSERT_TRUE(OpenKittiSequence(paths, &seq));
  EXPECT_TRUE(seq.imu.empty());  // no imu.csv: no IMU, and no error
  EXPECT_TRUE(seq.imu_path.empty());

  const std::vector<ImuSample> samples = {{0.0, {0.1, 0.2, 0.3}, {0.0, 0.0, 9.81}},
                                          {0.005, {0.1, 0.2, 0.3}, {0.0, 0.1, 9.8}}};
  ASSERT_TRUE(SaveImuCsv(paths.dir + "/imu.csv", samples));
  Status s = OpenKittiSequence(paths, &seq);
  EXPECT_NE(s.message.find("calib_imu_to_velo.txt: no such file"), std::string::npos) << s.message;
  WriteText(paths.dir + "/calib_imu_to_velo.txt", kKittiImuToVelo);
  s = OpenKittiSequence(paths, &seq);
  ASSERT_TRUE(s) << s.message;
  ASSERT_EQ(seq.imu.size(), 2u);
  EXPECT_EQ(seq.imu[1].t_s, 0.005);
  EXPECT_EQ(seq.imu[1].accel_mps2, samples[1].accel_mps2);
  EXPECT_EQ(seq.imu_path, paths.dir + "/imu.csv");
  EXPECT_NEAR(seq.imu_calib.T_velo_imu.translation().x(), -0.8086759, 1e-12);
}

}  // namespace
}  // namespace rotolidar
