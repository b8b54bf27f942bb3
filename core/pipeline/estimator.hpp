#pragma once
// The estimator: sensor messages in, a trajectory of T_world_base and a dense map out. The seed's LiDAR-inertial
// core (LV-SLAM, Sensors 2025, Sec. 3), docs/estimator.md:
//   rotary transform (encoder) -> deskew (IMU preintegration) -> preprocess -> curvature features
//   -> feature scan-to-map (degeneracy-aware) -> sliding-window LiDAR-IMU fusion -> global voxel map
//
// Feed() every message in time order (LiDAR packets by capture time). Each completed VLP-16 revolution is one
// scan; Process() runs the pipeline on every scan whose encoder (and, once IMU samples arrive, IMU) coverage has
// arrived. ProcessDeskewedScan() is the entry for clouds that are already motion-compensated (KITTI).
//
// The world frame is the base frame at the first scan's start time (not levelled: the sliding window carries
// gravity expressed in this frame, estimated at IMU initialisation). Thread safety: none (one owner).
// Failure: a malformed packet is counted and reported by Feed; a scan whose registration fails still gets a pose
// (IMU prediction, or constant velocity without IMU) and reports registration.converged = false.
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "core/deskew/deskew.hpp"
#include "core/graph/loop_closer.hpp"
#include "core/wire/scan_splitter.hpp"
#include "core/wire/vlp16.hpp"
#include "core/pipeline/estimator_config.hpp"
#include "core/deskew/rotary.hpp"
#include "core/pipeline/free_space.hpp"
#include "core/pipeline/map_recheck.hpp"
#include "core/pipeline/vacated_screen.hpp"
#include "core/pipeline/voxel_map.hpp"
#include "core/types/trajectory.hpp"

