#pragma once
// Loop closure beside the odometry: the seed's two-stage place recognition and a pose graph (LV-SLAM, Sensors
// 2025, Sec. 3.4, Fig. 5). The odometry hands each of its keyframes over (AddKeyframe: a copy into a queue, it
// never waits); a worker thread, in keyframe order:
//   1. stores the keyframe (pose, thinned deskewed points, LiDAR descriptor) in a bounded database and adds it to
//      the pose graph with an odometry edge from the previous keyframe;
//   2. stage 1, place recognition: with a camera frame and a vocabulary (LoadVocabulary), the ORB bag-of-words
//      database proposes earlier keyframes whose images look alike (the seed's stage 1); without, the LiDAR place
//      index (Scan Context, yaw-invariant ring key) proposes earlier keyframes that the rig has left and come back
//      to; when neither leads to a loop, the keyframe nearest on the current graph is tried too;
//   3. stage 2, geometric verification: the candidate's descriptor distance must pass, then GICP between the
//      keyframe's points and the candidate's submap, started from the graph's current relative pose, must converge
//      with enough overlap and a small residual, and land within the drift the odometry can have accumulated;
//   4. an accepted loop becomes a loop edge (its GICP covariance as information) and the graph is re-optimised;
//      its robust loss and chi2 test drop a wrong loop (core/graph/pose_graph.hpp).
// The corrected keyframe poses then correct the whole trajectory (CorrectTrajectory) and rebuild the map from the
// keyframes' points (the seed's removal of "ghost" copies, Fig. 5c/d).
//
// Frames: T_world_base is the odometry's (world = the estimator's world frame). The descriptor is taken in a
// gravity-aligned frame centred on the base origin (gravity from the caller, world frame).
// Determinism: keyframes are processed strictly in order and each sees only earlier ones, so after Finish() the
// outcome does not depend on thread timing; only State() before Finish() does.
// Thread safety: AddKeyframe and Finish from one (the odometry's) thread; State and the output calls from any.
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "core/graph/pose_graph.hpp"
#include "core/loop/bow_database.hpp"
#include "core/loop/geometric_verification.hpp"
#include "core/loop/lidar_descriptor.hpp"
#include "core/loop/orb_features.hpp"
#include "core/loop/vocabulary.hpp"
#include "core/types/trajectory.hpp"

