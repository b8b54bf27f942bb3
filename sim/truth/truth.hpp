#pragma once
// Ground truth of a simulated run, written beside the recording in <recording>/truth/ and read only by bench/:
//   base.tum      TUM lines "t tx ty tz qx qy qz qw" of T_world_base ('#' lines are comments)
//   lidar.tum     the same for T_world_lidar
//   cam.tum       the same for T_world_cam (camera optical frame) at each camera frame's time (mid-exposure;
//                 rolling shutter: the middle row's time); only header lines when the camera is off
//   rotor.csv     header "t_s,theta_rad"; theta is the true, unwrapped rotor angle [rad]
//   imu_bias.csv  header "t_s,bgx,bgy,bgz,bax,bay,baz"; true gyro [rad/s] and accel [m/s^2] biases, imu frame
//   dynamic_hits.csv  header "t_s,object_id,x_m,y_m,z_m"; one line per LiDAR return the packets carry whose
//                 surface is a dynamic object: firing time, the object's index in Scene::dynamic_objects and the
//                 exact (noise-free) hit position in the world frame [m]; only the header when there are none.
//                 Optional on reading (recordings written before it have none: read as empty).
// Numbers are written in the shortest form that reads back to the identical double (std::to_chars).
// Times are on the rig clock [s].
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/types/time.hpp"
#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"

namespace rotolidar::sim {

struct RotorAngleSample {
  Seconds t_s = 0.0;
  double theta_rad = 0.0;  ///< unwrapped rotor angle about the motor z axis
};

struct ImuBiasSample {
  Seconds t_s = 0.0;
  Eigen::Vector3d gyro_bias_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias_mps2 = Eigen::Vector3d::Zero();
};

/// One LiDAR return from a dynamic object (a walker, a car), as the packets carry it.
struct DynamicHitSample {
  Seconds t_s = 0.0;   ///< firing time of the laser
  int object_id = 0;   ///< index into Scene::dynamic_objects, >= 0
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  ///< exact first hit of the central ray, world frame [m]
};

/// Everything in <recording>/truth/, in memory. Each vector is in time order.
struct TruthLog {
  Trajectory base;   ///< T_world_base (StampedPose::T_ref_body with ref = world)
  Trajectory lidar;  ///< T_world_lidar
  Trajectory cam;    ///< T_world_cam at the camera frames' times (empty without camera; optional file)
  std::vector<RotorAngleSample> rotor;
  std::vector<ImuBiasSample> imu_bias;
  std::vector<DynamicHitSample> dynamic_hits;  ///< empty for scenes without dynamic objects and older recordings
};

/// Streams truth into <recording_dir>/truth/ (created if missing; existing files are overwritten).
/// Every call returns a Status whose message names the file on failure. Not thread-safe. The destructor closes
/// the files without reporting errors: call Close() to learn whether everything reached the disk.
class TruthWriter {
 public:
  TruthWriter() = default;
  TruthWriter(const TruthWriter&) = delete;
  TruthWriter& operator=(const TruthWriter&) = delete;

  Status Open(const std::string& recording_dir);
  Status WriteBase(const StampedPose& T_world_base);
  Status WriteLidar(const StampedPose& T_world_lidar);
  Status WriteCam(const StampedPose& T_world_cam);
  Status WriteRotor(const RotorAngleSample& sample);
  Status WriteImuBias(const ImuBiasSample& sample);
  Status WriteDynamicHit(const DynamicHitSample& sample);
  /// Flushes and closes all six files; an error names the first file that failed.
  Status Close();
  bool is_open() const { return open_; }
  const std::string& truth_dir() const { return dir_; }

 private:
  struct File {
    std::string path;
    std::ofstream stream;
  };
  Status Check(File& file);
  bool open_ = false;
  std::string dir_;
  File base_, lidar_, rotor_, imu_bias_, cam_, dynamic_hits_;
};

/// Writes a whole TruthLog through TruthWriter.
Status WriteTruth(const std::string& recording_dir, const TruthLog& log);

/// Reads a TUM file ("t tx ty tz qx qy qz qw", '#' comments and blank lines skipped). Errors name file:line.
Status ReadTum(const std::string& path, Trajectory* out);
/// Reads the files of <recording_dir>/truth/ back (cam.tum and dynamic_hits.csv only when present: older
/// recordings lack them). Errors name file:line and the field.
Status ReadTruth(const std::string& recording_dir, TruthLog* out);
/// Reads <recording_dir>/truth/dynamic_hits.csv alone (the bench's dynamic-object share needs nothing else); a
/// missing file reads as no hits. Errors name file:line and the field (object_id must be a whole number >= 0).
Status ReadDynamicHits(const std::string& recording_dir, std::vector<DynamicHitSample>* out);

}  // namespace rotolidar::sim