namespace rotolidar {

/// Wall time of each pipeline stage for one scan [ms].
struct ScanTimings {
  double deskew_ms = 0.0;      ///< rotary transform + motion compensation
  double preprocess_ms = 0.0;  ///< range gate, SOR, voxel
  double features_ms = 0.0;    ///< curvature features
  double register_ms = 0.0;    ///< scan-to-map
  double fuse_ms = 0.0;        ///< IMU initialisation / sliding window
  double map_ms = 0.0;         ///< local feature map + global voxel map
  double total_ms = 0.0;       ///< the whole ProcessScan
};

/// Feature counts of one scan (sizes of the FeatureSet clouds).
struct FeatureCounts {
  size_t edge = 0, planar = 0, less_sharp = 0, less_flat = 0;
};

/// Scan-to-map outcome (ScanToMapResult, without the matrices).
struct RegistrationSummary {
  bool attempted = false;  ///< false for the first scan (it defines the map) or too few features
  bool converged = false;
  bool remapped = false;   ///< degenerate: the solve ran again on the well-observed subspace
  int iterations = 0;      ///< correspondence rebuilds
  int solver_iterations = 0;
  int neighbour_searches = 0;  ///< map kNN searches (ScanToMapResult::neighbour_searches)
  int edge_inliers = 0, planar_inliers = 0;
  double initial_cost = 0.0, final_cost = 0.0;  ///< [m^2]
  double rmse_m = 0.0;
  Vector6d hessian_eigenvalues = Vector6d::Zero();  ///< plain eigenvalues of J^T J, ascending [m^0 .. mixed]
  std::string message;     ///< why it failed; empty on success
};

/// Degeneracy of the scan's registration (core/registration/degeneracy.hpp).
struct DegeneracyRecord {
  bool degenerate = false;
  Vector6d eigenvalues = Vector6d::Zero();  ///< generalised lambda, ascending (dimensionless)
  int num_degenerate = 0;                   ///< directions below DegeneracyConfig::min_eigenvalue
  /// Degenerate directions, unit, tangent [dt (world); dtheta (world)] of T_world_base.
  std::vector<Vector6d> directions;
  /// Largest |component| over the degenerate directions, per tangent axis [tx ty tz rx ry rz] (0 when none):
  /// which world axes the LiDAR did not observe (the IMU holds them).
  Vector6d axis_weight = Vector6d::Zero();
};

/// What happened to one scan.
struct ScanReport {
  Seconds t_start_s = 0.0, t_end_s = 0.0;
  size_t num_points = 0;          ///< decoded points in the revolution
  size_t num_registered = 0;      ///< points after preprocessing (the feature extractor's input)
  size_t num_rotor_fallback = 0;  ///< points placed with the uniform-rotation model (no encoder bracket)
  size_t num_motion_extrapolated = 0;  ///< points outside the motion table's span (held at its end)
  FeatureCounts features;
  RegistrationSummary registration;
  DegeneracyRecord degeneracy;
  bool imu_initialized = false;   ///< the sliding window ran for this scan
  bool imu_deskew = false;        ///< carrier motion came from the IMU (false: constant velocity / none)
  bool held_static = false;       ///< static start: the IMU was still, the pose was held (no registration)
  /// The window's rotor-angle offset estimate after this scan [rad] (window.estimate_rotor_offset; else 0),
  /// removed from the encoder angles of the scans that follow.
  double rotor_offset_rad = 0.0;
  /// The window's IMU time-offset estimate after this scan [s]: its correction of calib.yaml's imu_time_offset_s
  /// (IMU stamp = rig time + calib's offset + this; window.estimate_time_offset; else 0), removed from the stamps
  /// of the IMU samples that follow.
  double imu_time_offset_s = 0.0;
  bool keyframe = false;          ///< the scan's features went into the local map (UpdateMap)
  /// Free-space test (core/pipeline/free_space.hpp): keyframe features that earlier scans saw through (kept out
  /// of the local map), and the dense-map points released at this scan (those of the scan delay_s earlier):
  /// how many were tested and how many were dynamic (kept out of the dense map), and how many dense-map points
  /// this scan saw through again (free_space.recheck_s; taken out of the map).
  size_t num_dynamic_features = 0;
  /// Scan-side features (edge + planar) dropped before registration because earlier scans saw through where
  /// they stand at the predicted pose (free_space.screen_scan_features).
  size_t num_moving_scan_features = 0;
  /// Of those, the ones dropped because they stand near a place the present scan sees vacated
  /// (free_space.vacated_radius_m: objects moving with the rig).
  size_t num_vacated_features = 0;
  /// The vacated screen would have dropped more than free_space.vacated_max_share of the features (the prediction
  /// looked off), so it dropped none.
  bool vacated_valve = false;
  FreeSpaceCounts map_free_space;
  size_t map_points = 0;    ///< points in the dense map after this scan (its memory: ~24 B each plus the index)
  VisualScanReport visual;  ///< the camera path (config.visual.enabled; zeros otherwise)
  ScanTimings timings;
  Pose3 T_world_base = Pose3::Identity();  ///< at t_start_s
  Eigen::Vector3d v_world_mps = Eigen::Vector3d::Zero();  ///< imu origin velocity from the window, world [m/s] (0 before IMU init)
  Eigen::Vector3d bias_gyro_radps = Eigen::Vector3d::Zero();  ///< the window's gyro bias estimate, imu frame (0 before init)
  Eigen::Vector3d bias_accel_mps2 = Eigen::Vector3d::Zero();  ///< the window's accelerometer bias estimate, imu frame
  /// Only with EstimatorConfig::keep_deskewed: the decoded points (lidar frame, with t_s) and, same size and
  /// order, each point deskewed into the base frame at t_start_s (NaN where it was not deskewed).
  std::vector<LidarPoint> deskew_source;
  std::vector<Eigen::Vector3f> deskewed_base;
};

class Estimator {
 public:
  /// `calib` must be valid; `config` must Validate (both ROTOLIDAR_CHECKed).
  Estimator(const RigCalib& calib, const EstimatorConfig& config);

  /// The configuration in use, resolved against the calibration (features.range_sigma_m from calib.yaml).
  const EstimatorConfig& config() const { return config_; }
  ~Estimator();

  void Feed(const EncoderSample& sample);
  void Feed(const ImuSample& sample);
  /// Takes a data or position packet. Data packets pass a short reorder window first (config.packet_order:
  /// ~50 ms of data is held; duplicates, late and wild-stamped packets are dropped and counted), then are decoded.
  /// A malformed packet is reported and skipped (no points lost silently: the Status says which field at which
  /// offset; with reordering the packet reported may be an earlier one that this call released).
  Status Feed(const LidarPacket& packet);
  /// A camera frame (frames in time order, the recording's clock): tracked when config.visual.enabled (every
  /// frame), and kept for the loop closer's visual stage 1 when it has a vocabulary (about one frame per
  /// max_camera_offset_s, the last second of them); otherwise dropped unread. The image is shared, not copied.
  void Feed(const CameraFrame& frame);
  /// The same for a frame on disk: decoded only when kept; the tracker's frames are decoded in its thread
  /// (VisualConfig::track_in_thread). An unreadable image is reported and skipped.
  void Feed(const CameraFrameRef& ref);
  /// Whether Feed would keep a frame at t_s (a player can skip decoding the others).
  bool WantsCameraFrame(Seconds t_s) const;
  /// Processes every ready scan; returns their reports (in time order).
  std::vector<ScanReport> Process();
  /// Complete revolutions waiting for Process (for their encoder / IMU coverage, or for the caller).
  size_t pending_scans() const { return pending_scans_.size(); }
  /// A live caller that falls behind drops the oldest waiting revolutions, keeping the newest `keep`: whole scans
  /// only, never part of one (the IMU keeps bridging the gap). Returns how many were dropped.
  size_t DropPendingScans(size_t keep);
  /// End of data: flushes the partial last revolution and processes everything left.
  std::vector<ScanReport> Finish();