namespace rotolidar::graph {

inline loop::LoopVerificationConfig LoopVerificationDefaults() {
  loop::LoopVerificationConfig c;
  c.max_fitness_rmse_m = 0.22;
  return c;
}

struct LoopClosureConfig {
  bool enabled = false;
  bool threaded = true;  ///< false: AddKeyframe does the work itself (tests; timing studies)
  /// Loop keyframes are a subset of the odometry's: a new one once the rig moved this far [m] or turned this
  /// much [rad] since the last (the odometry's keyframes come every few scans; closer ones add nothing).
  double keyframe_spacing_m = 1.0;
  double keyframe_spacing_rad = 0.5;
  double cloud_voxel_m = 0.2;     ///< the stored points (descriptor, verification), VoxelGrid leaf [m]
  double map_voxel_m = 0.1;       ///< the stored points for the rebuilt map [m]; 0: keep no map points
  double max_range_m = 40.0;      ///< stored points farther from the sensor are dropped [m]
  /// A candidate must be this much older [s] and the rig must have travelled this far [m] since it: a loop is a
  /// return after leaving, not the trail just behind.
  double exclude_recent_s = 20.0;
  double min_travel_m = 10.0;
  int num_candidates = 2;               ///< stage-1 candidates verified per keyframe, best first
  /// After an accepted loop, no search until the rig has travelled this far [m]: the next keyframes of the same
  /// revisit would add near-copies of the loop at a GICP each (~0.5 s).
  double after_loop_travel_m = 10.0;
  /// Stage 2's descriptor gate (Scan Context distance in [0, 1]; synthetic true revisits measured <= 0.28).
  double max_descriptor_distance = 0.35;
  /// The LiDAR descriptor describes the keyframe's own points plus those of the keyframes of the last this many
  /// seconds, placed by the odometry [s]; >= 0, 0: its own scan only. A rotary rig's scan is one 30 deg fan of the
  /// sphere, so two scans of one place at different rotor angles describe it differently. 2.5 s is about one
  /// rotor turn at the default 2.6 rad/s (every fan orientation, twice). Seed 1 with `bench loops
  /// --descriptor-window`, recall at precision 1 (own scan -> 1.2 s -> 2.5 s): urban loop 0.17 -> 0.50 -> 0.58,
  /// parking 0.65 -> 0.81 -> 0.83; garage 0.45 -> 0.71 at 2.5 s (docs/loop_closure.md has the seeds).
  double descriptor_window_s = 2.5;
  int submap_neighbours = 2;            ///< the candidate's submap: it and this many keyframes either side
  /// The verified relative pose may differ from the graph's current one by at most base + per_m * (path length
  /// between the two keyframes) in translation [m] (the odometry's drift bound; rejects a look-alike place).
  double max_guess_offset_m = 1.0;
  double max_guess_offset_per_m = 0.05;
  double max_guess_offset_rad = 0.35;  ///< the same for rotation (plus per_m times the path, in rad)
  /// Stage 1's candidates farther apart than this [m] (plus the drift bound above) on the current graph go no
  /// further: two scans of one place overlap within a few metres, and GICP costs ~0.5 s.
  double max_revisit_distance_m = 8.0;
  /// A verified loop must join keyframes at most this far apart (GICP's relative translation) [m]: in the garage
  /// (typical realism, seed 1) loops 9.6 m apart measured 0.01-0.025 m pose error against the truth, loops 11.6-16.6 m
  /// apart 0.02-0.46 m (their scans share 10-40 % of the points; the repeated bays alias).
  double max_loop_distance_m = 10.0;
  /// Odometry edges' standard deviations: a floor plus a share of the edge's length / turn.
  double odometry_sigma_m = 0.01, odometry_sigma_per_m = 0.01;
  double odometry_sigma_rad = 0.002, odometry_sigma_per_rad = 0.01;
  size_t max_keyframes = 20000;  ///< database bound; beyond it keyframes are not stored (counted)
  /// Stage 1 with a camera (the seed's): an ORB vocabulary file (`rotolidar vocab train`; the twin's is
  /// scenes/vocabulary/twin_orb_k8_l5.bin). Empty: the LiDAR descriptor proposes. The caller loads it
  /// (LoopCloser::LoadVocabulary) and hands camera frames with the keyframes.
  std::string vocabulary;
  double max_camera_offset_s = 0.1;  ///< a keyframe takes the camera frame nearest its time within this [s]
  loop::OrbConfig orb;
  /// The bag-of-words acceptance (eta >= 0.35, the seed's); its exclude_recent_s is replaced by the one above.
  loop::LoopQueryConfig bow;
  loop::LidarDescriptorConfig descriptor;
  /// GICP gates. The fitness gate is wider than VerifyLoop's default: on the parking lot's second lap (typical
  /// realism, 0.2 m voxels, moving cars) true revisits measured fitness 0.14-0.21 m at overlap >= 0.77, while
  /// look-alike candidates measured >= 0.24 m at overlap <= 0.35.
  loop::LoopVerificationConfig verification = LoopVerificationDefaults();
  InformationFloor loop_information_floor;
  PoseGraphConfig graph;
  bool Validate(std::string* error) const;
};

/// One keyframe as the odometry hands it over (a copy; the caller keeps nothing alive).
struct KeyframeInput {
  Seconds t_s = 0.0;
  Pose3 T_world_base = Pose3::Identity();  ///< the odometry's pose at t_s
  /// Direction of gravity in world (any length > 0; zero or non-finite: world -z is taken as down).
  Eigen::Vector3d gravity_world = -Eigen::Vector3d::UnitZ();
  std::vector<Eigen::Vector3f> points_base;  ///< deskewed points, base frame at t_s [m]
  cv::Mat image;  ///< the camera frame nearest t_s (BGR8 or GRAY8; shared, not modified); empty: none
};

/// A loop that passed stage 2 (and what the graph made of it).
struct LoopRecord {
  int query_id = 0, match_id = 0;  ///< keyframe ids (query: the newer)
  Seconds t_query_s = 0.0, t_match_s = 0.0;
  Pose3 T_match_query = Pose3::Identity();  ///< GICP's relative pose
  double descriptor_distance = 1.0, fitness_rmse_m = 0.0, overlap = 0.0;
  bool rejected = false;  ///< the pose graph's chi2 test dropped it (an outlier)
};

/// One stage-1 candidate and how far it got (the raw data of precision/recall studies).
struct CandidateRecord {
  enum class Outcome { kDescriptorRejected, kTooFar, kGicpFailed, kBeyondDrift, kGraphError, kAccepted };
  int query_id = 0, match_id = 0;
  /// Who proposed it: the LiDAR descriptor, the camera's bag of words, or nearness on the graph (the fallback).
  enum class Source { kLidar, kVisual, kGraph };
  Source source = Source::kLidar;
  double bow_score = 0.0;  ///< the bag of words' normalised score eta (visual proposals)
  double descriptor_distance = 1.0;
  double graph_distance_m = 0.0;  ///< |translation| between the two on the graph when proposed
  Outcome outcome = Outcome::kTooFar;
  double fitness_rmse_m = 0.0, overlap = 0.0;  ///< GICP's (0 when it did not run)
  std::string reason;                         ///< GICP's rejection reason, when it rejected
};
const char* ToString(CandidateRecord::Outcome outcome);
const char* ToString(CandidateRecord::Source source);  ///< "lidar", "visual", "graph"

struct KeyframePose {
  int id = 0;
  Seconds t_s = 0.0;
  Pose3 T_world_odom = Pose3::Identity();       ///< as the odometry gave it
  Pose3 T_world_corrected = Pose3::Identity();  ///< after the latest graph solve
};

/// A stored keyframe as the database holds it (a copy: saving it with the run, offline precision/recall studies).
struct KeyframeCloud {
  int id = 0;
  Seconds t_s = 0.0;
  Pose3 T_world_odom = Pose3::Identity();
  Pose3 T_world_corrected = Pose3::Identity();
  Eigen::Matrix3d R_level_base = Eigen::Matrix3d::Identity();  ///< base -> the descriptor's gravity-aligned frame
  std::vector<Eigen::Vector3d> cloud_base;  ///< cloud_voxel_m-thinned points within max_range_m, base frame [m]
  /// The bag-of-words vector of its camera image as the visual stage 1 stored it (L1-normalised TF-IDF,
  /// loop::BowDatabase::Find; a few hundred words, ~50 B a word); empty when it has none (no vocabulary, no image
  /// near its time, or ORB / the vocabulary failed on it). No image is kept.
  loop::BowVector bow;
};

/// A snapshot of the loop closer's outcome.
struct LoopClosureState {
  std::vector<KeyframePose> keyframes;  ///< in time order
  std::vector<LoopRecord> loops;        ///< in the order they were found
  std::vector<CandidateRecord> candidates;  ///< every stage-1 candidate, in the order proposed
  size_t keyframes_offered = 0;         ///< AddKeyframe calls
  size_t keyframes_dropped = 0;         ///< over max_keyframes, a non-finite or non-rotation pose
  size_t visual_keyframes = 0;          ///< keyframes with an image in the bag-of-words database
  size_t visual_failures = 0;           ///< images whose ORB or BoW step failed (LiDAR stage 1 instead)
  size_t candidates_proposed = 0;       ///< stage-1 candidates far enough back on the path
  size_t candidates_checked = 0;        ///< candidates that reached GICP (near enough on the graph)
  double verify_time_s = 0.0;           ///< total GICP time [s]
  size_t graph_solves = 0;
  double last_solve_time_s = 0.0, max_solve_time_s = 0.0;
  bool last_solve_converged = true;
  std::string last_message;  ///< the last failure (graph or database), empty when none
};

class LoopCloser {
 public:
  explicit LoopCloser(const LoopClosureConfig& config);  ///< config must Validate (ROTOLIDAR_CHECK)
  ~LoopCloser();                                          ///< stops the worker (drops unprocessed keyframes)
  LoopCloser(const LoopCloser&) = delete;
  LoopCloser& operator=(const LoopCloser&) = delete;

