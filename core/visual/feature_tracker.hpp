#pragma once
// The visual front end: point features tracked from camera frame to camera frame, as in the front ends of
// VINS-Mono (Qin, Li, Shen, TRO 2018) and LVI-SAM. The sliding window turns the tracks into inverse-depth landmarks.
//
// Method, per Track() call:
//  1. The BGR8 image is converted to grey and a Lucas-Kanade pyramid is built (cv::buildOpticalFlowPyramid; it is
//     kept for the next call, so each image's pyramid is built once).
//  2. The previous frame's features are tracked by pyramidal Lucas-Kanade (Lucas & Kanade 1981; Bouguet, "Pyramidal
//     implementation of the Lucas Kanade feature tracker", Intel 2000: cv::calcOpticalFlowPyrLK). A track is lost
//     when KLT reports failure or ends within border_px of the image edge. With a rotation hint (below) every
//     feature starts at its position predicted by the infinite homography (cv::OPTFLOW_USE_INITIAL_FLOW).
//  3. Forward-backward check (Kalal, Mikolajczyk, Matas, ICPR 2010): each survivor is tracked back into the
//     previous image, starting from the hint's inverse prediction (or from its own position without a hint, so the
//     backward pass never starts at the answer), and is rejected when it misses its start by more than
//     fb_threshold_px.
//  4. Outlier rejection: RANSAC on the essential matrix with Nister's 5-point solver (Nister, TPAMI 2004:
//     cv::findEssentialMat with cv::RANSAC) on the undistorted normalised coordinates of the previous and current
//     positions, identity camera matrix, threshold ransac_threshold_px / ((fx + fy) / 2) (OpenCV's test is the
//     Sampson distance). Skipped (all kept, stats.ransac_ran = false) below ransac_min_matches matches.
//     Pure rotation or a tiny baseline leaves E ill-conditioned (t ~ 0: every static point satisfies x2 ~ R x1 and
//     hence x2^T [t]x R x1 = 0 for any t). The inlier test still holds then: static points remain inliers; an
//     independently moving point is rejected unless its motion happens to lie along an epipolar line of the
//     (arbitrary) t RANSAC picked. E is used only as an inlier test here, never decomposed into a pose.
//  5. Spread (VINS-Mono's setMask): the surviving tracks are visited longest first (ties: lower id first) and a
//     track closer than min_distance_px to one already kept is dropped, so every pair of features is at least
//     min_distance_px apart.
//  6. New features fill up to max_features: Shi-Tomasi corners (Shi & Tomasi, "Good features to track", CVPR 1994:
//     cv::goodFeaturesToTrack) outside a disc of radius min_distance_px around every kept feature. With a grid
//     (grid_rows x grid_cols > 1) each cell is first topped up to its share max_features / cells, with the quality
//     level relative to the cell's strongest corner, so low-contrast regions get features too; a global pass then
//     fills what the cells left. Corners are at integer pixels (no sub-pixel refinement: KLT refines them on the next
//     frame, and the first position only anchors the track).
//
// Frames and units: pixel coordinates [px] with (0, 0) at the centre of the top-left pixel (OpenCV). The camera
// frame (docs/frames.md "cam") is x right, y down, z forward. Normalised coordinates are (x/z, y/z) on the z = 1
// plane of the camera frame, undistorted (cv::undistortPoints with up to 20 iterations: they reproject onto the
// pixels within 1e-6 px for k1 = -0.28 in the tests, where OpenCV's default 5 iterations leave up to 0.74 px).
// Naming rule of the project: T_a_b maps points from frame b into frame a.
//   Rotation hint: R_prev_cur = R_camprev_camcur maps points from the CURRENT camera frame into the PREVIOUS one,
//   p_prev = R_prev_cur * p_cur. From the gyro: R_prev_cur = R_cam_imu * R_imuprev_imucur * R_cam_imu^T, with
//   R_imuprev_imucur = ExpSO3(w_1 dt_1) * ExpSO3(w_2 dt_2) * ... (bias-corrected rates, earliest first) between
//   the two frames' mid-exposure times. A static point's bearing then moves as
//   b_cur ~ R_prev_cur^T * b_prev, i.e. pixel_cur ~ K R_prev_cur^T K^-1 pixel_prev on undistorted pixels; the
//   prediction is re-distorted before KLT.
//
// Determinism: the result is a function of the config, the frames and the hints only. cv::findEssentialMat with
// cv::RANSAC runs OpenCV's classic RANSACPointSetRegistrator, which seeds a local cv::RNG with a fixed value on
// every call (it does not draw from cv::theRNG(), and cv::setRNGSeed does not change it): the same matches in the
// same order (here: by id) give the same inlier set. This is OpenCV's behaviour (4.x), not an API guarantee; the
// tests pin it with cv::theRNG() perturbed between two trackers. The USAC methods would take an explicit seed
// (cv::UsacParams::randomGeneratorState) instead.
//
// Ownership: the tracker keeps no reference to the caller's image (it keeps the pyramid of its own grey copy).
// Thread safety: one FeatureTracker is not safe for concurrent calls; distinct trackers may run concurrently
// (OpenCV's own worker threads are used inside calcOpticalFlowPyrLK). Failure: a bad config, intrinsics, frame or
// hint is reported as ok = false with a message naming the field, never thrown, and leaves the tracker's state as it
// was. Cost: ~10 ms per 640x480 frame with 150 features on a shared 2-core machine (the tests print it), of which
// a first frame (grey, pyramid and detection only) takes ~8.5 ms.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"