  /// Points already in the base frame at t_s, motion-compensated; skips rotary transform and deskew.
  /// LiDAR-only (no IMU factor) when no IMU samples were fed. Rings may number up to 256 (KITTI: 64); range_m
  /// must be the point's sensor range (the range gate uses it). Scans must come in time order.
  ScanReport ProcessDeskewedScan(Seconds t_s, std::vector<ScanPoint> points);
  /// Points in the base frame at their own times p.t_s >= t_s (a fixed LiDAR's raw revolution, e.g. a KITTI bin
  /// with per-point times): deskewed into the base frame at t_s like ProcessScan (IMU motion once initialised,
  /// else the last two poses' constant twist), then processed as ProcessDeskewedScan. No rotary transform. Feed
  /// the IMU up to the last point's time first. Scans must come in time order.
  ScanReport ProcessTimedScan(Seconds t_s, std::vector<ScanPoint> points);

  const Trajectory& trajectory() const { return trajectory_; }  ///< T_world_base at each scan start
  /// Dense map of deskewed points [world]. With the free-space test on, a scan's points enter it
  /// free_space.delay_s later (or at Finish / FlushMap).
  const VoxelMap& map() const { return dense_map_; }
  /// Hands the points still waiting for the free-space test to the dense map (Finish does this; callers of
  /// ProcessDeskewedScan / ProcessTimedScan call it after their last scan). Returns what the test did.
  FreeSpaceCounts FlushMap();
  /// The loop closer (config.loop_closure.enabled), or null. It runs beside the odometry: trajectory() and map()
  /// stay the odometry's; its Correct() / CorrectedMap() give the loop-closed ones (final after Finish()).
  const graph::LoopCloser* loop_closer() const { return loop_closer_.get(); }
  /// The same, for set-up before the first scan (LoopCloser::LoadVocabulary).
  graph::LoopCloser* loop_closer() { return loop_closer_.get(); }
  /// Waits for the loop closer to process every keyframe handed to it (Finish does this; callers of
  /// ProcessDeskewedScan / ProcessTimedScan call it after their last scan). No-op without loop closure.
  void FinishLoopClosure();
  size_t bad_packets() const { return bad_packets_; }
  /// What putting the data packets into timestamp order repaired or dropped (config.packet_order).
  const PacketOrderCounts& packet_order_counts() const { return orderer_.counts(); }
  bool imu_initialized() const;

 private:
  struct Prediction;
  Status DecodeOrdered();