  /// Loads the vocabulary of the visual stage 1 (before the first AddKeyframe; errors name the file). Without one,
  /// images handed with keyframes are ignored.
  Status LoadVocabulary(const std::string& path);
  bool has_vocabulary() const { return vocabulary_ != nullptr; }

  /// Offers an odometry keyframe; takes it when it is spaced enough from the last one taken. Keyframes must come
  /// in time order. Threaded: a queue push (no solve, no search on the caller's thread).
  void AddKeyframe(KeyframeInput keyframe);
  /// Waits until every offered keyframe has been processed (the outcome is then final and deterministic).
  void Finish();

  LoopClosureState State() const;
  /// Pose-graph solves so far (each accepted loop triggers one): cheap to poll after every scan to rebuild outputs
  /// when it changes (State() copies the whole record).
  size_t GraphSolves() const;
  /// The odometry trajectory mapped onto the corrected keyframes (continuous interpolation of the corrections);
  /// unchanged when no keyframe exists. Call after Finish for the final answer.
  Trajectory Correct(const Trajectory& odometry) const;
  /// The map rebuilt from the keyframes' stored points at their corrected poses [world], at most
  /// `points_per_voxel` per `voxel_m` voxel.
  std::vector<Eigen::Vector3d> CorrectedMap(double voxel_m, int points_per_voxel) const;
  /// Copies of the stored keyframes in id order (after Finish: all of them), ~24 B per stored point, with their
  /// bag-of-words vectors.
  std::vector<KeyframeCloud> KeyframeClouds() const;

