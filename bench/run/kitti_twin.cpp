// The KITTI twin: an HDL-64E on KITTI's ground-truth path through a generated street scene, written as a KITTI
// odometry sequence (see the header).
#include "bench/run/kitti_twin.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "core/io/recording.hpp"
#include "sim/rig/carrier_paths.hpp"
#include "sim/sim_config.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

Matrix34d Row34(const std::array<double, 12>& v) {
  Matrix34d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = v[size_t(4 * r + c)];
  return m;
}

std::string FramePath(const std::string& dir, const char* folder, int id) {
  char name[32];
  std::snprintf(name, sizeof(name), "/%s/%06d.bin", folder, id);
  return dir + name;
}

/// The carrier path's base is cam0 with x forward (cam z), y left (-cam x), z up (-cam y): T_base_velo =
/// T_cam_base^-1 * Tr.
Pose3 BaseVelo(const Pose3& T_cam0_velo) {
  Pose3 T_cam_base = Pose3::Identity();
  T_cam_base.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  return T_cam_base.inverse() * T_cam0_velo;
}

/// T_world_cam0(t) * Tr: the LiDAR in the scene frame.
Pose3 WorldVelo(const sim::BaseMotion& motion, const Pose3& T_cam0_velo, Seconds t) {
  return motion.At(t).T_world_base * BaseVelo(T_cam0_velo);
}

/// imu.csv and calib_imu_to_velo.txt: the IMU model at its rate over [0, t_end_s].
Status WriteImu(const KittiTwinOptions& o, const sim::BaseMotion& motion, Seconds t_end_s, size_t* count) {
  const KittiImuCalib imu_calib = KittiTwinImuCalib();
  const Pose3 T_base_imu = BaseVelo(KittiTwinCalib().T_cam0_velo) * imu_calib.T_velo_imu;
  sim::ImuModel model(o.imu, T_base_imu, o.seed);
  std::vector<ImuSample> samples;
  const double dt = 1.0 / o.imu.noise.rate_hz;
  for (long k = 0; k * dt <= t_end_s + 1e-9; ++k) samples.push_back(model.Sample(motion.At(k * dt), k * dt));
  *count = samples.size();
  if (Status s = SaveImuCsv(o.out_dir + "/imu.csv", samples); !s) return s;
  return WriteKittiImuCalib(o.out_dir + "/calib_imu_to_velo.txt", imu_calib);
}

KittiSequenceInfo TwinInfo(const KittiTwinOptions& o, const std::string& scene_path) {
  KittiSequenceInfo info;
  info.sensor = "Velodyne HDL-64E S2 (simulated: rotolidar kitti-twin)";
  info.scan_lines = sim::kHdl64Lasers;
  info.range_sigma_m = o.lidar.range_noise_sigma_m;
  info.point_order = "line by line, top laser first; each line in firing order (azimuth atan2(y, x) from 0 "
                     "counter-clockwise through 360 deg)";
  info.point_times = "velodyne_times/%06d.bin: float32 firing time [s] after the frame's times.txt entry";
  if (o.motion_compensate) {
    info.frame = "velodyne (LiDAR) frame at the frame time";
    info.deskew = "truth: every point moved from its firing-time pose into the frame-time pose (true poses)";
  } else {
    info.frame = "velodyne (LiDAR) frame at each point's own firing time";
    info.deskew = "none: raw, each point as measured from the pose at its own firing time";
  }
  info.returns = "single (first surface hit)";
  info.source = "kitti-twin: KITTI " + o.sequence + " ground-truth poses, scene " + scene_path + ", seed " +
                std::to_string(o.seed);
  if (o.lidar.elevation_error_deg != 0.0)
    info.source += ", elevation error " + std::to_string(o.lidar.elevation_error_deg) + " deg";
  return info;
}

