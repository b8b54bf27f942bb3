#pragma once
// The KITTI odometry format (Geiger et al., CVPR 2012; the odometry devkit's readme), read and written bit-exactly:
//
//   <dataset>/sequences/<NN>/velodyne/%06d.bin  frame k: float32 little-endian x y z reflectance per point, in the
//                                               Velodyne frame of that frame [m], reflectance in [0, 1]
//   <dataset>/sequences/<NN>/times.txt          one time [s] a line; line k = frame k
//   <dataset>/sequences/<NN>/calib.txt          "P0: 12 numbers" .. "P3:" (3x4 projection matrices [px], row-major)
//                                               and "Tr: 12 numbers" = T_cam0_velo (row-major [R | t], metres)
//   <dataset>/poses/<NN>.txt                    line k: 12 numbers, row-major [R | t] of T_cam0(0)_cam0(k): the
//                                               left camera of frame k in the left camera of frame 0
//
// Files are parsed strictly: every error names the file and the line (text) or the byte offset (bins) and the
// field. Numbers are written in the shortest form that reads back to the identical double (std::to_chars), so a
// write -> read round trip reproduces every value bit for bit. Readers leave their output untouched on failure.
//
// Two companion files that KITTI itself does not have (both optional; `rotolidar export --kitti` writes them):
//   <dataset>/sequences/<NN>/velodyne_times/%06d.bin  frame k: float32 little-endian per point, in the bin's
//                                               order: the point's time [s] after line k of times.txt
//   <dataset>/sequences/<NN>/sequence_info.txt  "key: value" lines (KittiSequenceInfo): the sensor, its scan line
//                                               count, how the points are ordered, how they were deskewed
//
// And an IMU, which KITTI's odometry sequences do not have (KITTI's raw recordings do, as OXTS at 10-100 Hz; both
// files optional, `rotolidar kitti-twin` writes them):
//   <dataset>/sequences/<NN>/imu.csv            the recording format's IMU CSV (docs/recording_format.md), stamped on
//                                               times.txt's clock, the IMU frame as calib_imu_to_velo.txt defines it
//   <dataset>/sequences/<NN>/calib_imu_to_velo.txt  KITTI raw's file of that name: "R: 9 numbers" (row-major) and
//                                               "T: 3 numbers" [m], p_velo = R * p_imu + T, i.e. T_velo_imu;
//                                               an optional "calib_time: ..." line is kept as text
//
// KittiScanPoints() turns one bin into the estimator's ScanPoints (rings from the bin's point order; see its
// comment and docs/kitti.md). Nothing here throws or keeps state; all functions are thread-safe.
#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/preprocess/filters.hpp"
#include "core/types/geometry.hpp"
#include "core/types/messages.hpp"
#include "core/types/time.hpp"
#include "core/util/status.hpp"

