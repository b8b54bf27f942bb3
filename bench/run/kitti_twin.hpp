#pragma once
// `rotolidar kitti-twin`: a simulated KITTI odometry sequence (docs/kitti.md, "KITTI twin"). A Velodyne HDL-64E S2
// (sim/lidar/hdl64_caster.hpp) rides KITTI's car along a real KITTI ground-truth trajectory through a generated
// street scene, and the revolutions are written as the sequence KITTI itself would be, so that the core (and any
// KITTI tool) runs on it and its relative error can be set against published KITTI numbers.
//
// The drive: sim::MakeKittiPath through every ground-truth pose exactly (cubic splines in time, frame k at
// t_k = 0.1 s * k), world = the scene frame of scenes/generators/make_urban_loop.py (x forward, y left, z up at the
// first cam0 pose; the ground 1.65 m below cam0). T_world_velo(t) = T_world_cam0(t) * Tr, Tr = T_cam0_velo of
// KITTI's calibration for sequences 00-02 (KittiTwinCalib). Frame k = the revolution from t_k (azimuth 0, straight
// ahead) to t_k + 0.1 s.
// Files in out_dir (the sequence folder; `rotolidar slam --kitti out_dir` reads it):
//   velodyne/%06d.bin        frame k: x y z reflectance per point (float32), line by line (top laser first, each
//                            line in firing order); in the LiDAR frame at each point's own firing time (not
//                            motion-compensated), or with motion_compensate at t_k (moved with the true poses)
//   velodyne_times/%06d.bin  per point: firing time after t_k [s] (float32)
//   poses.txt                the ground truth of frames 0..N-1 as read (KITTI's cam0 convention, bit-exact)
//   times.txt, calib.txt     t_k; P0..P3 and Tr of KittiTwinCalib
//   imu.csv                  with write_imu: the rig's IMU model (sim/sensors/imu_model.hpp, options.imu) mounted
//                            where KITTI's OXTS is (KittiTwinImuCalib), sampled at its rate from t = 0 to the last
//                            frame's end, stamped on times.txt's clock (plus the model's clock error)
//   calib_imu_to_velo.txt    with write_imu: KittiTwinImuCalib (T_velo_imu)
//   sequence_info.txt        sensor, 64 scan lines, range noise, point order, frame, deskew, source
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/io/kitti.hpp"
#include "sim/lidar/hdl64_caster.hpp"
#include "sim/sensors/imu_model.hpp"

namespace rotolidar::bench {

/// KITTI's odometry calibration of sequences 00-02 (calib.txt of the odometry devkit: rectified P0..P3 [px] and
/// Tr = T_cam0_velo [m]).
KittiCalib KittiTwinCalib();

/// KITTI's raw calibration of 2011_10_03 (the day of sequence 00; calib_imu_to_velo.txt): T_velo_imu of the OXTS
/// RT3003 unit, 0.81 m behind, 0.32 m left of and 0.80 m below the Velodyne.
KittiImuCalib KittiTwinImuCalib();

/// The default scene of a sequence: "urban_loop" for "07" (generated along KITTI 07 in the same frame), else "".
std::string KittiTwinDefaultScene(const std::string& sequence);

/// The vertical-angle error of KITTI's published velodyne bins: their points need their elevation corrected by
/// about 0.22 deg (J.-E. Deschaud, "IMLS-SLAM: scan-to-model matching based on 3D data", ICRA 2018), the
/// `typical` and `harsh` twins carry it.
constexpr double kKittiElevationErrorDeg = 0.22;

struct KittiTwinOptions {
  std::string sequence = "07";   ///< only named in sequence_info.txt
  std::string poses_path;        ///< KITTI ground-truth poses of the sequence (cam0, 12 numbers a line)
  std::string scene;             ///< scene name or file (sim::FindSceneFile) in the generator's frame
  std::string out_dir;           ///< the sequence folder to write (created)
  int frames = 0;                ///< frames from 0; 0 = as many as the poses allow (their count - 1)
  uint64_t seed = 1;             ///< run seed (the caster's "hdl64.range" stream)
  /// false: each point in the LiDAR frame at its own firing time (raw, as the sensor measures); true: moved into
  /// the LiDAR frame at the frame time with the true poses (as KITTI's published bins are compensated).
  bool motion_compensate = false;
  sim::Hdl64CasterConfig lidar;
  /// An IMU stream (imu.csv + calib_imu_to_velo.txt): the rig's consumer MEMS model rather than KITTI's OXTS, so
  /// a LiDAR-inertial number says what the core's IMU path does with the IMU it is built for.
  bool write_imu = true;
  sim::ImuConfig imu;            ///< noise and per-run errors (the CLI: the realism preset's)
  bool Validate(std::string* error) const;  ///< false naming the field
};

struct KittiTwinResult {
  std::string scene_path;
  size_t frames = 0;
  size_t points = 0;             ///< over all bins
  size_t imu_samples = 0;        ///< written to imu.csv
  std::vector<Seconds> times;    ///< as written to times.txt
  std::vector<Pose3> poses;      ///< as written to poses.txt
  double path_length_m = 0.0;    ///< of cam0 over the frames written
  double cast_s = 0.0;           ///< wall time spent casting [s]
};

/// Loads the poses and the scene, casts and writes the sequence. Fails naming the file on unreadable poses or
/// scene, fewer than 2 poses, more frames asked for than the poses cover, or unwritable output.
/// `progress(fraction)` is called about every 10 % of the frames.
Status RunKittiTwin(const KittiTwinOptions& options, KittiTwinResult* result,
                    const std::function<void(double)>& progress = nullptr);

}  // namespace rotolidar::bench