Status LoadTwinWorld(const std::string& scene_name, std::string* path, std::unique_ptr<sim::EmbreeScene>* es) {
  if (Status s = sim::FindSceneFile(scene_name, path); !s) return s;
  sim::Scene scene;
  if (Status s = sim::LoadScene(*path, &scene); !s) return s;
  return sim::EmbreeScene::Create(scene, es, 0.0);
}

Status WriteSmallFiles(const KittiTwinOptions& o, const std::string& scene_path, const std::vector<Pose3>& poses,
                       const std::vector<Seconds>& times) {
  if (Status s = WriteKittiCalib(o.out_dir + "/calib.txt", KittiTwinCalib()); !s) return s;
  if (Status s = WriteKittiTimeList(o.out_dir + "/times.txt", times); !s) return s;
  if (Status s = WriteKittiPoses(o.out_dir + "/poses.txt", poses); !s) return s;
  return WriteKittiSequenceInfo(o.out_dir + "/sequence_info.txt", TwinInfo(o, scene_path));
}

/// One revolution from t0 into a bin and its per-point times.
void CastFrame(sim::Hdl64Caster* caster, const sim::BaseMotion& motion, Seconds t0, bool compensate,
               std::vector<KittiPoint>* bin, std::vector<float>* times) {
  const Pose3 Tr = KittiTwinCalib().T_cam0_velo;
  const int n = caster->config().firings_per_revolution;
  const double dt = caster->period_s() / n;
  std::vector<Pose3> column_pose(static_cast<size_t>(n));  // the caster asks once per column, in order
  for (int c = 0; c < n; ++c) column_pose[size_t(c)] = WorldVelo(motion, Tr, t0 + c * dt);
  const auto pose_at = [&](Seconds t) { return column_pose[size_t(std::lround((t - t0) / dt))]; };
  std::vector<sim::Hdl64Point> points;
  caster->Revolution(t0, pose_at, &points);
  const Pose3 T_velo0_world = column_pose[0].inverse();
  bin->resize(points.size());
  times->resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const sim::Hdl64Point& p = points[i];
    Eigen::Vector3d x(p.x_m, p.y_m, p.z_m);
    if (compensate) x = T_velo0_world * (column_pose[size_t(std::lround(p.t_s / dt))] * x);
    (*bin)[i] = KittiPoint{float(x.x()), float(x.y()), float(x.z()), p.reflectance};
    (*times)[i] = p.t_s;
  }
}

}  // namespace

KittiCalib KittiTwinCalib() {
  KittiCalib c;
  c.P[0] = Row34({718.856, 0, 607.1928, 0, 0, 718.856, 185.2157, 0, 0, 0, 1, 0});
  c.P[1] = Row34({718.856, 0, 607.1928, -386.1448, 0, 718.856, 185.2157, 0, 0, 0, 1, 0});
  c.P[2] = Row34({718.856, 0, 607.1928, 45.38225, 0, 718.856, 185.2157, -0.1130887, 0, 0, 1, 0.003779761});
  c.P[3] = Row34({718.856, 0, 607.1928, -337.2877, 0, 718.856, 185.2157, 2.369057, 0, 0, 1, 0.004915215});
  const Matrix34d tr = Row34({4.276802385584e-04, -9.999672484946e-01, -8.084491683471e-03, -1.198459927713e-02,
                              -7.210626507497e-03, 8.081198471645e-03, -9.999413164504e-01, -5.403984729748e-02,
                              9.999738645903e-01, 4.859485810390e-04, -7.206933692422e-03, -2.921968648686e-01});
  c.T_cam0_velo.linear() = tr.leftCols<3>();
  c.T_cam0_velo.translation() = tr.col(3);
  return c;
}

