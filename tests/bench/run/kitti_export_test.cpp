// Export round trip: simulate 2 s in the "lab" scene (camera off), export the recording as a KITTI sequence, read
// it back with the core's KITTI reader: one frame per complete VLP-16 revolution, increasing times, poses = the
// truth, calib = the rig's camera, per-point times, sequence_info.txt stating the deskew. The truth-deskewed bins
// are then compared point by point with the estimator-deskewed export of the same recording (same revolutions,
// same points): two independent deskews of one cloud. Finally `slam --kitti` (RunKitti) reads the default
// (estimator-deskewed) export back: 16 lines per frame, no warning, a trajectory close to the export's poses.
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include <unistd.h>

#include <gtest/gtest.h>

#include "bench/eval/trajectory_lookup.hpp"
#include "bench/run/kitti_export.hpp"
#include "bench/run/kitti_run.hpp"
#include "core/io/recording.hpp"
#include "sim/sim_runner.hpp"
#include "sim/truth/truth.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

class KittiExport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs each test in its own process, possibly two at once (-j2).
    dir_ = new std::string((fs::temp_directory_path() / ("rotolidar_kitti_export_" + std::to_string(getpid()))).string());
    fs::remove_all(*dir_);
    sim::SimConfig config = sim::DefaultSimConfig();
    config.scene = "lab";
    config.carrier_from_scene = true;  // the lab's own walk (the default scripted loop leaves the lab)
    config.duration_s = 4.0;           // it rests 2 s at its first waypoint, then walks ~2 m
    config.camera.enabled = false;     // the export needs only the camera's calibration (same numbers, 6x faster)
    sim::SimSummary summary;
    sim_status_ = new Status(sim::RunSimulation(config, *dir_ + "/recording", &summary));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete sim_status_;
  }
  void SetUp() override { ASSERT_TRUE(sim_status_->ok) << sim_status_->message; }

  /// Complete head revolutions in the recording, counted here from the decoded azimuths: a wrap is a drop of more
  /// than 180 deg; complete revolutions lie between consecutive wraps.
  static size_t CompleteRevolutions(const std::string& recording) {
    Recording rec;
    EXPECT_TRUE(LoadRecording(recording, &rec));
    Vlp16DecoderConfig dc;
    dc.min_range_m = rec.calib.lidar.min_range_m;
    dc.max_range_m = rec.calib.lidar.max_range_m;
    dc.lidar_clock_offset_s = rec.calib.lidar_clock_offset_s;
    Vlp16Decoder decoder(rec.calib.lidar, dc);
    std::vector<LidarPoint> points;
    for (const LidarPacket& p : rec.lidar_packets) EXPECT_TRUE(decoder.Decode(p, &points));
    size_t wraps = 0;
    for (size_t i = 1; i < points.size(); ++i) wraps += points[i - 1].azimuth_deg - points[i].azimuth_deg > 180.f;
    return wraps > 0 ? wraps - 1 : 0;
  }

  static std::string* dir_;
  static Status* sim_status_;
};
std::string* KittiExport::dir_ = nullptr;
Status* KittiExport::sim_status_ = nullptr;

