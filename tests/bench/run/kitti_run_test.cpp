// `slam --kitti` on real KITTI data ($ROTOLIDAR_DATA/kitti00: sequence 00, frames 0-10; skipped when absent).
//  - the bins split into the HDL-64E's 64 scan lines, descending in elevation; the cam0 <-> velodyne conversion
//    reproduces the shipped velodyne-frame poses;
//  - the runner's frame-to-frame motion (RPE, delta 1 frame) against two independent stereo SLAM results on the
//    same frames: ORB-SLAM2 (the runner's own --poses evaluation) and S-PTAM (converted to the LiDAR frame here).
//    KITTI's official ground truth is wrong for frames 0 to ~13 of sequence 00 (a constant 0.86 m per frame while
//    the car accelerates from ~0.68 m per frame; docs/kitti.md), so it is printed, not asserted.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "bench/run/kitti_run.hpp"
#include "tests/common/kitti00_reference.hpp"
#include "tests/common/test_data.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

using namespace testdata;  // NOLINT: the kitti00 references and bounds
constexpr size_t kFrames = kKitti00Frames;

/// The runner's inputs; the poses file is ORB-SLAM2's trajectory (cam0 convention, frames 0-10).
KittiSequencePaths Kitti00Paths(const std::string& dir) {
  KittiSequencePaths paths;
  paths.dir = dir;
  paths.calib_path = dir + "/calib_00.txt";
  paths.times_path = dir + "/times_00_frames_0-10.txt";
  paths.poses_path = dir + "/orbslam2_stereo_00_frames_0-10_cam0.txt";
  return paths;
}


class Kitti00Run : public ::testing::Test {
 protected:
  void SetUp() override {
    ROTOLIDAR_REQUIRE_DATA(dir, "kitti00");
    dir_ = dir;
  }
  std::string dir_;
};

