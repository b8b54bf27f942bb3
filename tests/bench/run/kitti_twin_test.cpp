// The KITTI twin: export -> read back with the core's KITTI reader (poses, times, calib bit-exact; bins with their
// per-point times and 64 scan lines), and the motion-compensated variant against the raw one.
#include <cmath>
#include <filesystem>

#include <unistd.h>

#include <gtest/gtest.h>

#include "bench/run/kitti_twin.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rotolidar_kitti_twin_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

/// A car driving straight ahead (cam0 +z) at 10 m/s and turning slowly (0.02 rad a frame about cam0 -y = up),
/// from the origin of urban_loop (the start of KITTI 07's street): `n` poses, 10 Hz.
std::vector<Pose3> StraightDrive(int n) {
  std::vector<Pose3> poses;
  for (int k = 0; k < n; ++k) {
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::AngleAxisd(-0.02 * k, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(0.0, 0.0, 1.0 * k);
    poses.push_back(T);
  }
  return poses;
}

KittiTwinOptions SmallTwin(const std::string& dir, bool compensate) {
  KittiTwinOptions o;
  o.poses_path = dir + "/gt.txt";
  o.scene = "urban_loop";
  o.out_dir = dir + (compensate ? "/compensated" : "/raw");
  o.frames = 3;
  o.seed = 5;
  o.motion_compensate = compensate;
  o.lidar.firings_per_revolution = 360;  // 1 deg: fast, and still every laser's full sweep
  return o;
}

TEST(KittiTwin, ExportReadsBackAsKitti) {
  const std::string dir = TempDir("roundtrip");
  const std::vector<Pose3> gt = StraightDrive(5);
  ASSERT_TRUE(WriteKittiPoses(dir + "/gt.txt", gt));
  const KittiTwinOptions o = SmallTwin(dir, false);
  KittiTwinResult r;
  ASSERT_TRUE(RunKittiTwin(o, &r)) << "twin failed";
  EXPECT_EQ(r.frames, 3u);

  KittiSequence seq;
  const Status opened = OpenKittiSequence({o.out_dir, "", "", ""}, &seq);
  ASSERT_TRUE(opened) << opened.message;
  EXPECT_EQ(seq.frame_ids, (std::vector<int>{0, 1, 2}));
  ASSERT_EQ(seq.poses.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(seq.poses[k].matrix(), gt[k].matrix()) << "frame " << k;  // bit-exact
    EXPECT_EQ(seq.times[k], 0.1 * double(k));
  }
  EXPECT_FALSE(seq.nominal_times);
  EXPECT_EQ(seq.calib.T_cam0_velo.matrix(), KittiTwinCalib().T_cam0_velo.matrix());
  EXPECT_EQ(seq.info.scan_lines, 64);
  EXPECT_EQ(seq.info.range_sigma_m, 0.02);
  ASSERT_EQ(seq.point_time_paths.size(), 3u);
  size_t points = 0;
  for (size_t k = 0; k < 3; ++k) {
    std::vector<KittiPoint> bin;
    std::vector<float> times;
    ASSERT_TRUE(ReadKittiBin(seq.bin_paths[k], &bin));
    ASSERT_TRUE(ReadKittiPointTimes(seq.point_time_paths[k], &times));
    ASSERT_EQ(bin.size(), times.size());
    points += bin.size();
    std::vector<ScanPoint> scan;
    KittiScanStats stats;
    ASSERT_TRUE(KittiScanPoints(bin, times, seq.times[k], KittiScanConfig(), &scan, &stats));
    // Every laser sees something in a street (the top ones the facades): 64 lines, times in one revolution.
    EXPECT_EQ(stats.num_lines, 64u) << "frame " << k;
    for (float t : times) ASSERT_TRUE(t >= 0.f && t < 0.1f);
    for (const KittiPoint& p : bin) ASSERT_TRUE(p.reflectance >= 0.f && p.reflectance <= 1.f);
  }
  EXPECT_EQ(points, r.points);
  fs::remove_all(dir);
}

// The compensated bins are the raw ones moved with the true poses: the first column (time 0) is unchanged, and
// late points move by about the car's travel since the frame time (10 m/s: ~1 m at the revolution's end).
TEST(KittiTwin, MotionCompensationMovesLatePointsByTheTravel) {
  const std::string dir = TempDir("compensate");
  ASSERT_TRUE(WriteKittiPoses(dir + "/gt.txt", StraightDrive(4)));
  KittiTwinResult raw_r, comp_r;
  ASSERT_TRUE(RunKittiTwin(SmallTwin(dir, false), &raw_r));
  ASSERT_TRUE(RunKittiTwin(SmallTwin(dir, true), &comp_r));
  std::vector<KittiPoint> raw, comp;
  std::vector<float> times;
  ASSERT_TRUE(ReadKittiBin(dir + "/raw/velodyne/000001.bin", &raw));
  ASSERT_TRUE(ReadKittiBin(dir + "/compensated/velodyne/000001.bin", &comp));
  ASSERT_TRUE(ReadKittiPointTimes(dir + "/raw/velodyne_times/000001.bin", &times));
  ASSERT_EQ(raw.size(), comp.size());  // same seed, same rays: the same points
  double late_shift = 0.0;
  size_t late = 0;
  for (size_t i = 0; i < raw.size(); ++i) {
    const Eigen::Vector3d d(comp[i].x_m - raw[i].x_m, comp[i].y_m - raw[i].y_m, comp[i].z_m - raw[i].z_m);
    if (times[i] == 0.f) {
      EXPECT_LT(d.norm(), 1e-5);
    }
    if (times[i] > 0.09f) late_shift += d.norm(), ++late;
  }
  ASSERT_GT(late, 0u);
  // 0.09..0.1 s at 10 m/s, plus the 0.02 rad turn over up to ~100 m lever arms: 0.9 .. ~3 m on average
  EXPECT_GT(late_shift / double(late), 0.85);
  EXPECT_LT(late_shift / double(late), 3.0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rotolidar::bench
