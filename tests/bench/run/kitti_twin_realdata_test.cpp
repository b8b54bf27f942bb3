// The KITTI twin on a real KITTI path (realdata: $ROTOLIDAR_DATA/kitti_poses): the twin's poses are KITTI's
// ground truth bit for bit, and the core's LiDAR-only odometry (`slam --kitti`) tracks the first frames of 07.
#include <cstdio>
#include <filesystem>

#include <unistd.h>

#include <gtest/gtest.h>

#include "bench/run/kitti_run.hpp"
#include "bench/run/kitti_twin.hpp"
#include "tests/common/test_data.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rotolidar_kitti_twin_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

// KITTI 07's first 30 frames (the car starts from standstill and drives ~10 m), motion-compensated like KITTI's
// own bins, through the core LiDAR-only (`slam --kitti`): per-frame RPE against the twin's truth.
TEST(KittiTwinRealdata, CoreTracksTheFirstFramesOf07) {
  ROTOLIDAR_REQUIRE_DATA(poses_dir, "kitti_poses");
  const std::string dir = TempDir("seq07");
  KittiTwinOptions o;
  o.sequence = "07";
  o.poses_path = poses_dir + "/07.txt";
  o.scene = KittiTwinDefaultScene("07");
  o.out_dir = dir + "/07";
  o.frames = 30;
  o.motion_compensate = true;
  KittiTwinResult twin;
  const Status s = RunKittiTwin(o, &twin);
  ASSERT_TRUE(s) << s.message;
  std::vector<Pose3> gt;
  ASSERT_TRUE(ReadKittiPoses(o.poses_path, &gt));
  for (size_t k = 0; k < twin.poses.size(); ++k) EXPECT_EQ(twin.poses[k].matrix(), gt[k].matrix());
  KittiRunOptions run;
  run.paths.dir = o.out_dir;
  run.out_dir = dir + "/slam";
  KittiRunResult r;
  const Status ran = RunKitti(run, &r);
  ASSERT_TRUE(ran) << ran.message;
  ASSERT_TRUE(r.has_ground_truth);
  EXPECT_EQ(r.frames_other_line_count, 0u);
  ASSERT_TRUE(r.rpe_translation.status);
  std::printf("kitti twin 07, 30 frames (%.1f m): RPE %.4f m / %.4f deg RMSE per frame, APE max %.3f m\n",
              twin.path_length_m, r.rpe_translation.stats.rmse, r.rpe_rotation.stats.rmse, r.ape.stats.max);
  // Measured: 0.0038 m and 0.018 deg RMSE per frame (over all 1100 frames 0.0022 m, 0.0063 deg): bounds at
  // ~2.5x, far under what a lost or drifting track gives (the raw, uncompensated bins: 0.009 m, 0.096 deg).
  EXPECT_LT(r.rpe_translation.stats.rmse, 0.01);
  EXPECT_LT(r.rpe_rotation.stats.rmse, 0.05);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rotolidar::bench
