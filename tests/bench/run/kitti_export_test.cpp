// Export round trip: simulate 2 s in the "lab" scene, export the recording as a KITTI sequence, read it back with
// the core's KITTI reader: one frame per complete VLP-16 revolution, increasing times, poses = the truth, calib =
// the rig's camera. The truth-deskewed bins are then compared point by point with the estimator-deskewed export of
// the same recording (same revolutions, same points): two independent deskews of one cloud.
#include <algorithm>
#include <filesystem>

#include <unistd.h>

#include <gtest/gtest.h>

#include "bench/run/kitti_export.hpp"
#include "bench/run/truth_eval.hpp"
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
    config.duration_s = 3.0;           // it rests 2 s at its first waypoint, then walks
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
  KittiExportResult r;
  const Status s = ExportKitti(o, &r);
  ASSERT_TRUE(s) << s.message;
  EXPECT_TRUE(r.deskewed_with_truth);
  EXPECT_EQ(r.points_skipped, 0u);
  EXPECT_EQ(r.bad_packets, 0u);
  EXPECT_EQ(r.frames, CompleteRevolutions(o.recording_dir));
  EXPECT_GE(r.frames, 28u);  // 3 s at 600 rpm: 30 revolutions, the partial first and last dropped
  EXPECT_LE(r.frames, 30u);

  KittiSequencePaths paths;
  paths.dir = *dir_ + "/kitti_truth/sequences/00";
  KittiSequence seq;
  const Status open = OpenKittiSequence(paths, &seq);  // poses found through ../../poses/00.txt
  ASSERT_TRUE(open) << open.message;
  ASSERT_EQ(seq.frame_ids.size(), r.frames);
  EXPECT_EQ(seq.frame_ids.back(), int(r.frames) - 1);
  EXPECT_FALSE(seq.nominal_times);
  ASSERT_EQ(seq.poses.size(), r.frames);
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
  // Measured (seed 1, lab, 2 s): median 3.3 cm, p99 9.9 cm, max 10.9 cm; per frame the median grows steadily from
  // 1.8 cm (frame 0) to 5.4 cm (frame 17): the core's encoder/IMU deskew against the exact one. Bounds ~1.5x:
  // a frame convention slip (wrong scan-start frame, lidar instead of base, a revolution off) gives decimetres.
  EXPECT_LT(median, 0.05);
  EXPECT_LT(p99, 0.15);
}

}  // namespace
}  // namespace rotolidar::bench
