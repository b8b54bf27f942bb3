#pragma once
// The estimator's camera path (seed paper "LV-SLAM", Sec. 3.3; LVI-SAM's visual-inertial subsystem): every camera
// frame is tracked (core/visual/feature_tracker.hpp, KLT at the camera's rate), and each window state takes the
// tracked frame nearest its time as observations of landmarks (core/backend/visual_landmarks.hpp). A feature
// that starts a landmark gets its depth from the LiDAR points of the last depth_cloud_s (one rotor turn of a
// rotary rig covers the camera's view) when they give one (core/visual/feature_depth.hpp), as LVI-SAM does.
//
// Time: the image's mid-exposure time t_img (+ the camera's time offset td, 0 unless the landmarks estimate it)
// and the state's time t_s differ by up to half a frame period; each observation is moved to t_s along the
// feature's tracked velocity on the normalised plane (VINS-Mono's time-offset model).
// Frames: T_world_base estimates of the estimator; RigCalib's T_base_cam; observations are undistorted
// normalised coordinates of the camera at t_s.
// Threads (track_in_thread): frames are decoded in one worker thread and tracked in another while the estimator's
// thread handles the LiDAR (LVI-SAM runs its feature tracker as a node of its own; decoding a recording's PNG costs
// more than tracking the frame, and the two stages overlap); ObservationsAt first waits until
// every frame handed over that it may choose (within max_image_offset_s of its time) is tracked and ignores any
// tracked beyond, so the results do not depend on the threads' timing.
// Ownership: owns the tracker, its two workers, its recent results, the depth cloud and the landmarks (the window only
// points at them). Thread safety: every public member is for one caller thread (the estimator's).
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>

#include "core/backend/visual_landmarks.hpp"
#include "core/io/recording.hpp"
#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/types/scan_point.hpp"
#include "core/visual/feature_depth.hpp"
#include "core/visual/feature_tracker.hpp"

namespace rotolidar {

struct VisualConfig {
  /// Off: camera frames serve only the loop closer (when it has a vocabulary). On: every frame is tracked and
  /// the window fuses reprojection factors (LiDAR-visual-inertial).
  bool enabled = false;
  visual::FeatureTrackerConfig tracker;
  VisualWindowConfig landmarks;
  visual::LidarDepthConfig depth;
  /// A window state takes its observations from the tracked frame nearest its time, when within this [s]
  /// (half of a 30 Hz frame period is 0.017 s; 0.05 s tolerates a dropped frame).
  double max_image_offset_s = 0.05;
  /// Frames nearer than 0.9 / max_tracking_rate_hz to the last tracked one are skipped [Hz] (their decoding too:
  /// Estimator::WantsCameraFrame). 15 Hz tracks every other frame of a 30 Hz camera: KLT's 3-level pyramid
  /// follows ~80 px per step, and a 1 rad/s handheld turn moves features ~30 px in 1/15 s. 0 (default): every
  /// frame. 15 Hz runs ~1.3x faster, but raised the median ATE of clean_street 30 s (typical, seeds 1-5) by 5 %
  /// and left the lab slightly worse than LiDAR-inertial alone (docs/visual.md, "Tracking rate").
  double max_tracking_rate_hz = 0.0;
  /// LiDAR points of the last this many seconds give new landmarks their depth [s]: 2.5 s is one rotor turn at
  /// 2.6 rad/s, so the camera's whole view has been swept.
  double depth_cloud_s = 2.5;
  /// Depth points farther from the camera than this are not kept [m] (the camera's features are nearer).
  double depth_cloud_max_range_m = 40.0;
  /// Only points inside the camera's view at their own scan, widened by this on every side [rad], enter the depth
  /// cloud: the camera turns with the base, so later states see nearly the same cone. 0.35 rad (20 deg) covers a
  /// 0.14 rad/s turn over the cloud's 2.5 s; a rotary scan's ~15 k points over 2.5 s cost ~15 ms per state to
  /// project, the ~20 % in view ~3 ms.
  double depth_view_margin_rad = 0.35;
  /// Decode and track frames in two worker threads (see above); off: in the caller's thread. Same results.
  bool track_in_thread = true;
  /// With the camera fused, the registration's gate on weak directions (registration.degeneracy_weak_gate_m) is
  /// this instead [m] (ResolveFromCalib applies it). The gate tests the LiDAR's estimate along a weakly observed
  /// direction against the guess; the camera observes the axis the LiDAR sees weakly, so the guess along it stays
  /// good and an estimate straying beyond a few cm is more likely biased than a correction. clean_street 30 s
  /// (typical, seeds 1-5), median ATE with the camera: 0.175 m at 3 cm, 0.209 m at 6 cm, 0.242 m at 10 cm.
  double registration_weak_gate_m = 0.03;
  bool Validate(std::string* error) const;
};

/// What the camera path did for one window state (ScanReport::visual; scans.csv columns).
struct VisualScanReport {
  bool image = false;          ///< a tracked frame within max_image_offset_s gave observations
  double image_offset_s = 0.0; ///< t_img + td - t_s of that frame [s]
  int frames_tracked = 0;      ///< frames tracked since the previous state's
  int tracked = 0, inliers = 0, new_features = 0;  ///< FeatureTrackStats of the frame used
  int observations = 0;        ///< handed to the window
  int lidar_depths = 0;        ///< of those, features without a landmark that got a LiDAR depth
  int landmarks = 0, factors = 0, rejected_total = 0;  ///< VisualLandmarkStats after the previous solve
  double sigma_px = 0.0;          ///< the camera's pixel sigma for the next solve (adaptive weight) [px]
  double residual_median_px = 0.0;  ///< median reprojection error of the previous solve [px]
  double time_offset_s = 0.0;       ///< the camera time offset td the observations were moved with [s]
  double track_ms = 0.0;       ///< tracker time since the previous state [ms]
  double depth_ms = 0.0;       ///< depth-cloud projection and queries [ms]
};

class VisualFrontEnd {
 public:
  /// config must Validate and calib's camera intrinsics be usable (ROTOLIDAR_CHECK).
  VisualFrontEnd(const VisualConfig& config, const RigCalib& calib);
  ~VisualFrontEnd();  ///< stops the worker; frames not yet tracked are dropped
  VisualFrontEnd(const VisualFrontEnd&) = delete;
  VisualFrontEnd& operator=(const VisualFrontEnd&) = delete;