KittiImuCalib KittiTwinImuCalib() {
  KittiImuCalib c;
  c.calib_time = "25-May-2012 16:47:16";
  c.T_velo_imu.linear() << 9.999976e-01, 7.553071e-04, -2.035826e-03, -7.854027e-04, 9.998898e-01, -1.482298e-02,
      2.024406e-03, 1.482454e-02, 9.998881e-01;
  c.T_velo_imu.translation() << -8.086759e-01, 3.195559e-01, -7.997231e-01;
  return c;
}

std::string KittiTwinDefaultScene(const std::string& sequence) { return sequence == "07" ? "urban_loop" : ""; }

bool KittiTwinOptions::Validate(std::string* error) const {
  const auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (poses_path.empty()) return fail("kitti-twin: the ground-truth poses file is required");
  if (scene.empty()) return fail("kitti-twin: a scene is required (sequence " + sequence + " has no default)");
  if (out_dir.empty()) return fail("kitti-twin: the output folder is required");
  if (frames < 0) return fail("kitti-twin: frames must be >= 0");
  if (write_imu && !imu.Validate(error)) return false;
  return lidar.Validate(error);
}

Status RunKittiTwin(const KittiTwinOptions& o, KittiTwinResult* result, const std::function<void(double)>& progress) {
  std::string error;
  if (!o.Validate(&error)) return Status::Error(error);
  std::vector<Pose3> gt;
  if (Status s = ReadKittiPoses(o.poses_path, &gt); !s) return s;
  if (gt.size() < 2) return Status::Error(o.poses_path + ": need at least 2 poses");
  const int frames = o.frames > 0 ? o.frames : int(gt.size()) - 1;  // the last revolution needs the next pose
  if (frames > int(gt.size()) - 1)
    return Status::Error(o.poses_path + ": " + std::to_string(gt.size()) + " poses cover at most " +
                         std::to_string(gt.size() - 1) + " frames (asked for " + std::to_string(frames) + ")");
  sim::KittiPathConfig path_config;
  path_config.poses_file = o.poses_path;
  path_config.height_m = 0.0;  // the generator's frame: the first cam0 at the origin
  std::unique_ptr<sim::BaseMotion> motion;
  if (Status s = sim::MakeKittiPath(path_config, gt, {}, &motion); !s) return s;
  KittiTwinResult r;
  std::unique_ptr<sim::EmbreeScene> es;
  if (Status s = LoadTwinWorld(o.scene, &r.scene_path, &es); !s) return s;
  std::error_code ec;
  for (const char* sub : {"velodyne", "velodyne_times"}) {
    fs::create_directories(o.out_dir + "/" + sub, ec);
    if (ec) return Status::Error(o.out_dir + "/" + sub + ": cannot create (" + ec.message() + ")");
  }
  sim::Hdl64Caster caster(es.get(), o.lidar, o.seed);
  std::vector<KittiPoint> bin;
  std::vector<float> times;
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < frames; ++k) {
    const Seconds t0 = 0.1 * k;  // KITTI's 10 Hz frames
    CastFrame(&caster, *motion, t0, o.motion_compensate, &bin, &times);
    if (Status s = WriteKittiBin(FramePath(o.out_dir, "velodyne", k), bin); !s) return s;
    if (Status s = WriteKittiPointTimes(FramePath(o.out_dir, "velodyne_times", k), times); !s) return s;
    r.points += bin.size();
    r.times.push_back(t0);
    r.poses.push_back(gt[size_t(k)]);
    if (k > 0) r.path_length_m += (gt[size_t(k)].translation() - gt[size_t(k - 1)].translation()).norm();
    if (progress && (k + 1) % std::max(1, frames / 10) == 0) progress(double(k + 1) / frames);
  }
  r.cast_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.frames = size_t(frames);
  if (Status s = WriteSmallFiles(o, r.scene_path, r.poses, r.times); !s) return s;
  if (o.write_imu)
    if (Status s = WriteImu(o, *motion, 0.1 * frames, &r.imu_samples); !s) return s;
  *result = std::move(r);
  return Status::Ok();
}

}  // namespace rotolidar::bench