namespace rotolidar {

/// One point of a velodyne .bin (16 bytes on disk).
struct KittiPoint {
  float x_m = 0.f, y_m = 0.f, z_m = 0.f;  ///< Velodyne frame of the frame [m]
  float reflectance = 0.f;                ///< [0, 1] in KITTI's bins
};

/// Reads a whole .bin. Fails (naming the file) when it cannot be opened or its size is not a multiple of 16 bytes
/// (the message gives the offset of the trailing partial point). Non-finite values are kept as stored.
Status ReadKittiBin(const std::string& path, std::vector<KittiPoint>* points);
/// Writes `points` as a .bin (overwritten). Fails naming the file when it cannot be written.
Status WriteKittiBin(const std::string& path, const std::vector<KittiPoint>& points);

/// Reads / writes a per-point time file (velodyne_times/%06d.bin): float32 little-endian, seconds after the
/// frame's time. The reader fails naming the file when its size is not a multiple of 4 bytes (giving the offset
/// of the trailing partial value); non-finite values are kept as stored.
Status ReadKittiPointTimes(const std::string& path, std::vector<float>* times_s);
Status WriteKittiPointTimes(const std::string& path, const std::vector<float>& times_s);

/// sequence_info.txt: what a producer states about its sequence. One "key: value" a line, '#' starts a comment
/// line; keys are those below, each at most once; an unknown key, a repeated key, a scan_lines outside 1..256 or
/// a range_sigma_m that is not a finite number > 0 is an error naming file:line. Text values are kept as written
/// (trimmed).
struct KittiSequenceInfo {
  std::string sensor;       ///< e.g. "VLP-16"
  int scan_lines = 0;       ///< the sensor's scan lines (lasers) = rings per bin; 0 = not stated
  double range_sigma_m = 0.0;  ///< the sensor's range noise, 1 sigma [m]; 0 = not stated
  /// Rotor angle a rotary rig's sensor turns through per frame [deg]; 0 = no rotor (a fixed sensor, e.g. KITTI's
  /// own HDL-64E). The runner derives its keyframe policy from it, as the estimator does from calib.yaml.
  double rotor_deg_per_scan = 0.0;
  std::string point_order;  ///< how a bin orders its points
  std::string point_times;  ///< where the per-point times are, and their unit and origin
  std::string frame;        ///< what the "velodyne" frame of a bin is
  std::string deskew;       ///< how the points were motion-compensated
  std::string returns;      ///< which echoes of a multi-return sensor are in the bins
  std::string source;       ///< what the sequence was made from
};
Status ReadKittiSequenceInfo(const std::string& path, KittiSequenceInfo* info);
/// Writes the set fields (empty strings and zero numbers are left out) under a '#' header comment; a value with a
/// line break is an error.
Status WriteKittiSequenceInfo(const std::string& path, const KittiSequenceInfo& info);

using Matrix34d = Eigen::Matrix<double, 3, 4>;

/// calib_imu_to_velo.txt of KITTI's raw recordings: T_velo_imu. Lines "R: 9 numbers", "T: 3 numbers" (each exactly
/// once) and optionally "calib_time: TEXT"; blank lines are skipped. Another key, a missing one, a wrong count, a
/// non-number or an R that is not a rotation (within 1e-3) is an error naming file:line and the key.
struct KittiImuCalib {
  Pose3 T_velo_imu = Pose3::Identity();  ///< maps IMU-frame points into the Velodyne frame [m]
  std::string calib_time;                ///< as written; empty when absent
};
Status ReadKittiImuCalib(const std::string& path, KittiImuCalib* calib);
Status WriteKittiImuCalib(const std::string& path, const KittiImuCalib& calib);

/// calib.txt of an odometry sequence.
struct KittiCalib {
  /// P0..P3: projection matrices of cameras 0..3 (rectified) [px]; zero until set
  std::array<Matrix34d, 4> P = {Matrix34d::Zero(), Matrix34d::Zero(), Matrix34d::Zero(), Matrix34d::Zero()};
  Pose3 T_cam0_velo = Pose3::Identity();  ///< "Tr": Velodyne -> left grey camera (cam0) [m]
};

/// Reads calib.txt: lines "KEY: 12 numbers" with KEY one of P0 P1 P2 P3 Tr, each exactly once; blank lines are
/// skipped. Any other key, a missing key, a count other than 12, a non-number or a Tr whose rotation block is not
/// a rotation (|R^T R - I| > 1e-3) is an error naming file:line and the key.
Status ReadKittiCalib(const std::string& path, KittiCalib* calib);
Status WriteKittiCalib(const std::string& path, const KittiCalib& calib);

/// Reads a poses file: one pose a line, 12 numbers (row-major [R | t]), kept exactly as written (no
/// re-orthonormalisation; a rotation block farther than 1e-3 from a rotation is an error). Empty lines are allowed
/// only at the end (line k must be frame k). Errors name file:line and the field index.
Status ReadKittiPoses(const std::string& path, std::vector<Pose3>* poses);
Status WriteKittiPoses(const std::string& path, const std::vector<Pose3>& poses);

/// Reads times.txt: one finite, non-decreasing time [s] a line (empty lines only at the end).
Status ReadKittiTimeList(const std::string& path, std::vector<Seconds>* times);
Status WriteKittiTimeList(const std::string& path, const std::vector<Seconds>& times);

/// KITTI's pose convention from a trajectory of the Velodyne frame: T_cam0(0)_cam0(k) = Tr * T_velo(0)_velo(k) *
/// Tr^-1 with Tr = T_cam0_velo, and back. Tr^-1 is the general matrix inverse (KITTI's Tr is a rotation only to
/// ~1e-7), so the identity maps to the identity to round-off.
Pose3 VeloToCam0Pose(const Pose3& T_cam0_velo, const Pose3& T_velo0_velok);
Pose3 Cam0ToVeloPose(const Pose3& T_cam0_velo, const Pose3& T_cam0_0_cam0_k);

/// Where the files of one sequence are. Empty paths take the defaults named below.
struct KittiSequencePaths {
  std::string dir;         ///< the sequence folder: holds velodyne/ (required)
  std::string calib_path;  ///< default <dir>/calib.txt (required)
  std::string times_path;  ///< default <dir>/times.txt; when absent: nominal 10 Hz, t_k = 0.1 s * k
  std::string poses_path;  ///< default <dir>/poses.txt, else <dir>/../../poses/<name of dir>.txt; may be absent
  std::string imu_path;    ///< default <dir>/imu.csv; may be absent (then no IMU)
  std::string imu_calib_path;  ///< default <dir>/calib_imu_to_velo.txt; required when there is an IMU
};

/// An opened sequence: the frame list and the small files (bins are read one by one with ReadKittiBin).
struct KittiSequence {
  std::vector<int> frame_ids;           ///< numbers of velodyne/%06d.bin, ascending (may have gaps)
  std::vector<std::string> bin_paths;   ///< same order
  KittiCalib calib;
  std::string calib_path;
  std::vector<Seconds> times;           ///< by frame id (times[id]); size > the largest frame id
  bool nominal_times = false;           ///< no times file: times[id] = 0.1 s * id
  std::string times_path;               ///< empty when nominal
  std::vector<Pose3> poses;             ///< by frame id, KITTI convention (cam0); empty when there is no file
  std::string poses_path;               ///< empty when none
  /// Per-point time files, same order as bin_paths, when the sequence has a velodyne_times/ folder; else empty.
  std::vector<std::string> point_time_paths;
  KittiSequenceInfo info;               ///< from sequence_info.txt; default (nothing stated) without one
  std::string info_path;                ///< empty when there is no sequence_info.txt
  std::vector<ImuSample> imu;           ///< imu.csv's samples (times.txt's clock); empty when there is none
  std::string imu_path, imu_calib_path; ///< empty when there is no IMU
  KittiImuCalib imu_calib;              ///< T_velo_imu (identity when there is no IMU)
};

/// Lists velodyne/*.bin (a .bin whose name is not a frame number is an error; other files are ignored), reads
/// calib, times, poses and sequence_info.txt (optional). With a velodyne_times/ folder every bin needs its time
/// file there (a missing one is an error naming it).
/// A times or poses file with fewer lines than the largest frame id + 1 is an error (more lines are fine: the
/// bins may be a subset of the sequence). An explicitly given file that does not exist is an error. An IMU file
/// without calib_imu_to_velo.txt is an error (its frame would be unknown).
Status OpenKittiSequence(const KittiSequencePaths& paths, KittiSequence* sequence);

/// Writes sequence files in the dataset layout: <root>/sequences/<name>/{velodyne/, times.txt, calib.txt} and
/// <root>/poses/<name>.txt. Create the folders with CreateKittiDatasetFolders first.
struct KittiDatasetLayout {
  std::string root;
  std::string name = "00";
  std::string SequenceDir() const { return root + "/sequences/" + name; }
  std::string BinPath(int frame_id) const;  ///< <sequence>/velodyne/%06d.bin
  std::string PointTimesPath(int frame_id) const;  ///< <sequence>/velodyne_times/%06d.bin
  std::string InfoPath() const { return SequenceDir() + "/sequence_info.txt"; }
  std::string TimesPath() const { return SequenceDir() + "/times.txt"; }
  std::string CalibPath() const { return SequenceDir() + "/calib.txt"; }
  std::string PosesPath() const { return root + "/poses/" + name + ".txt"; }
};
/// Creates velodyne/ and poses/, and with point_times velodyne_times/ (then every bin needs its time file).
Status CreateKittiDatasetFolders(const KittiDatasetLayout& layout, bool point_times = false);

// ---------------------------------------------------------------------------------------------------------------
/// How a bin becomes ScanPoints (docs/kitti.md).
struct KittiScanConfig {
  /// Bins without per-point times: a drop of the counter-clockwise azimuth atan2(y, x) in [0, 360) larger than
  /// this between consecutive points of the bin starts a new scan line (the bins store the HDL-64E's 64 lines one
  /// after the other, each sweeping 0 -> 360 deg; within a line the azimuth steps back by at most ~7 deg,
  /// measured on KITTI 00) [deg].
  double line_break_deg = 180.0;
  /// Scan lines a bin should have; a bin with another count is reported (KittiScanStats), not rejected. 0 = the
  /// sequence's: sequence_info.txt's scan_lines, else the count found in the first frame used (bench/run).
  int expected_lines = 0;
  /// The head's revolution period [s] (10 Hz). Without per-point times: t_s = t_frame + period * azimuth / 360
  /// (ordering only); with them: azimuth = 360 * time / period (the head's sweep since the frame time).
  double scan_period_s = 0.1;
  bool Validate(std::string* error) const;
};

struct KittiScanStats {
  size_t num_input = 0;
  size_t num_nonfinite = 0;        ///< dropped (a non-finite coordinate, reflectance or point time)
  size_t num_lines = 0;            ///< scan lines found = rings assigned
  bool lines_from_times = false;   ///< lines split where the per-point time falls back (else: the azimuth)
  /// Azimuth split only: consecutive lines whose median elevation rises although lines must descend (top beam
  /// first): 0 when the line split is the HDL-64E's laser order. Not checked (0) for a split by time.
  size_t elevation_inversions = 0;
  std::vector<float> line_median_elevation_deg;  ///< by line, in stored order (top first), in the bin's frame
};

/// Converts one bin into ScanPoints of the frame at t_frame_s. p_base = the point (base = Velodyne frame);
/// range_m = |p|; azimuth_deg = atan2(y, x) in [0, 360), counter-clockwise from +x: the HDL-64E's sweep direction,
/// so it grows with firing time as LidarPoint::azimuth_deg does; intensity = 255 * reflectance; t_s as in
/// KittiScanConfig; ring = (lines - 1 - line index), so ring 0 is the lowest beam as for LidarPoint::ring.
/// Non-finite points are dropped. Fails only when more than 256 lines are found (the bin is not stored ring by
/// ring) or the config is invalid; *stats may be null.
Status KittiScanPoints(const std::vector<KittiPoint>& bin, Seconds t_frame_s, const KittiScanConfig& config,
                       std::vector<ScanPoint>* points, KittiScanStats* stats = nullptr);

/// The same for a bin with per-point times (velodyne_times/: point_times_s[i] = point i's time after
/// t_frame_s [s]), stored line by line, each line in firing order: a line ends where the time falls back. Then
/// t_s = t_frame_s + point time, azimuth_deg = 360 * point time / scan_period_s (mod 360: the head's sweep since
/// the frame time at the nominal rate; the sensor's own azimuth is not in the files) and the median-elevation
/// check is skipped (the line order is the producer's; a rotary rig's bins are in its base frame, where a line's
/// elevation has no order). Fails when the sizes differ, more than 256 lines are found or the config is invalid.
Status KittiScanPoints(const std::vector<KittiPoint>& bin, const std::vector<float>& point_times_s,
                       Seconds t_frame_s, const KittiScanConfig& config, std::vector<ScanPoint>* points,
                       KittiScanStats* stats = nullptr);

}  // namespace rotolidar