namespace rotolidar::visual {

struct FeatureTrackerConfig {
  /// Features kept per frame. 150: VINS-Mono's default (MAX_CNT), enough landmarks for the sliding window.
  int max_features = 150;
  /// Minimum distance between any two features [px]. 30: VINS-Mono's default at 752x480; spreads 150 features
  /// over a 640x480 image (a hexagonal packing at 30 px holds ~390).
  double min_distance_px = 30.0;
  /// KLT window side [px] (odd, >= 3). 21: VINS-Mono's (a smaller window converges less far per level).
  int klt_window_px = 21;
  /// Highest 0-based pyramid level (0 = no pyramid). 3 (4 levels): VINS-Mono's. On the tests' texture plain KLT
  /// still holds all tracks at ~25 px of flow (3 deg of yaw at f = 462 px) and loses most beyond ~40 px (5 deg;
  /// 0 of 113 at 10 deg): at 30 Hz that is ~90 deg/s of rotation. Faster turns need the rotation hint (which kept
  /// 101 of 113 at 10 deg).
  int klt_max_level = 3;
  /// KLT iterations per level and its convergence step [px]. 30 and 0.01: VINS-Mono's criteria.
  int klt_max_iterations = 30;
  double klt_epsilon_px = 0.01;
  /// A track ending within this distance of the image edge is lost [px]. 1: VINS-Mono's BORDER_SIZE; the window
  /// is padded by the pyramid's border, so only positions off the image must be dropped.
  double border_px = 1.0;
  /// Forward-backward round-trip error above which a track is rejected [px]. 0.5: KLT converges to ~0.1 px (the
  /// tests' median error), so a correct track returns well within it; a track caught on a wrong patch does not
  /// (it rejected 125 of 127 wrong tracks of an unhinted 10 deg turn in the tests).
  double fb_threshold_px = 0.5;
  /// RANSAC inlier threshold on the Sampson distance [px] (converted to normalised units by (fx + fy) / 2).
  /// 1.0: VINS-Mono's F_THRESHOLD; KLT noise is ~0.1 px, an independently moving object moves by more.
  double ransac_threshold_px = 1.0;
  /// RANSAC confidence (0, 1) and iteration cap. 0.99 / 1000: VINS-Mono's confidence, OpenCV's cap.
  double ransac_confidence = 0.99;
  int ransac_max_iterations = 1000;
  /// RANSAC runs only with at least this many matches (>= 5, the 5-point minimum). 8: VINS-Mono's; fewer leave
  /// too few redundant points to tell an outlier from the model.
  int ransac_min_matches = 8;
  /// Shi-Tomasi quality level: corners weaker than this share of the strongest are ignored. 0.01: VINS-Mono's.
  double corner_quality = 0.01;
  /// Shi-Tomasi block size [px]. 3: OpenCV's default.
  int corner_block_px = 3;
  /// Detection grid (1 x 1 = none). With more cells every cell gets its share of new features even where the
  /// contrast is low; off by default, as in VINS-Mono (the min-distance mask already spreads the features).
  int grid_rows = 1;
  int grid_cols = 1;
  /// Pyramid level new corners are detected at (0: the full image), then refined to sub-pixel positions on the
  /// full image (cv::cornerSubPix, +-2 px window). 1 (half resolution) cuts Shi-Tomasi's ~7 ms over a 640 x 480
  /// frame to ~2 ms. At most klt_max_level.
  int detect_level = 1;