TEST_F(Kitti00Run, BinsSplitIntoSixtyFourDescendingLinesAndPosesConvert) {
  KittiSequence seq;
  const Status s = OpenKittiSequence(Kitti00Paths(dir_), &seq);
  ASSERT_TRUE(s) << s.message;
  ASSERT_EQ(seq.frame_ids, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
  ASSERT_FALSE(seq.nominal_times);
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
  // The shipped velodyne-frame copy of the official poses (frames 0-5) was converted as T_velo_k = Tr^-1 P_k Tr.
  std::vector<Pose3> cam0, velo;
  ASSERT_TRUE(ReadKittiPoses(dir_ + "/gt_poses_00_frames_0-5_cam0.txt", &cam0));
  ASSERT_TRUE(ReadKittiPoses(dir_ + "/gt_velo_poses_00_frames_0-5.txt", &velo));
  ASSERT_EQ(cam0.size(), 6u);
  ASSERT_EQ(velo.size(), 6u);
  for (size_t k = 0; k < 6; ++k) {
    const Pose3 mine = Cam0ToVeloPose(seq.calib.T_cam0_velo, cam0[k]);
    EXPECT_LT(TranslationError(mine, velo[k]), 1e-6) << k;  // the shipped file has 10 significant digits
    EXPECT_LT(RotationErrorDeg(mine, velo[k]), 1e-5) << k;
  }
}

/// The runner's files exist and trajectory.kitti starts at the identity.
void ExpectOutputs(const std::string& out_dir) {
  for (const char* f : {"trajectory.kitti", "trajectory.tum", "trajectory_velo.tum", "times.txt", "map.ply",
                        "scans.csv", "slam_config.yaml", "metrics.json"})
    EXPECT_TRUE(fs::exists(out_dir + "/" + f)) << f;
  std::vector<Pose3> written;
  const Status s = ReadKittiPoses(out_dir + "/trajectory.kitti", &written);
  ASSERT_TRUE(s) << s.message;
  ASSERT_EQ(written.size(), kFrames);
  EXPECT_LT((written[0].matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
}

/// LiDAR-frame reference steps of kitti00 (ORB-SLAM2, S-PTAM, official truth).
struct ReferenceSteps {
  std::vector<Pose3> orb, sptam, official;
};

/// Per step: the runner's RPE against ORB-SLAM2 and its error against S-PTAM within kMaxStereoStep*, printed with
/// the official truth's error; the RMS over the steps below the two references' RMS disagreement.
void ExpectStepsMatchStereo(const KittiRunResult& r, const ReferenceSteps& ref) {
  std::vector<double> sptam_m, refs_m;  // per step: ours vs S-PTAM, ORB-SLAM2 vs S-PTAM [m]
  for (size_t k = 0; k + 1 < kFrames; ++k) {
    const Pose3 ours = r.trajectory_velo[k].T_ref_body.inverse() * r.trajectory_velo[k + 1].T_ref_body;
    const ScanReport& rep = r.scans[k + 1];
    std::printf("KITTI 00 %zu->%zu: ours %.4f m | RPE vs ORB-SLAM2 %.2f cm %.3f deg | vs S-PTAM %.2f cm %.3f deg | "
                "vs official %.2f cm %.3f deg | edge %d planar %d inliers, %.0f ms\n",
                k, k + 1, ours.translation().norm(), 100 * r.rpe_translation.errors[k], r.rpe_rotation.errors[k],
                100 * TranslationError(ours, ref.sptam[k]), RotationErrorDeg(ours, ref.sptam[k]),
                100 * TranslationError(ours, ref.official[k]), RotationErrorDeg(ours, ref.official[k]),
                rep.registration.edge_inliers, rep.registration.planar_inliers, rep.timings.total_ms);
    EXPECT_TRUE(rep.registration.converged) << k + 1;
    // Bounds as in core_registration_realdata_test: the two stereo SLAMs disagree by 0.9-3.7 cm (RMS 2.7 cm) and
    // 0.05-0.24 deg per step here, so each step must be within 4.5 cm / 0.3 deg of each (measured: <= 2.5 cm /
    // 0.13 deg RPE against ORB-SLAM2, <= 3.9 cm / 0.27 deg against S-PTAM).
    EXPECT_LT(r.rpe_translation.errors[k], kMaxStereoStepM) << k;
    EXPECT_LT(r.rpe_rotation.errors[k], kMaxStereoStepDeg) << k;
    EXPECT_LT(TranslationError(ours, ref.sptam[k]), kMaxStereoStepM) << k;
    EXPECT_LT(RotationErrorDeg(ours, ref.sptam[k]), kMaxStereoStepDeg) << k;
    sptam_m.push_back(TranslationError(ours, ref.sptam[k]));
    refs_m.push_back(TranslationError(ref.orb[k], ref.sptam[k]));
  }
  std::printf("KITTI 00 vs ORB-SLAM2: RPE (1 frame) rmse %.2f cm max %.2f cm, rmse %.3f deg max %.3f deg; APE (no "
              "align) rmse %.2f cm | vs S-PTAM rmse %.2f cm | ORB vs S-PTAM rmse %.2f cm\n",
              100 * r.rpe_translation.stats.rmse, 100 * r.rpe_translation.stats.max, r.rpe_rotation.stats.rmse,
              r.rpe_rotation.stats.max, 100 * r.ape.stats.rmse, 100 * Rms(sptam_m), 100 * Rms(refs_m));
  // No farther from either reference than they are from each other (measured 1.6 and 2.0 cm vs 2.7 cm RMS).
  EXPECT_LT(r.rpe_translation.stats.rmse, Rms(refs_m));
  EXPECT_LT(Rms(sptam_m), Rms(refs_m));
}

TEST_F(Kitti00Run, RunnerStepsMatchBothStereoSlams) {
  KittiRunOptions o;
  o.paths = Kitti00Paths(dir_);  // --poses = ORB-SLAM2's trajectory
  o.out_dir = (fs::temp_directory_path() / "rotolidar_kitti00_run").string();
  KittiCalib calib;
  const Status c = ReadKittiCalib(o.paths.calib_path, &calib);
  ASSERT_TRUE(c) << c.message;
  ReferenceSteps ref;
  for (const auto& [path, steps] : {std::pair{o.paths.poses_path, &ref.orb},
                                    std::pair{dir_ + "/sptam_stereo_00_frames_0-10_cam0.txt", &ref.sptam},
                                    std::pair{dir_ + "/gt_poses_00_frames_0-10_cam0.txt", &ref.official}}) {
    const Status s = ReadVeloSteps(path, calib.T_cam0_velo, steps);
    ASSERT_TRUE(s) << s.message;
  }
  fs::remove_all(o.out_dir);
  KittiRunResult r;
  const Status s = RunKitti(o, &r);
  ASSERT_TRUE(s) << s.message;
  ASSERT_EQ(r.frame_ids.size(), kFrames);
  EXPECT_EQ(r.frames_other_line_count, 0u);
  EXPECT_EQ(r.expected_lines, 64);  // KITTI has no sequence_info.txt: the first frame's count, the HDL-64E's
  EXPECT_EQ(r.expected_lines_source, "first frame");
  EXPECT_FALSE(r.point_times);
  EXPECT_EQ(r.range_sigma_m, kKittiDefaultRangeSigmaM);
  ExpectOutputs(o.out_dir);
  // The runner's own RPE against its --poses (cam0 convention, delta 1 frame): one error per consecutive pair.
  ASSERT_TRUE(r.has_ground_truth);
  ASSERT_TRUE(r.rpe_translation.status) << r.rpe_translation.status.message;
  ASSERT_TRUE(r.rpe_rotation.status) << r.rpe_rotation.status.message;
  ASSERT_EQ(r.rpe_translation.errors.size(), kFrames - 1);
  ASSERT_EQ(r.rpe_rotation.errors.size(), kFrames - 1);
  ExpectStepsMatchStereo(r, ref);
}

}  // namespace
}  // namespace rotolidar::bench
