// The saved keyframe database (bench/run/keyframe_db.hpp): round trip and damaged files.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "bench/run/keyframe_db.hpp"

namespace rotolidar::bench {
namespace {

std::string TempDir(const std::string& name) {
  const std::string dir = (std::filesystem::temp_directory_path() / ("rotolidar_kfdb_" + name)).string();
  std::filesystem::remove_all(dir);
  return dir;
}

std::vector<graph::KeyframeCloud> Sample() {
  std::vector<graph::KeyframeCloud> out(3);
  for (int i = 0; i < 3; ++i) {
    graph::KeyframeCloud& k = out[i];
    k.id = i;
    k.t_s = 100.0 + 0.123456789 * i;
    k.T_world_odom = RotZ(0.3 * i);
    k.T_world_odom.translation() << i, -2.0 * i, 0.5;
    k.T_world_corrected = k.T_world_odom * RotZ(0.01);
    k.R_level_base = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()).toRotationMatrix();
    if (i != 1)  // keyframe 1 saw nothing within range
      for (int j = 0; j < 50; ++j) k.cloud_base.emplace_back(0.5 * j, 39.0 - j * 0.3, -1.25);
  }
  return out;
}

TEST(KeyframeDatabase, RoundTrip) {
  const std::string dir = TempDir("roundtrip");
  const std::vector<graph::KeyframeCloud> in = Sample();
  ASSERT_TRUE(WriteKeyframeDatabase(dir, in));
  EXPECT_FALSE(std::filesystem::exists(dir + "/kf_000001.pcd"));  // an empty keyframe has no point file
  std::vector<graph::KeyframeCloud> out;
  const Status s = ReadKeyframeDatabase(dir, &out);
  ASSERT_TRUE(s) << s.message;
  ASSERT_EQ(out.size(), in.size());
  for (size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].id, in[i].id);
    EXPECT_NEAR(out[i].t_s, in[i].t_s, 1e-9);  // times are written with 9 decimals
    EXPECT_TRUE(out[i].T_world_odom.isApprox(in[i].T_world_odom, 1e-12));
    EXPECT_TRUE(out[i].T_world_corrected.isApprox(in[i].T_world_corrected, 1e-12));
    EXPECT_TRUE(out[i].R_level_base.isApprox(in[i].R_level_base, 1e-12));
    ASSERT_EQ(out[i].cloud_base.size(), in[i].cloud_base.size());
    for (size_t j = 0; j < in[i].cloud_base.size(); ++j)  // float32 in the PCD: ~4e-6 m at 40 m
      EXPECT_LT((out[i].cloud_base[j] - in[i].cloud_base[j]).norm(), 1e-5);
  }
  std::filesystem::remove_all(dir);
}

TEST(KeyframeDatabase, DamageIsNamed) {
  const std::string dir = TempDir("damage");
  ASSERT_TRUE(WriteKeyframeDatabase(dir, Sample()));
  std::vector<graph::KeyframeCloud> out;
  std::filesystem::remove(dir + "/kf_000002.pcd");  // a lost point file is an error, not an empty keyframe
  Status s = ReadKeyframeDatabase(dir, &out);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message.find("keyframes.csv:4"), std::string::npos) << s.message;
  std::filesystem::remove_all(dir);
  s = ReadKeyframeDatabase(dir, &out);  // no database at all
  EXPECT_FALSE(s);
  EXPECT_NE(s.message.find("keyframes.csv"), std::string::npos) << s.message;
}

}  // namespace
}  // namespace rotolidar::bench