TEST_F(KittiExport, ReadsBackAsOneFramePerRevolutionWithTruthPoses) {
  KittiExportOptions o;
  o.recording_dir = *dir_ + "/recording";
  o.out_dir = *dir_ + "/kitti_truth";
  EXPECT_EQ(o.deskew, KittiDeskewSource::kEstimator);  // truth is never the default
  KittiDeskewSource parsed;
  EXPECT_FALSE(ParseKittiDeskewSource("auto", &parsed));
  o.deskew = KittiDeskewSource::kTruth;
  KittiExportResult r;
  const Status s = ExportKitti(o, &r);
  ASSERT_TRUE(s) << s.message;
  EXPECT_TRUE(r.deskewed_with_truth);
  EXPECT_EQ(r.points_skipped, 0u);
  EXPECT_EQ(r.bad_packets, 0u);
  EXPECT_EQ(r.frames, CompleteRevolutions(o.recording_dir));
  EXPECT_GE(r.frames, 38u);  // 4 s at 600 rpm: 40 revolutions, the partial first and last dropped
  EXPECT_LE(r.frames, 40u);

  KittiSequencePaths paths;
  paths.dir = *dir_ + "/kitti_truth/sequences/00";
  KittiSequence seq;
  const Status open = OpenKittiSequence(paths, &seq);  // poses found through ../../poses/00.txt
  ASSERT_TRUE(open) << open.message;
  ASSERT_EQ(seq.frame_ids.size(), r.frames);
  EXPECT_EQ(seq.frame_ids.back(), int(r.frames) - 1);
  EXPECT_FALSE(seq.nominal_times);
  ASSERT_EQ(seq.poses.size(), r.frames);
  // sequence_info.txt says what the bins are, the truth deskew included.
  EXPECT_EQ(seq.info_path, r.info_path);
  EXPECT_EQ(seq.info.scan_lines, 16);
  EXPECT_EQ(seq.info.deskew.rfind("truth (the simulation's ground truth", 0), 0u) << seq.info.deskew;
  ASSERT_EQ(seq.point_time_paths.size(), r.frames);
  size_t points = 0;
  for (size_t k = 0; k < r.frames; ++k) {
    // 600 rpm head; a frame's time is its first return's, up to ~12 ms after the cut where the head looks at
    // nothing (measured: first frame 11.9 ms late, gaps 95.4-100.0 ms)
    if (k > 0) {
      EXPECT_NEAR(seq.times[k] - seq.times[k - 1], 0.1, 0.01) << k;
    }
    EXPECT_EQ(seq.times[k], r.times[k]);
    std::vector<KittiPoint> bin;
    ASSERT_TRUE(ReadKittiBin(seq.bin_paths[k], &bin));
    EXPECT_GT(bin.size(), 10000u) << k;  // a VLP-16 revolution indoors: ~28k returns
    points += bin.size();
    // Point times: one per point, from the frame time (its first return) to one revolution after it; they fall
    // back exactly 15 times (16 rings, each in firing order).
    std::vector<float> times;
    ASSERT_TRUE(ReadKittiPointTimes(seq.point_time_paths[k], &times));
    ASSERT_EQ(times.size(), bin.size()) << k;
    EXPECT_EQ(*std::min_element(times.begin(), times.end()), 0.f) << k;
    EXPECT_LT(*std::max_element(times.begin(), times.end()), 0.1) << k;
    size_t falls = 0;
    for (size_t i = 1; i < times.size(); ++i) falls += times[i] < times[i - 1];
    EXPECT_EQ(falls, 15u) << k;
  }
  EXPECT_EQ(points, r.points);

  // calib: cam0 = the rig's camera; poses: T_base(0)_base(k) from truth/base.tum, in cam0 convention.
  Recording rec;
  ASSERT_TRUE(LoadRecording(o.recording_dir, &rec));
  EXPECT_LT((seq.calib.T_cam0_velo.matrix() - rec.calib.T_base_cam.inverse().matrix()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(seq.calib.P[0](0, 0), rec.calib.camera.fx_px);
  Trajectory base, at;
  ASSERT_TRUE(sim::ReadTum(o.recording_dir + "/truth/base.tum", &base));
  for (Seconds t : seq.times) at.push_back({t, Pose3::Identity()});
  const Trajectory truth = InterpolateTrajectory(base, at);
  ASSERT_EQ(truth.size(), r.frames);
  double worst_m = 0.0, worst_rad = 0.0, travelled_m = 0.0;
  for (size_t k = 0; k < r.frames; ++k) {
    const Pose3 expected = truth[0].T_ref_body.inverse() * truth[k].T_ref_body;
    const Pose3 got = Cam0ToVeloPose(seq.calib.T_cam0_velo, seq.poses[k]);
    worst_m = std::max(worst_m, (got.translation() - expected.translation()).norm());
    worst_rad = std::max(worst_rad, Eigen::AngleAxisd(got.linear().transpose() * expected.linear()).angle());
    travelled_m = std::max(travelled_m, expected.translation().norm());
  }
  // Only floating-point round-off separates the two (the file is written in round-trip precision).
  EXPECT_LT(worst_m, 1e-9);
  EXPECT_LT(worst_rad, 1e-9);
  EXPECT_GT(travelled_m, 0.05);  // the rig moved: the check is not trivially identity against identity
  EXPECT_LT((seq.poses[0].matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(KittiExport, TruthAndEstimatorDeskewAgreePointByPoint) {
  KittiExportOptions truth;
  truth.recording_dir = *dir_ + "/recording";
  truth.out_dir = *dir_ + "/kitti_truth_b";
  truth.deskew = KittiDeskewSource::kTruth;
  KittiExportOptions est = truth;
  est.out_dir = *dir_ + "/kitti_estimator";
  est.deskew = KittiDeskewSource::kEstimator;
  KittiExportResult a, b;
  ASSERT_TRUE(ExportKitti(truth, &a));
  const Status s = ExportKitti(est, &b);
  ASSERT_TRUE(s) << s.message;
  EXPECT_FALSE(b.deskewed_with_truth);
  EXPECT_TRUE(b.wrote_poses);  // poses still come from the truth
  ASSERT_EQ(a.frames, b.frames);
  std::vector<double> errors;
  for (size_t k = 0; k < a.frames; ++k) {
    EXPECT_EQ(a.times[k], b.times[k]) << k;
    KittiDatasetLayout la{truth.out_dir, "00"}, lb{est.out_dir, "00"};
    std::vector<KittiPoint> pa, pb;
    ASSERT_TRUE(ReadKittiBin(la.BinPath(int(k)), &pa));
    ASSERT_TRUE(ReadKittiBin(lb.BinPath(int(k)), &pb));
    ASSERT_EQ(pa.size(), pb.size()) << "frame " << k << " (estimator skipped " << b.points_skipped << ")";
    std::vector<double> frame;
    for (size_t i = 0; i < pa.size(); ++i)
      frame.push_back((Eigen::Vector3f(pa[i].x_m, pa[i].y_m, pa[i].z_m) -
                       Eigen::Vector3f(pb[i].x_m, pb[i].y_m, pb[i].z_m)).norm());
    std::sort(frame.begin(), frame.end());
    if (k == 0 || k + 1 == a.frames)
      std::printf("frame %zu: median %.4f m, max %.4f m\n", k, frame[frame.size() / 2], frame.back());
    errors.insert(errors.end(), frame.begin(), frame.end());
  }
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2], p99 = errors[errors.size() * 99 / 100];
  std::printf("truth vs estimator deskew over %zu points: median %.4f m, p99 %.4f m, max %.4f m\n", errors.size(),
              median, p99, errors.back());
  // Measured (seed 1, the lab's own walk, 4 s: 2 s at rest, then walking): median 0.17 cm, p99 1.1 cm, max 2.0 cm
  // (on the old 2 s loop that left the lab: median 1.0 cm, p99 5.4 cm): the core's encoder/IMU deskew against the
  // exact one. Bounds kept from the faster loop (2-7x here): a frame convention slip (wrong scan-start frame, lidar
  // instead of base, a revolution off) gives decimetres.
  EXPECT_LT(median, 0.02);
  EXPECT_LT(p99, 0.08);
}

// The default export (estimator deskew) read back by `slam --kitti`: sequence_info.txt gives 16 lines, the
// per-point times split every frame into exactly those 16 rings (no warning), and the LiDAR-only trajectory
// follows the export's poses (the simulation's truth).
TEST_F(KittiExport, SlamKittiReadsTheExportBack) {
  KittiExportOptions o;
  o.recording_dir = *dir_ + "/recording";
  o.out_dir = *dir_ + "/kitti_roundtrip";
  KittiExportResult exported;
  const Status s = ExportKitti(o, &exported);
  ASSERT_TRUE(s) << s.message;
  EXPECT_FALSE(exported.deskewed_with_truth);
  KittiSequenceInfo info;
  ASSERT_TRUE(ReadKittiSequenceInfo(exported.info_path, &info));
  EXPECT_EQ(info.deskew.rfind("estimator", 0), 0u) << info.deskew;

  // Without its point times the export cannot be split into rings: in the base frame of a rotary rig a ring's
  // azimuth does not sweep 0 -> 360 deg.
  std::vector<KittiPoint> bin0;
  ASSERT_TRUE(ReadKittiBin(KittiDatasetLayout{o.out_dir, "00"}.BinPath(0), &bin0));
  std::vector<ScanPoint> points0;
  KittiScanStats by_azimuth;
  const Status split = KittiScanPoints(bin0, 0.0, KittiScanConfig(), &points0, &by_azimuth);
  std::printf("frame 0 split by azimuth: %s, %zu lines\n", split.message.c_str(), by_azimuth.num_lines);
  EXPECT_TRUE(!split || by_azimuth.num_lines != 16u);

  KittiRunOptions run;
  run.paths.dir = exported.sequence_dir;
  run.out_dir = *dir_ + "/kitti_roundtrip_run";
  // The rig's range gate (EstimatorConfig's 0.8 m) instead of KITTI's 2 m, which drops the car there and most of
  // this 7 m deep lab here (measured with 2 m: APE max 0.45 m; the docs say to pass it with --config).
  run.estimator.preprocess.min_range_m = EstimatorConfig().preprocess.min_range_m;
  KittiRunResult r;
  const Status ran = RunKitti(run, &r);
  ASSERT_TRUE(ran) << ran.message;
  ASSERT_EQ(r.frame_ids.size(), exported.frames);
  EXPECT_EQ(r.expected_lines, 16);
  EXPECT_EQ(r.expected_lines_source, exported.info_path);
  EXPECT_TRUE(r.point_times);
  for (size_t lines : r.scan_lines) EXPECT_EQ(lines, 16u);
  EXPECT_EQ(r.frames_other_line_count, 0u);
  EXPECT_EQ(r.elevation_inversions, 0u);
  EXPECT_EQ(r.range_sigma_source, exported.info_path);  // the sim's range noise, from calib.yaml via the export
  ASSERT_TRUE(r.has_ground_truth);
  ASSERT_TRUE(r.ape.status) << r.ape.status.message;
  ASSERT_TRUE(r.rpe_translation.status) << r.rpe_translation.status.message;
  double travelled_m = 0.0;
  for (const StampedPose& p : r.ground_truth_cam0) travelled_m = std::max(travelled_m, p.T_ref_body.translation().norm());
  std::printf("slam --kitti on the export: %zu frames, APE max %.4f m (rmse %.4f), RPE rmse %.4f m / %.3f deg, "
              "truth travelled %.3f m\n",
              r.frame_ids.size(), r.ape.stats.max, r.ape.stats.rmse, r.rpe_translation.stats.rmse,
              r.rpe_rotation.stats.rmse, travelled_m);
  // Measured (seed 1, the lab's own walk, 4 s, 38 frames): truth travelled 0.96 m; APE max 0.100 m, rmse 0.042 m;
  // RPE rmse 0.023 m / 0.52 deg per frame. That is LiDAR-only odometry from a cold start on 30 deg VLP-16 fans (no
  // IMU, no encoder; keyframes by the rotor angle per frame that sequence_info.txt states); on a 2 s loop the
  // truth-deskewed export gave APE max 0.081 m against 0.092 m, so the deskew is not what limits it (the rig's own
  // estimator, with IMU and encoder, is at ~1 cm). Bounds ~1.5x: an identity trajectory would give ~1 m, KITTI's 2 m range gate 0.45 m, a frame slip (lidar for base, Tr not conjugated) decimetres.
  EXPECT_GT(travelled_m, 0.5);
  EXPECT_LT(r.ape.stats.max, 0.15);
  EXPECT_LT(r.ape.stats.rmse, 0.08);
  EXPECT_LT(r.rpe_translation.stats.rmse, 0.06);
  EXPECT_LT(r.rpe_rotation.stats.rmse, 1.0);
}

}  // namespace
}  // namespace rotolidar::bench
