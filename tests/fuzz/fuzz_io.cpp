// Fuzz targets of core/io: CSV streams, calib.yaml, point clouds, KITTI files, trajectories.
#include "tests/fuzz/fuzz_target.hpp"

#include "core/io/calib_yaml.hpp"
#include "core/io/kitti.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/io/recording.hpp"
#include "core/io/trajectory_io.hpp"

namespace rotolidar::fuzz {
namespace {

ROTOLIDAR_FUZZ_TARGET(imu_csv) {
  std::vector<ImuSample> samples;
  (void)LoadImuCsv(WriteInput(data, size, "imu.csv"), &samples);
  return 0;
}

// encoder.csv and camera.csv are read by LoadRecording (with calib.yaml and an empty lidar.pcap beside them) and
// by LoadCameraIndex.
ROTOLIDAR_FUZZ_TARGET(stream_csv) {
  const std::string dir = std::filesystem::path(WriteInput(data, size, "encoder.csv")).parent_path().string();
  std::vector<CameraFrameRef> frames;
  WriteInput(data, size, "camera.csv");
  (void)LoadCameraIndex(dir, &frames);
  std::ofstream(dir + "/calib.yaml") << "format_version: 1\n";
  std::ofstream(dir + "/imu.csv") << "t_s,gyro_x_radps,gyro_y_radps,gyro_z_radps,accel_x_mps2,accel_y_mps2,"
                                     "accel_z_mps2\n";
  Recording rec;
  (void)LoadRecording(dir, &rec);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(calib_yaml) {
  RigCalib calib;
  (void)LoadCalibYaml(WriteInput(data, size, "calib.yaml"), &calib);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(ply) {
  std::vector<Eigen::Vector3d> points;
  (void)LoadPointCloud(WriteInput(data, size, "input.ply"), &points);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(pcd) {
  std::vector<Eigen::Vector3d> points;
  (void)LoadPointCloud(WriteInput(data, size, "input.pcd"), &points);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(kitti_bin) {
  std::vector<KittiPoint> points;
  (void)ReadKittiBin(WriteInput(data, size, "000000.bin"), &points);
  std::vector<float> times;
  (void)ReadKittiPointTimes(WriteInput(data, size, "000000.times"), &times);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(kitti_text) {
  const std::string path = WriteInput(data, size, "kitti.txt");
  KittiCalib calib;
  (void)ReadKittiCalib(path, &calib);
  KittiImuCalib imu;
  (void)ReadKittiImuCalib(path, &imu);
  std::vector<Pose3> poses;
  (void)ReadKittiPoses(path, &poses);
  std::vector<Seconds> times;
  (void)ReadKittiTimeList(path, &times);
  KittiSequenceInfo info;
  (void)ReadKittiSequenceInfo(path, &info);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(trajectory) {
  const std::string path = WriteInput(data, size, "trajectory.txt");
  for (const char* name : {"tum", "kitti", "euroc"}) {
    TrajectoryFormat format;
    if (!ParseTrajectoryFormat(name, &format)) continue;
    Trajectory traj;
    (void)ReadTrajectory(path, format, &traj);
  }
  return 0;
}

}  // namespace
}  // namespace rotolidar::fuzz
