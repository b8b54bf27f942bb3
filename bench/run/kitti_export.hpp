#pragma once
// `rotolidar export RECORDING --kitti OUT`: any recording folder as a KITTI odometry sequence, so other odometry
// tools (KISS-ICP, ...) run on our data. docs/kitti.md.
//
// One KITTI frame per VLP-16 head revolution (Vlp16Decoder + RevolutionSplitter, cut at azimuth 0; the partial
// first and last revolutions are dropped). KITTI bins hold a motion-compensated cloud in the sensor frame at the
// frame time; for a rotary rig the sensor moves on the base, so here "velodyne" = the BASE frame at the
// revolution's first point (the frame time): each point is placed at its own firing time and moved into it.
//   deskew from truth (recording has truth/): p_base0 = T_world_base(t0)^-1 * T_world_lidar(t) * p_lidar, both
//     interpolated from truth/base.tum and truth/lidar.tum (exact: rotor angle and carrier motion are both true);
//   deskew by the estimator (no truth/, or asked for): the Estimator's own rotary transform (encoder) and motion
//     compensation (EstimatorConfig::keep_deskewed), i.e. what the core itself believes.
// Files (KittiDatasetLayout): OUT/sequences/<name>/velodyne/%06d.bin (frame ids from 0), times.txt (rig clock
// [s] of each frame), calib.txt (P0..P3 = K [I | 0] of the rig's camera, Tr = T_cam_base: cam0 IS the rig's
// camera), and with truth OUT/poses/<name>.txt = Tr * T_base(0)_base(k) * Tr^-1 (KITTI's cam0 convention relative
// to the first frame). Reflectance = VLP-16 reflectivity / 255.
#include <functional>
#include <string>
#include <vector>

#include "core/io/kitti.hpp"
#include "core/io/vlp16.hpp"
#include "core/pipeline/estimator_config.hpp"

namespace rotolidar::bench {

enum class KittiDeskewSource { kAuto, kTruth, kEstimator };
/// "auto", "truth", "estimator" -> source; false otherwise.
bool ParseKittiDeskewSource(const std::string& name, KittiDeskewSource* out);

struct KittiExportOptions {
  std::string recording_dir;
  std::string out_dir;           ///< dataset root (sequences/, poses/ are created in it)
  std::string sequence = "00";   ///< sequence folder name
  /// Which echo a dual-return recording contributes (kStrongest or kLast); single-return recordings keep theirs.
  Vlp16ReturnFilter return_filter = Vlp16ReturnFilter::kStrongest;
  KittiDeskewSource deskew = KittiDeskewSource::kAuto;  ///< kAuto: truth when truth/ exists, else the estimator
  EstimatorConfig estimator;     ///< the estimator deskew only (keep_deskewed is forced on)
  bool Validate(std::string* error) const;  ///< false naming the field
};

struct KittiExportResult {
  std::string sequence_dir;          ///< where the bins went
  size_t frames = 0;
  size_t points = 0;                 ///< written over all bins
  size_t points_skipped = 0;         ///< no deskew possible (outside the truth's span, or NaN from the estimator)
  size_t bad_packets = 0;            ///< undecodable packets (skipped, counted)
  bool deskewed_with_truth = false;
  bool wrote_poses = false;
  std::vector<Seconds> times;        ///< as written to times.txt
  std::vector<Pose3> poses;          ///< as written to poses/<name>.txt (empty without truth)
  KittiCalib calib;                  ///< as written to calib.txt
};

/// Writes the sequence. Fails naming the file on unreadable input (recording, truth) or unwritable output, when
/// truth deskew is asked for without truth/, or when the recording holds no complete revolution.
Status ExportKitti(const KittiExportOptions& options, KittiExportResult* result,
                   const std::function<void(double)>& progress = nullptr);

}  // namespace rotolidar::bench
