// `slam --kitti` on real KITTI data ($ROTOLIDAR_DATA/kitti00: sequence 00, frames 0-5; skipped when unset).
//  - the bins split into the HDL-64E's 64 scan lines, descending in elevation; the cam0 <-> velodyne conversion
//    reproduces the shipped velodyne-frame ground truth;
//  - the runner's frame-to-frame motion is checked against PCL's GICP between consecutive raw frames (an
//    independent registration) and printed against the shipped ground truth. Known data issue
//    (tests/core/registration/registration_realdata_test.cpp, docs/registration.md): these bins do not move like
//    their ground truth (0.69 m vs 0.86 m for 0->1, found by our registration and by PCL GICP alike), so the
//    ground-truth bound only catches gross failures while the GICP bound carries the precision.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "bench/run/kitti_run.hpp"
#include "core/pipeline/scan_matcher.hpp"
#include "tests/common/test_data.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

const char* DataRoot() { return std::getenv("ROTOLIDAR_DATA"); }

KittiSequencePaths Kitti00Paths() {
  const std::string d = std::string(DataRoot()) + "/kitti00";
  // kitti00 has no times.txt: the sequence's own times come with evo's copy of the KITTI 00 ground truth. The
  // official poses of frames 0-10 (the folder's bins); the 0-5 file is the same truth for fewer frames.
  return {d, d + "/calib_00.txt", std::string(DataRoot()) + "/evo/KITTI_00_gt_times.txt",
          d + "/gt_poses_00_frames_0-10_cam0.txt"};
}

