#pragma once
// The visual half of the sliding window (seed paper "LV-SLAM", Sec. 3.3; VINS-Mono's FeatureManager and its
// marginalisation, as LVI-SAM uses them): inverse-depth landmarks anchored in the camera of their first window
// state, their reprojection factors (core/visual/reprojection_factor.hpp) against the window's pose blocks, and
// the terms that fold them into the marginalisation prior when their anchor state leaves the window.
//
// Life of a landmark (one tracked feature, keyed by the tracker's id):
//   - created at the first window state that observes it (its anchor), with the inverse depth of its LiDAR
//     depth (LVI-SAM's depth association) when the observation carries one, else of a triangulation from later
//     observations, else of config.initial_depth_m (VINS-Mono's 5 m);
//   - enters the problem once seen in at least min_observations window states (one reprojection factor per
//     observation after the anchor's, on {anchor pose, observing pose, inverse depth}, with a Huber loss); a
//     LiDAR-depth landmark's inverse depth also gets a prior from that depth (or, with fix_lidar_depth, is held
//     constant as LVI-SAM does);
//   - after each solve, dropped when it lies behind a camera, nearer than min_depth_m, or any of its observations
//     reprojects farther than max_reprojection_px (VINS-Mono's removeFailures / outlier rejection);
//   - when its anchor state is marginalised, its factors and inverse depth are marginalised with it (TermsOf);
//     a feature still tracked afterwards starts a new landmark at its next observation.
//
// The camera's weight (adaptive_sigma): after each solve the pixel sigma is re-estimated from the window's own
// reprojection residuals (a robust variance-component estimate, Foerstner's reweighting of one observation group:
// sigma = median |r| / sqrt(2 ln 2), the median of a 2-D Gaussian residual's norm), smoothed, and held in
// [pixel_sigma_px, max_pixel_sigma_px]; the next solve whitens with it. A blurred, noisy or badly timed camera
// thus loses weight as a whole while a good one keeps its nominal weight. The outlier gate stays in pixels:
// widening it with the sigma kept the poor camera's worst tracks and made the corridor test's drift worse than
// the IMU's alone (tests/core/backend/visual_window_test.cpp). The gate truncates the residuals the estimate
// sees, so a poor camera's sigma reads low (4 px of noise gives ~3 px): a weight, not a calibration.
//
// The camera's time offset (estimate_time_offset; VINS-Mono's online td): t_imu = t_cam + td. Each observation
// arrives moved to its state's time with the td estimate of that moment (td_s) along its tracked velocity; the
// factors (ReprojectionTimeOffsetFactor) correct it by (td - td_s) * velocity, with td one block shared by the
// window, a Gaussian prior of time_offset_prior_sigma_s around calib's value (0) in every solve, and the
// information of marginalised landmarks carried in the window's prior.
//
// Frames and units: observations are undistorted normalised coordinates (x/z, y/z) in the camera at the window
// state's time [1]; pose blocks are T_world_imu (core/imu/imu_factor.hpp); T_imu_cam from RigCalib
// (CameraExtrinsic); depths along the camera's optical axis [m]; pixel quantities through focal_px.
// States are identified by the address of their pose block (stable: the window keeps states behind pointers).
// Ownership: the landmarks own their inverse-depth blocks, factors and loss; the window owns the pose blocks.
// Thread safety: none; the window's owner calls everything. Failure: bad observations (non-finite) are skipped and
// counted; an invalid config is a programmer error (ROTOLIDAR_CHECK, Validate first).
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <Eigen/Core>

#include "core/backend/pose_factors.hpp"
#include "core/types/geometry.hpp"
#include "core/visual/reprojection_factor.hpp"