  ScanReport ProcessScan(const LidarScan& scan);
  ScanReport ProcessBaseFrameScan(Seconds t_s, std::vector<ScanPoint> points, bool deskew);
  /// The shared back half: preprocess -> features -> register -> fuse -> map.
  void ProcessCloud(Seconds t_s, std::vector<ScanPoint> points, const Prediction& prediction, ScanReport* report);
  std::vector<ScanPoint> Deskew(const LidarScan& scan, const Prediction& prediction, ScanReport* report);
  /// Preprocess + features; keeps the preprocessed points in preprocessed_ (the dense map's input).
  FeatureSet ExtractScanFeatures(Seconds t_s, std::vector<ScanPoint> points, ScanReport* report);
  /// Drops the scan-side edge / planar features that earlier scans saw through at the guess (moving objects)
  /// once the IMU or, without it, the LiDAR-only velocity window predicts the pose (free_space.screen_scan_features),
  /// and, on the IMU's prediction only, those near places the recent scans' features vacated (objects moving with
  /// the rig; unscreened_base: the scan's features before any screen, RegistrationFeatures); counts them.
  void ScreenMovingFeatures(Seconds t_s, const Pose3& T_world_base_guess, const Eigen::Matrix3Xf& unscreened_base,
                            FeatureSet* features, ScanReport* report);
  /// Scan-to-map from the guess; *information_base = the LiDAR factor's information (zero: no usable result).
  bool HoldStaticStart(ScanReport* report);
  Pose3 Register(const FeatureSet& features, const Pose3& T_world_base_guess, ScanReport* report,
                 Matrix6d* information_base);
  /// LiDAR pose + IMU in the sliding window (or LiDAR-only before initialisation / without IMU).
  Pose3 Fuse(Seconds t_s, const Pose3& T_world_base_lidar, const Matrix6d& information_base,
             const Prediction& prediction, ScanReport* report);
  void UpdateMap(Seconds t_s, const FeatureSet& features, const Pose3& T_world_base, ScanReport* report);
  void HandKeyframeToLoopCloser(Seconds t_s, const Pose3& T_world_base);
  /// The scan's points (or, with the free-space test, those of the scan delay_s ago) into the dense map.
  FreeSpaceCounts AddToDenseMap(Seconds t_s, const Pose3& T_world_base, bool flush);
  /// MapRecheck's verdict of the newest image on the dense map's recent points: removes them; returns how many.
  size_t RecheckDenseMap(Seconds t_s);

  /// The motion prior for a scan spanning [t0_s, t1_s].
  Prediction Predict(Seconds t0_s, Seconds t1_s) const;
  Prediction PredictFromWindow(Seconds t0_s, Seconds t1_s) const;
  Prediction PredictConstantVelocity(Seconds t0_s, Seconds t1_s) const;
  /// After a scan's pose is in trajectory_: the pose its registration measured best (measured_poses_).
  void RecordMeasuredPose(Seconds t0_s, Seconds t1_s, const MotionTable* applied);
  void TryInitializeImu();
  bool StartWindow(const Eigen::Vector3d& gravity_world_mps2, const NavState& state);
  void DropOldData(Seconds t_s);

  RigCalib calib_;
  EstimatorConfig config_;
  PacketOrderer orderer_;
  std::vector<LidarPacket> ordered_;  // released by orderer_, waiting to be decoded
  Vlp16Decoder decoder_;
  RevolutionSplitter splitter_;
  RotorAngleInterpolator rotor_;
  std::vector<ImuSample> imu_;  ///< time-ordered, stamps in rig time; trimmed as scans are processed
  double imu_time_offset_s_ = 0.0;  ///< removed from every IMU stamp fed after calib's (window's estimate; else 0) [s]
  std::deque<LidarScan> pending_scans_;
  std::vector<LidarPoint> packet_points_;
  LocalMap local_map_;
  VoxelMap dense_map_;
  std::unique_ptr<FreeSpaceFilter> free_space_;  ///< null when config.free_space.enabled is false
  std::unique_ptr<MapRecheck> map_recheck_;  ///< null without free_space_ or with free_space.recheck_s 0
  /// null without free_space_, with free_space.screen_scan_features false, free_space.vacated_radius_m 0 or
  /// use_imu false (it runs on the IMU's prediction only)
  std::unique_ptr<VacatedScreen> vacated_;
  std::vector<size_t> map_kept_, map_removed_;  ///< AddToDenseMap's buffers (map indices), kept for their memory
  std::unique_ptr<graph::LoopCloser> loop_closer_;  ///< null when config.loop_closure.enabled is false
  std::unique_ptr<VisualFrontEnd> visual_;  ///< null when config.visual.enabled is false
  std::deque<CameraFrame> camera_frames_;  ///< the last second of kept frames (the loop closer's images)
  std::unique_ptr<SlidingWindow> window_;  ///< created at IMU initialisation (its gravity is in the world frame)
  Trajectory trajectory_;
  /// Mid-scan poses for the constant-velocity prediction: the last two (with use_imu false: those of the last
  /// lidar_only_velocity_window_s, at least two).
  std::deque<StampedPose> measured_poses_;
  std::vector<Pose3> init_poses_imu_;      ///< T_world_imu of the LiDAR-only scans before IMU initialisation
  std::vector<Seconds> init_times_s_;
  std::vector<ScanPoint> preprocessed_;    ///< the current scan's preprocessed points (base at scan start)
  int scans_since_keyframe_ = 0;
  bool static_start_ = true;  ///< every scan so far was still (EstimatorConfig::hold_static_start)
  size_t bad_packets_ = 0;
};

}  // namespace rotolidar