  /// True when every field is usable; otherwise false with a message naming the field in *error.
  bool Validate(std::string* error) const;
};

/// One tracked feature, as observed in the frame of the result that holds it.
struct TrackedFeature {
  uint64_t id = 0;  ///< unique for this tracker, assigned in increasing order, never reused (not by Reset either)
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();  ///< measured (distorted) pixel position [px]
  Eigen::Vector2d normalized = Eigen::Vector2d::Zero();  ///< undistorted (x/z, y/z) in the camera frame [-]
  int track_length = 1;  ///< frames observed so far, this one included (1 = detected in this frame)
  /// Pixel velocity (this position - the previous one) / (t - t_prev) [px/s]; zero for a new feature.
  Eigen::Vector2d velocity_pxps = Eigen::Vector2d::Zero();
  /// The same on the normalised coordinates [1/s] (what VINS-Mono's time-offset factor uses); zero when new.
  Eigen::Vector2d velocity_normalized_ps = Eigen::Vector2d::Zero();
};

/// Counts of one Track() call. previous = tracked + lost by KLT/border;
/// inliers = tracked - rejected_fb - rejected_ransac; total = inliers - rejected_crowded + new_features.
struct FeatureTrackStats {
  int previous = 0;          ///< features entering from the previous frame
  int tracked = 0;           ///< KLT converged and the position lies inside the border
  int rejected_fb = 0;       ///< failed the forward-backward check
  int rejected_ransac = 0;   ///< outliers of the essential-matrix RANSAC
  int inliers = 0;           ///< tracks that passed every check
  int rejected_crowded = 0;  ///< inliers dropped to keep min_distance_px (shorter tracks go first)
  int new_features = 0;      ///< detected in this frame
  int total = 0;             ///< features in the result
  bool ransac_ran = false;   ///< false: fewer than ransac_min_matches matches (or no E found): all were kept
  double time_ms = 0.0;      ///< wall time of the Track() call [ms]
};

struct FeatureTrackResult {
  bool ok = false;
  std::string message;  ///< why not ok (names the field); empty when ok
  Seconds t_s = 0.0;    ///< the frame's time
  std::vector<TrackedFeature> features;  ///< sorted by id (so the longest tracks come first)
  FeatureTrackStats stats;
};

class FeatureTracker {
 public:
  /// An invalid config is reported by every Track() call (ok = false, message "config: ...").
  explicit FeatureTracker(const FeatureTrackerConfig& config = FeatureTrackerConfig());

  /// Tracks the previous frame's features into `frame` and tops them up with new ones. `frame.image`: BGR8
  /// (CV_8UC3; CV_8UC1 grey is accepted too) of intrinsics.width_px x height_px; `frame.t_s` must be later than the
  /// previous accepted frame's. `R_prev_cur`: optional rotation from the current into the previous camera frame
  /// (see the header comment), a proper rotation matrix; unused on a first frame. When the image size changes,
  /// tracking restarts (all features are new; ids keep counting).
  FeatureTrackResult Track(const CameraFrame& frame, const CameraIntrinsics& intrinsics,
                           const std::optional<Eigen::Matrix3d>& R_prev_cur = std::nullopt);

  /// Drops every track and the previous image; the next frame starts fresh. Ids are not reused.
  void Reset();

  const FeatureTrackerConfig& config() const { return config_; }
  const std::vector<TrackedFeature>& features() const { return features_; }  ///< those of the last result
  uint64_t next_id() const { return next_id_; }

 private:
  std::vector<TrackedFeature> TrackPrevious(const std::vector<cv::Mat>& pyramid, const CameraIntrinsics& intrinsics,
                                            const std::optional<Eigen::Matrix3d>& R_prev_cur, double dt_s,
                                            FeatureTrackStats* stats) const;
  /// KLT of `from_px` from one pyramid into the other, starting at *to_px (same size; overwritten). Per-point status.
  std::vector<uchar> Klt(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                         const std::vector<cv::Point2f>& from_px, std::vector<cv::Point2f>* to_px) const;
  std::vector<int> RansacInliers(const std::vector<Eigen::Vector2d>& prev_normalized,
                                 const std::vector<Eigen::Vector2d>& cur_normalized,
                                 const CameraIntrinsics& intrinsics, FeatureTrackStats* stats) const;
  void Thin(std::vector<TrackedFeature>* features, FeatureTrackStats* stats) const;
  /// grey: the full image; pyramid: its buildOpticalFlowPyramid levels (with derivatives: level L at 2 L).
  void AddNewFeatures(const cv::Mat& grey, const std::vector<cv::Mat>& pyramid, const CameraIntrinsics& intrinsics,
                      std::vector<TrackedFeature>* features, FeatureTrackStats* stats);

  FeatureTrackerConfig config_;
  std::string config_error_;  ///< empty when the config is valid
  std::vector<TrackedFeature> features_;
  std::vector<cv::Mat> pyramid_;  ///< the previous frame's KLT pyramid (with derivatives); empty before the first
  Seconds t_prev_s_ = 0.0;
  uint64_t next_id_ = 0;
};

}  // namespace rotolidar::visual