double TranslationError(const Pose3& a, const Pose3& b) { return (a.translation() - b.translation()).norm(); }
double RotationErrorDeg(const Pose3& a, const Pose3& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

class Kitti00Run : public ::testing::Test {
 protected:
  void SetUp() override {
    ROTOLIDAR_REQUIRE_DATA(dir, "kitti00");
  }
};

TEST_F(Kitti00Run, BinsSplitIntoSixtyFourDescendingLinesAndPosesConvert) {
  KittiSequence seq;
  const Status s = OpenKittiSequence(Kitti00Paths(), &seq);
  ASSERT_TRUE(s) << s.message;
  ASSERT_EQ(seq.frame_ids, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
  for (size_t k = 0; k < seq.bin_paths.size(); ++k) {
    std::vector<KittiPoint> bin;
    ASSERT_TRUE(ReadKittiBin(seq.bin_paths[k], &bin));
    std::vector<ScanPoint> points;
    KittiScanStats stats;
    ASSERT_TRUE(KittiScanPoints(bin, seq.times[k], KittiScanConfig(), &points, &stats));
    EXPECT_EQ(stats.num_lines, 64u) << k;
    EXPECT_EQ(stats.elevation_inversions, 0u) << k;
    // Top and bottom lines where KITTI's HDL-64E has them (nominal +2 / -24.8 deg; measured +2.6 / -23.7).
    EXPECT_NEAR(stats.line_median_elevation_deg.front(), 2.6, 0.3) << k;
    EXPECT_NEAR(stats.line_median_elevation_deg.back(), -23.7, 0.3) << k;
  }
  // The shipped velodyne-frame truth was converted as T_velo_k = Tr^-1 * P_k * Tr.
  std::vector<Pose3> velo;
  ASSERT_TRUE(ReadKittiPoses(std::string(DataRoot()) + "/kitti00/gt_velo_poses_00_frames_0-5.txt", &velo));
  ASSERT_EQ(velo.size(), 6u);
  for (size_t k = 0; k < 6; ++k) {
    const Pose3 mine = Cam0ToVeloPose(seq.calib.T_cam0_velo, seq.poses[k]);
    EXPECT_LT(TranslationError(mine, velo[k]), 1e-6) << k;  // the shipped file has 10 significant digits
    EXPECT_LT(RotationErrorDeg(mine, velo[k]), 1e-5) << k;
  }
}

/// PCL GICP (through core's ScanMatcher) from frame k-1 to frame k of the first `frames` raw bins:
/// T_velo(k-1)_velo(k).
std::vector<Pose3> GicpSteps(const KittiSequence& seq, size_t frames) {
  auto cloud = [&](size_t k) {
    std::vector<KittiPoint> bin;
    EXPECT_TRUE(ReadKittiBin(seq.bin_paths[k], &bin));
    std::vector<Eigen::Vector3d> p;
    for (const KittiPoint& q : bin) {
      const Eigen::Vector3d v(q.x_m, q.y_m, q.z_m);
      if (v.allFinite() && v.norm() >= 2.0) p.push_back(v);
    }
    return VoxelDownsample(p, 0.3);
  };
  ScanMatcherConfig config;  // as in the registration realdata test
  config.max_correspondence_m = 1.0;
  config.max_iterations = 100;
  config.transformation_epsilon = 1e-10;
  ScanMatcher gicp(config);
  std::vector<Pose3> steps;
  std::vector<Eigen::Vector3d> previous = cloud(0);
  for (size_t k = 1; k < frames; ++k) {
    std::vector<Eigen::Vector3d> current = cloud(k);
    gicp.SetTarget(previous);
    const Pose3 guess = steps.empty() ? Pose3::Identity() : steps.back();  // constant velocity
    const RegistrationResult r = gicp.Align(current, guess);
    EXPECT_TRUE(r.converged) << "GICP " << k - 1 << "->" << k;
    steps.push_back(r.T_target_source);
    previous = std::move(current);
  }
  return steps;
}

TEST_F(Kitti00Run, RunnerFollowsPclGicpFrameToFrame) {
  KittiRunOptions o;
  o.paths = Kitti00Paths();
  o.max_frames = 6;  // frames 0-5, as measured in docs/kitti.md
  o.out_dir = (fs::temp_directory_path() / "rotolidar_kitti00_run").string();
  fs::remove_all(o.out_dir);
  KittiRunResult r;
  const Status s = RunKitti(o, &r);
  ASSERT_TRUE(s) << s.message;
  ASSERT_EQ(r.frame_ids.size(), 6u);
  EXPECT_EQ(r.frames_other_line_count, 0u);
  EXPECT_EQ(r.expected_lines, 64);  // KITTI has no sequence_info.txt: the first frame's count, the HDL-64E's
  EXPECT_EQ(r.expected_lines_source, "first frame");
  EXPECT_FALSE(r.point_times);
  EXPECT_EQ(r.range_sigma_m, kKittiDefaultRangeSigmaM);  // as KittiEstimatorConfig set it before
  ASSERT_TRUE(r.has_ground_truth);
  for (const char* f : {"trajectory.kitti", "trajectory.tum", "trajectory_velo.tum", "times.txt", "map.ply",
                        "scans.csv", "slam_config.yaml", "metrics.json"})
    EXPECT_TRUE(fs::exists(o.out_dir + "/" + f)) << f;
  std::vector<Pose3> written;
  ASSERT_TRUE(ReadKittiPoses(o.out_dir + "/trajectory.kitti", &written));
  ASSERT_EQ(written.size(), 6u);
  EXPECT_LT((written[0].matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-12);

  KittiSequence seq;
  ASSERT_TRUE(OpenKittiSequence(o.paths, &seq));
  const std::vector<Pose3> gicp = GicpSteps(seq, 6);
  std::vector<Pose3> gt_velo;
  for (int id : r.frame_ids) gt_velo.push_back(Cam0ToVeloPose(seq.calib.T_cam0_velo, seq.poses[size_t(id)]));
  double worst_gicp_m = 0.0, worst_gicp_deg = 0.0, worst_gt_m = 0.0;
  for (size_t k = 1; k < 6; ++k) {
    const Pose3 ours = r.trajectory_velo[k - 1].T_ref_body.inverse() * r.trajectory_velo[k].T_ref_body;
    const Pose3 truth = gt_velo[k - 1].inverse() * gt_velo[k];
    const ScanReport& rep = r.scans[k];
    std::printf("KITTI 00 %zu->%zu: ours %.4f m | vs PCL GICP %.4f m %.4f deg | vs GT %.4f m %.4f deg (GT %.4f m, "
                "GICP %.4f m) | converged %d, edge %d planar %d inliers, %.0f ms\n",
                k - 1, k, ours.translation().norm(), TranslationError(ours, gicp[k - 1]),
                RotationErrorDeg(ours, gicp[k - 1]), TranslationError(ours, truth), RotationErrorDeg(ours, truth),
                truth.translation().norm(), gicp[k - 1].translation().norm(), rep.registration.converged,
                rep.registration.edge_inliers, rep.registration.planar_inliers, rep.timings.total_ms);
    EXPECT_TRUE(rep.registration.converged) << k;
    worst_gicp_m = std::max(worst_gicp_m, TranslationError(ours, gicp[k - 1]));
    worst_gicp_deg = std::max(worst_gicp_deg, RotationErrorDeg(ours, gicp[k - 1]));
    worst_gt_m = std::max(worst_gt_m, TranslationError(ours, truth));
  }
  std::printf("KITTI 00 vs GT: APE (no align) rmse %.4f m max %.4f m, RPE rmse %.4f m / %.4f deg\n", r.ape.stats.rmse,
              r.ape.stats.max, r.rpe_translation.stats.rmse, r.rpe_rotation.stats.rmse);
  // Measured: <= 10.4 mm / 0.049 deg from PCL GICP per frame (our features + scan-to-map against GICP on 0.3 m
  // voxels); 2.5 cm / 0.1 deg keeps ~2x headroom. Against the shipped truth 0.12-0.19 m per frame (the data issue
  // above: it says 0.86 m per frame, both registrations 0.68-0.75 m); 0.25 m still fails on a lost frame (a frame
  // left at constant velocity or unregistered is off by the whole 0.7 m step).
  EXPECT_LT(worst_gicp_m, 0.025);
  EXPECT_LT(worst_gicp_deg, 0.1);
  EXPECT_LT(worst_gt_m, 0.25);
}

}  // namespace
}  // namespace rotolidar::bench
