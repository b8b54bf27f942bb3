// The camera inside the sim: frames, timestamps and images in the recording, the lens and extrinsic in
// calib.yaml (from the camera config and the rig model's cam site), the true camera pose in truth/cam.tum, and
// the same bytes for the same seed.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include <mujoco/mujoco.h>
#include <unistd.h>

#include "core/io/recording.hpp"
#include "sim/rig/rig_model.hpp"
#include "sim/sim_runner.hpp"
#include "sim/truth/truth.hpp"

namespace rotolidar::sim {
namespace {

namespace fs = std::filesystem;

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

class CameraSimTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = fs::temp_directory_path() / ("rotolidar_camera_sim_" + std::to_string(::getpid())); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(CameraSimTest, WritesFramesCalibAndTrueCameraPoses) {
  SimConfig config = DefaultSimConfig();
  config.duration_s = 0.5;
  ASSERT_TRUE(config.camera.enabled);  // on by default, 30 Hz
  SimSummary summary;
  Status s = RunSimulation(config, (dir_ / "a").string(), &summary);
  ASSERT_TRUE(s.ok) << s.message;
  // Frames at (k + 0.5) / 30 s whose exposure ends by 0.5 s: k = 0..14.
  EXPECT_EQ(summary.camera_frames, 15u);
  Recording rec;
  s = LoadRecording((dir_ / "a").string(), &rec);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(rec.camera.size(), 15u);
  for (std::size_t k = 0; k < rec.camera.size(); ++k) EXPECT_NEAR(rec.camera[k].t_s, (k + 0.5) / 30.0, 1e-9);
  CameraFrame frame;
  ASSERT_TRUE(LoadCameraFrame(rec.camera[3], &frame).ok);
  EXPECT_EQ(frame.image.cols, 640);
  EXPECT_EQ(frame.image.rows, 480);
  // calib.yaml: the configured lens, and T_base_cam = the compiled rig model's cam site (a child of the base).
  const CameraIntrinsics& k = rec.calib.camera;
  EXPECT_EQ(k.fx_px, config.camera.fx_px);
  EXPECT_EQ(k.k1, config.camera.k1);
  EXPECT_EQ(k.p2, config.camera.p2);
  EXPECT_EQ(k.rate_hz, 30.0);
  std::unique_ptr<RigModel> rig;
  ASSERT_TRUE(RigModel::Create(config.rig_model, &rig).ok);
  const mjModel* m = rig->model();
  const int site = rig->cam_site_id();
  ASSERT_EQ(m->site_bodyid[site], rig->base_body_id());
  const Eigen::Vector3d site_pos(m->site_pos[3 * site], m->site_pos[3 * site + 1], m->site_pos[3 * site + 2]);
  const Eigen::Quaterniond site_q(m->site_quat[4 * site], m->site_quat[4 * site + 1], m->site_quat[4 * site + 2],
                                  m->site_quat[4 * site + 3]);
  EXPECT_LT((rec.calib.T_base_cam.translation() - site_pos).norm(), 1e-9);  // MJCF text carries ~12 digits
  EXPECT_LT((rec.calib.T_base_cam.linear() - site_q.toRotationMatrix()).norm(), 1e-9);
  // truth/cam.tum: one pose per frame, T_world_base (truth/base.tum, 1 kHz, interpolated) * T_base_cam.
  TruthLog truth;
  s = ReadTruth((dir_ / "a").string(), &truth);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(truth.cam.size(), 15u);
  for (const StampedPose& cam : truth.cam) {
    const auto after = std::lower_bound(truth.base.begin(), truth.base.end(), cam.t_s,
                                        [](const StampedPose& p, double t) { return p.t_s < t; });
    ASSERT_TRUE(after != truth.base.begin() && after != truth.base.end());
    const auto before = after - 1;
    const double f = (cam.t_s - before->t_s) / (after->t_s - before->t_s);
    const Pose3 T_world_base = Interpolate(before->T_ref_body, after->T_ref_body, f);
    const Pose3 expected = T_world_base * rec.calib.T_base_cam;
    // Interpolating the 1 kHz truth at walking speed: < 1 um and < 1e-6 rad from the exact pose.
    EXPECT_LT((cam.T_ref_body.translation() - expected.translation()).norm(), 1e-5);
    EXPECT_LT((cam.T_ref_body.linear() - expected.linear()).norm(), 1e-5);
  }
  // The same seed writes the same image bytes; another seed other noise.
  s = RunSimulation(config, (dir_ / "b").string(), &summary);
  ASSERT_TRUE(s.ok) << s.message;
  config.seed = 2;
  s = RunSimulation(config, (dir_ / "c").string(), &summary);
  ASSERT_TRUE(s.ok) << s.message;
  for (const char* name : {"camera/000000.png", "camera/000007.png", "camera/000014.png"}) {
    EXPECT_EQ(ReadBytes(dir_ / "a" / name), ReadBytes(dir_ / "b" / name)) << name;
    EXPECT_NE(ReadBytes(dir_ / "a" / name), ReadBytes(dir_ / "c" / name)) << name;
  }
}

TEST_F(CameraSimTest, DisabledCameraWritesNoFrames) {
  SimConfig config = DefaultSimConfig();
  config.duration_s = 0.2;
  config.camera.enabled = false;
  SimSummary summary;
  Status s = RunSimulation(config, dir_.string(), &summary);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(summary.camera_frames, 0u);
  EXPECT_FALSE(fs::exists(dir_ / "camera.csv"));
  TruthLog truth;
  ASSERT_TRUE(ReadTruth(dir_.string(), &truth).ok);
  EXPECT_TRUE(truth.cam.empty());
}

}  // namespace
}  // namespace rotolidar::sim