namespace rotolidar {

struct VisualWindowConfig {
  /// Reprojection noise [px]: KLT's sub-pixel error plus the image-to-state time alignment; VINS-Mono whitens
  /// with 1.5 px (FOCAL_LENGTH / 1.5).
  double pixel_sigma_px = 1.5;
  /// Huber threshold on the whitened residual [sigmas] (VINS-Mono: HuberLoss(1.0)).
  double huber_sigmas = 1.0;
  /// A landmark enters the problem when seen in this many window states (2: the anchor and one more).
  int min_observations = 2;
  /// Landmarks nearer than this [m] (or behind a camera) are dropped after each solve; farther than
  /// max_depth_m they carry rotation only and are not created from a LiDAR depth.
  double min_depth_m = 0.3;
  double max_depth_m = 80.0;
  /// After a solve, a landmark whose observation reprojects farther than this [px] is dropped (3 sigma at the
  /// default 1.5 px is 4.5 px; 5 px leaves the Huber loss to weigh the rest).
  double max_reprojection_px = 5.0;
  /// Depth of a landmark with neither a LiDAR depth nor a triangulation [m] (VINS-Mono's INIT_DEPTH).
  double initial_depth_m = 5.0;
  /// A LiDAR depth d [m] enters as a prior on the landmark's inverse depth with the depth sigma
  /// lidar_depth_sigma_m + lidar_depth_sigma_per_m * d (range noise plus the ray-plane association's error,
  /// growing with range), i.e. sigma_rho = sigma_d / d^2. A free depth would let the camera trade it against the
  /// poses (the clean street's 60 s: 1.8 m ATE instead of 0.09 m); the prior keeps it while letting a slightly
  /// wrong association give way (0.09 -> 0.05 m there).
  double lidar_depth_sigma_m = 0.03;
  double lidar_depth_sigma_per_m = 0.01;
  /// Hold LiDAR-depth landmarks' inverse depth constant instead (LVI-SAM's choice).
  bool fix_lidar_depth = false;
  int max_landmarks = 400;  ///< new observations are ignored beyond this many live landmarks
  /// Re-estimate the pixel sigma from the residuals after each solve (see above); off: pixel_sigma_px always.
  bool adaptive_sigma = true;
  /// The largest sigma the camera is given [px]: at 10 px its factors weigh 1/44 of the nominal 1.5 px ones.
  double max_pixel_sigma_px = 10.0;
  /// Weight of the newest estimate in the smoothed sigma (exponential smoothing of log sigma), in (0, 1].
  double sigma_smoothing = 0.3;
  /// Fewer residuals than this leave the sigma unchanged (a median of a handful is not an estimate).
  int min_residuals_for_sigma = 30;
  /// Estimate the camera's time offset td online (see above); off: td = 0 (calib.yaml's clock model).
  bool estimate_time_offset = false;
  /// Prior sigma of td around 0 [s]: 20 ms covers an unsynchronised consumer camera's latency.
  double time_offset_prior_sigma_s = 0.02;
  bool Validate(std::string* error) const;
};

/// One feature seen in one window state.
struct VisualObservation {
  uint64_t feature_id = 0;
  Eigen::Vector2d normalized = Eigen::Vector2d::Zero();  ///< undistorted, at the state's time (moved with td_s)
  double lidar_depth_m = 0.0;  ///< depth along the optical axis from the LiDAR [m]; <= 0 or NaN: none
  Eigen::Vector2d velocity_normalized_ps = Eigen::Vector2d::Zero();  ///< tracked velocity [1/s] (for td)
  double td_s = 0.0;  ///< the time offset `normalized` was moved with [s] (VisualLandmarks::time_offset_s())
};

struct VisualLandmarkStats {
  int live = 0;            ///< landmarks held
  int in_problem = 0;      ///< landmarks with factors in the last problem
  int with_lidar_depth = 0;
  int factors = 0;         ///< reprojection factors in the last problem
  int rejected_total = 0;  ///< landmarks dropped by RejectOutliers so far
  int skipped_total = 0;   ///< non-finite observations and those over max_landmarks
  double sigma_px = 0.0;   ///< the pixel sigma the next solve whitens with [px]
  double residual_median_px = 0.0;  ///< median reprojection error of the last solve's factors [px]
  double time_offset_s = 0.0;       ///< td estimate [s] (0 unless estimate_time_offset)
};

class VisualLandmarks {
 public:
  /// focal_px > 0 (the camera's mean focal length) and a valid config are checked (ROTOLIDAR_CHECK).
  VisualLandmarks(const VisualWindowConfig& config, const Pose3& T_imu_cam, double focal_px);
  ~VisualLandmarks();
  VisualLandmarks(const VisualLandmarks&) = delete;
  VisualLandmarks& operator=(const VisualLandmarks&) = delete;