  /// Tracks one frame (frames in time order). A frame the tracker refuses (bad image) is logged and skipped.
  void Track(const CameraFrame& frame);
  /// The same for a frame on disk, decoded where it is tracked; an unreadable image is logged and skipped.
  void Track(const CameraFrameRef& ref);
  /// Whether Track would use a frame at t_s (max_tracking_rate_hz).
  bool WantsFrame(Seconds t_s) const;
  /// One scan's points (base frame at the scan's start, posed by T_world_base) into the depth cloud.
  void AddDepthPoints(Seconds t_s, const Pose3& T_world_base, const std::vector<ScanPoint>& points);
  /// The observations of the window state at t_s whose base pose is estimated as T_world_base; empty without a
  /// tracked frame near t_s. Fills *report.
  std::vector<VisualObservation> ObservationsAt(Seconds t_s, const Pose3& T_world_base, VisualScanReport* report);

  VisualLandmarks* landmarks() { return &landmarks_; }

 private:
  struct DepthScan {
    Seconds t_s;
    std::vector<Eigen::Vector3f> points_world;
  };
  struct Pending {  ///< a frame handed over: decoded (frame.image) or on disk (ref; frame.t_s set, image empty)
    CameraFrame frame;
    std::optional<CameraFrameRef> ref;
    bool unreadable = false;  ///< its image could not be decoded (logged); it is skipped
  };
  void Enqueue(Pending pending);
  static void Decode(Pending* pending);  ///< loads a frame on disk into frame.image; marks it unreadable on failure
  void TrackNow(Pending pending);  ///< decode if still on disk, track, keep the result
  void WaitForTracking(Seconds t_limit_s);  ///< until every frame handed over up to t_limit_s is tracked
  void StageLoop(std::condition_variable& cv, std::deque<Pending>& queue, const std::function<void(Pending&)>& work,
                 const std::function<void(Pending&)>& done);
  void DecodeLoop();
  void TrackLoop();
  /// The depth of each feature without a landmark (NaN where the LiDAR gives none).
  std::vector<double> LidarDepths(const std::vector<Eigen::Vector2d>& normalized, const Pose3& T_world_cam,
                                  int* valid);

  VisualConfig config_;
  RigCalib calib_;
  visual::FeatureTracker tracker_;
  VisualLandmarks landmarks_;
  std::deque<visual::FeatureTrackResult> recent_;  ///< tracked frames of the last ~0.2 s
  std::deque<DepthScan> depth_cloud_;
  std::optional<Seconds> last_tracked_s_;  ///< the last frame handed over (caller's thread)
  std::optional<Seconds> last_state_s_;  ///< the previous ObservationsAt's t_s
  // The two workers (track_in_thread): frames pass the decoder, then the tracker, in the order handed over, so the
  // oldest frame not yet tracked is in_flight_.front(). recent_ (declared above) is written by TrackNow (the
  // tracker) and copied by ObservationsAt, both under mutex_, which guards all of these.
  std::mutex mutex_;
  std::condition_variable decode_cv_, track_cv_, idle_cv_;
  std::deque<Pending> decode_queue_, track_queue_;
  std::deque<Seconds> in_flight_;  ///< times of the frames handed over and not yet tracked, oldest first
  bool stop_ = false;
  std::thread decoder_, tracker_thread_;
};

}  // namespace rotolidar
