#pragma once
// `rotolidar export RECORDING --kitti OUT`: any recording folder as a KITTI odometry sequence, so other odometry
// tools (KISS-ICP, ...) run on our data. docs/kitti.md.
//
// One KITTI frame per VLP-16 head revolution (Vlp16Decoder + RevolutionSplitter, cut at azimuth 0; the partial
// first and last revolutions are dropped). KITTI bins hold a motion-compensated cloud in the sensor frame at the
// frame time; for a rotary rig the sensor moves on the base, so here "velodyne" = the BASE frame at the
// revolution's first point (the frame time): each point is placed at its own firing time and moved into it.
//   deskew by the estimator (the default): the Estimator's own rotary transform (encoder) and motion
//     compensation (EstimatorConfig::keep_deskewed), i.e. what the core itself believes;
//   deskew from truth (only when asked for; needs truth/): p_base0 = T_world_base(t0)^-1 * T_world_lidar(t) *
//     p_lidar, both interpolated from truth/base.tum and truth/lidar.tum (exact: rotor angle and carrier motion
//     are both true, so another odometry run on it gets an input no real rig gives).
// Files (KittiDatasetLayout): OUT/sequences/<name>/velodyne/%06d.bin (frame ids from 0; points ring by ring, top
// ring first, each ring in firing order), velodyne_times/%06d.bin (per point, same order: float32 [s] after the
// frame time), times.txt (rig clock [s] of each frame = its first return), calib.txt (P0..P3 = K [I | 0] of the
// rig's camera, Tr = T_cam_base: cam0 IS the rig's camera), sequence_info.txt (sensor, scan_lines 16, point
// order, frame, which deskew, which echo, the source), and with truth OUT/poses/<name>.txt = Tr * T_base(0)_base(k)
// * Tr^-1 (KITTI's cam0 convention relative to the first frame). Reflectance = VLP-16 reflectivity / 255.
#include <functional>
#include <string>
#include <vector>

#include "core/io/kitti.hpp"
#include "core/wire/vlp16.hpp"
#include "core/pipeline/estimator_config.hpp"

namespace rotolidar::bench {

enum class KittiDeskewSource { kEstimator, kTruth };
/// "estimator", "truth" -> source; false otherwise.
bool ParseKittiDeskewSource(const std::string& name, KittiDeskewSource* out);
/// One line saying which deskew and what it means, as sequence_info.txt and the CLI state it.
std::string KittiDeskewDescription(KittiDeskewSource source);

struct KittiExportOptions {
  std::string recording_dir;
  std::string out_dir;           ///< dataset root (sequences/, poses/ are created in it)
  std::string sequence = "00";   ///< sequence folder name
  /// Which echo a dual-return recording contributes (kStrongest or kLast); single-return recordings keep theirs.
  Vlp16ReturnFilter return_filter = Vlp16ReturnFilter::kStrongest;
  KittiDeskewSource deskew = KittiDeskewSource::kEstimator;  ///< kTruth must be asked for (needs truth/)
  EstimatorConfig estimator;     ///< the estimator deskew only (keep_deskewed is forced on)
  bool Validate(std::string* error) const;  ///< false naming the field
};

struct KittiExportResult {
  std::string sequence_dir;          ///< where the bins went
  size_t frames = 0;
  size_t points = 0;                 ///< written over all bins
  size_t points_skipped = 0;         ///< no deskew possible (outside the truth's span, or NaN from the estimator)
  size_t bad_packets = 0;            ///< undecodable packets (skipped, counted)
  KittiDeskewSource deskew = KittiDeskewSource::kEstimator;  ///< as used (= the option)
  bool deskewed_with_truth = false;  ///< deskew == kTruth
  bool wrote_poses = false;
  std::string info_path;             ///< sequence_info.txt (says which deskew was used)
  std::vector<Seconds> times;        ///< as written to times.txt
  std::vector<Pose3> poses;          ///< as written to poses/<name>.txt (empty without truth)
  KittiCalib calib;                  ///< as written to calib.txt
};

/// Writes the sequence. Fails naming the file on unreadable input (recording, truth) or unwritable output, when
/// truth deskew is asked for without truth/, or when the recording holds no complete revolution.
Status ExportKitti(const KittiExportOptions& options, KittiExportResult* result,
                   const std::function<void(double)>& progress = nullptr);

}  // namespace rotolidar::bench