  /// The observations of the window state whose pose block is `pose` (its current value is the state's
  /// estimate). A feature without a landmark starts one anchored here.
  void AddObservations(const double* pose, const std::vector<VisualObservation>& observations);
  /// Adds the inverse-depth blocks and factors of every landmark seen in >= min_observations states. The pose
  /// blocks must already be in `problem` (with their manifold). Returns the number of factors added.
  int AddToProblem(ceres::Problem* problem);
  /// After a solve: drops landmarks behind a camera, too near, or reprojecting beyond max_reprojection_px, then
  /// re-estimates the sigma (adaptive_sigma).
  int RejectOutliers();
  /// Marginalisation terms of the landmarks anchored at `pose` (their factors in the last problem), with their
  /// inverse-depth blocks appended to *dropped. Call before RemoveState(pose).
  std::vector<MarginalizationTerm> TermsOf(const double* pose, std::vector<const double*>* dropped);
  /// Forgets a state leaving the window: its landmarks and every observation made in it.
  void RemoveState(const double* pose);
  void Clear();

  bool HasLandmark(uint64_t feature_id) const { return landmarks_.count(feature_id) > 0; }
  /// The camera's time offset td estimate [s] (t_imu = t_cam + td): new observations should be moved with it.
  double time_offset_s() const { return td_s_[0]; }
  VisualLandmarkStats stats() const;
  /// World positions [m] of the landmarks the last problem estimated (for tests and maps); needs the anchor pose
  /// blocks alive.
  std::vector<std::pair<uint64_t, Eigen::Vector3d>> LandmarkPositions() const;  ///< (feature id, p_world)

 private:
  struct Observation;
  struct Landmark;
  bool InFrontEverywhere(const Landmark& l) const;
  /// An observation corrected to the current td (unchanged without estimate_time_offset).
  Eigen::Vector2d Corrected(const Observation& o) const;
  std::unique_ptr<ceres::CostFunction> MakeFactor(const Landmark& l, const Observation& o) const;
  std::vector<double*> FactorBlocks(Landmark& l, const Observation& o);
  /// Appends the reprojection error [px] of each factor of l; returns the largest (0 without factors).
  double ReprojectionErrorsPx(const Landmark& l, std::vector<double>* errors_px) const;
  void Triangulate(Landmark* l) const;
  void UpdateSigma(std::vector<double>* residuals_px);

  VisualWindowConfig config_;
  Pose3 T_imu_cam_;
  double focal_px_;
  Eigen::Matrix2d sqrt_information_;     ///< whitening at the nominal pixel_sigma_px
  double sigma_px_ = 0.0;                 ///< current pixel sigma (>= pixel_sigma_px)
  double loss_sigma_px_ = 0.0;            ///< the sigma loss_ was built for
  std::unique_ptr<ceres::LossFunction> loss_;  ///< Huber at sigma_px_ on residuals whitened at the nominal sigma
  std::map<uint64_t, std::unique_ptr<Landmark>> landmarks_;  ///< by feature id (stable addresses)
  double td_s_[kTimeOffsetBlockSize] = {0.0};  ///< the td block (kept across Clear: a property of the rig)
  std::unique_ptr<ceres::CostFunction> td_prior_;  ///< ScalarPrior on td
  VisualLandmarkStats stats_;
};

}  // namespace rotolidar