 private:
  struct Keyframe;
  void WorkerLoop();
  void Process(KeyframeInput input);
  bool StoreKeyframe(KeyframeInput input, int id);
  bool AddImage(const cv::Mat& image, int id, Seconds t_s);
  void SearchLoops(int id);
  bool SearchVisual(int id);
  bool SearchLidar(int id);
  int NearestOnGraph(int id) const;
  bool TryCandidate(CandidateRecord record, const loop::DescriptorMatch& match);
  bool VerifyCandidate(const loop::DescriptorMatch& match, CandidateRecord* record);
  bool AddLoopEdge(int id, int match_id, const loop::LoopVerification& v, double descriptor_distance);
  void Solve();
  std::vector<Eigen::Vector3d> Submap(int center_id) const;  ///< around center_id, in its frame
  double PathLengthBetween(int older_id, int newer_id) const;

  LoopClosureConfig config_;
  // Odometry side: the spacing test.
  bool has_last_offered_ = false;
  Pose3 last_taken_T_world_base_ = Pose3::Identity();
  size_t offered_ = 0;
  // Worker side (guarded by mutex_ where State() or the outputs read it).
  mutable std::mutex mutex_;
  std::condition_variable queue_cv_, idle_cv_;
  std::deque<KeyframeInput> queue_;
  bool busy_ = false, stop_ = false;
  std::vector<std::unique_ptr<Keyframe>> keyframes_;  // id = index
  std::vector<double> path_length_m_;                 // odometry path length at each keyframe
  std::vector<Eigen::Vector3d> described_;            // the newest keyframe's descriptor points, for its search
  double last_loop_path_m_ = -1e300;                  // path length at the last accepted loop
  loop::LidarPlaceIndex index_;
  std::unique_ptr<loop::Vocabulary> vocabulary_;  // null: no visual stage 1
  loop::BowDatabase bow_;  // written by the worker under mutex_; read by the worker, or by others under mutex_
  PoseGraph graph_;
  LoopClosureState state_;
  std::thread worker_;
};

}  // namespace rotolidar::graph
