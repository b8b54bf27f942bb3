#pragma once
// Precision and recall of loop detection against the twin's truth (`rotolidar bench loops`).
//
// Truth: two keyframes are a true revisit when their truth positions are within revisit_max_distance_m and, placed
// with their truth poses, at least revisit_min_overlap of the query's points have a point of the other keyframe's
// submap (it and loop.submap_neighbours either side, as stage 2 registers against) within overlap_radius_m: the
// same surfaces seen again, not just the same spot behind a wall. A submap, not one keyframe: a rotary rig's scan
// is one tilted fan of the sphere, and two scans from one spot at other rotor angles share little.
//
// Queries: every keyframe that has an eligible earlier keyframe (older by exclude_recent_s and at least
// min_travel_m of odometry path back, the loop closer's own rule). A query is a positive when one of its eligible
// keyframes is a true revisit. Each detector proposes one keyframe per query; a detection at threshold tau is
// a true positive when the proposed pair is a true revisit, a false positive otherwise:
//   stage 1 alone   the nearest eligible keyframe by Scan Context distance; score: that distance
//   stage 2 alone   the nearest eligible keyframe on the odometry poses through the loop closer's stage 2
//                   (graph::CheckRevisit on the odometry poses: distance gate, GICP, drift bound) with every gate
//                   but the fitness one; score: GICP fitness [m]
//   both            the loop closer's own chain: stage 1's keyframe through the descriptor gate and stage 2; when
//                   that fails, the keyframe nearest on the odometry poses (within max_revisit_distance_m) the
//                   same way; score: GICP fitness [m] of the pair that passed
//   visual stage 1  the seed's camera stage 1 alone: each keyframe's bag-of-words vector (KeyframeCloud::bow) in a
//   alone           loop::BowDatabase fed in keyframe order, as the loop closer's; the eligible keyframe with the
//                   best normalised score eta = s(v_t, v_j) / s(v_t, v_{t-1}) (v_{t-1}: the previous keyframe with
//                   a vector; a query with s(v_t, v_{t-1}) < loop.bow.min_previous_score, or without a vector,
//                   proposes nothing); score: eta, HIGHER is better (a detection at tau: eta >= tau). Only when
//                   some keyframe has a vector; recall is still over all positives.
// precision = TP / (TP + FP) (1 when nothing is detected), recall = TP / positives (0 when there are none).
// Odometry poses are used as they are (no graph correction between queries): the curves rate the detectors, not
// the back end.
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/graph/loop_closer.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct LoopPrConfig {
  double revisit_max_distance_m = 10.0;  ///< truth distance bound of a true revisit [m]
  /// Share of the query's points seen again in the other's submap (truth poses).
  double revisit_min_overlap = 0.3;
  double overlap_radius_m = 0.5;         ///< "seen again": a point of the other keyframe within this [m]
  /// An accepted loop is correct when GICP's relative pose is within these of the truth's [m], [rad]; a wrong
  /// constraint otherwise (a false loop: what bends a map).
  double max_loop_error_m = 0.3;
  double max_loop_error_rad = 0.035;
  /// The loop closer's settings: eligibility (exclude_recent_s, min_travel_m), the descriptor, stage 2's gates
  /// (CheckRevisit). The operating point is its max_descriptor_distance and verification.max_fitness_rmse_m.
  graph::LoopClosureConfig loop;
  bool Validate(std::string* error) const;
};

/// Builds the truth labels once per run (a k-d tree per keyframe at its truth pose).
class RevisitTruth {
 public:
  /// keyframes and T_truth_base (truth pose at each keyframe's time) are index-aligned.
  RevisitTruth(const std::vector<graph::KeyframeCloud>& keyframes, const std::vector<Pose3>& T_truth_base,
               const LoopPrConfig& config);
  ~RevisitTruth();
  bool IsRevisit(int query_id, int match_id) const;  ///< the truth label of a pair (memoised)
  double Overlap(int query_id, int match_id) const;  ///< share of query points seen in match's submap (truth poses)
  double Distance(int query_id, int match_id) const;  ///< between their truth positions [m]
  Pose3 Relative(int query_id, int match_id) const;   ///< truth T_match_query

 private:
  struct Impl;
  Impl* impl_;
};

/// An accepted loop against the truth.
struct LoopTruthCheck {
  double truth_distance_m = 0.0, truth_overlap = 0.0;
  double error_m = 0.0, error_rad = 0.0;  ///< GICP's T_match_query against the truth's
  bool correct = false;                   ///< error within max_loop_error_m and max_loop_error_rad
};
LoopTruthCheck CheckLoop(const RevisitTruth& truth, const graph::LoopRecord& loop, const LoopPrConfig& config);

/// One query keyframe and what each detector made of it (-1: no proposal).
struct LoopQueryOutcome {
  int query_id = 0;
  Seconds t_query_s = 0.0;
  bool positive = false;                 ///< an eligible true revisit exists
  int stage1_match = -1;
  double stage1_distance = 1.0;
  bool stage1_true = false;
  double stage1_truth_distance_m = 0.0, stage1_truth_overlap = 0.0;  ///< the proposed pair's truth
  int stage2_match = -1;
  bool stage2_verified = false;          ///< stage 2 passed every gate but fitness
  double stage2_fitness_m = 0.0;
  bool stage2_true = false;
  double stage2_truth_distance_m = 0.0, stage2_truth_overlap = 0.0;
  int both_match = -1;                   ///< the pair that passed (else stage 1's proposal)
  bool both_verified = false;            ///< the descriptor gate and stage 2 (every gate but fitness) passed
  double both_fitness_m = 0.0;
  bool both_true = false;
  int visual_match = -1;                 ///< the visual stage 1's proposal (-1: none)
  double visual_eta = 0.0;               ///< its normalised score eta
  double visual_raw_score = 0.0;         ///< its raw L1 score s(v_t, v_j)
  bool visual_true = false;
  double visual_truth_distance_m = 0.0, visual_truth_overlap = 0.0;
};

struct PrPoint {
  /// The swept score's gate: a detection is score <= threshold, or score >= threshold for a higher-is-better score
  /// (the visual stage 1's eta).
  double threshold = 0.0;
  double precision = 1.0, recall = 0.0;
  int tp = 0, fp = 0;
};

struct LoopPrResult {
  std::vector<LoopQueryOutcome> queries;  ///< the eligible queries, in keyframe order
  int positives = 0;
  std::vector<PrPoint> stage1, stage2, both;  ///< by ascending threshold
  PrPoint operating;                          ///< both at the loop config's fitness gate
  /// The visual stage 1 alone, by DESCENDING eta (recall grows along it); empty when no keyframe has a vector.
  std::vector<PrPoint> visual;
  /// It at the loop closer's acceptance: eta >= loop.bow.min_normalised_score (the seed's 0.35) and raw score >=
  /// loop.bow.min_raw_score; threshold = that eta.
  PrPoint visual_operating;
  int visual_keyframes = 0;  ///< keyframes with a bag-of-words vector
  std::string visual_absent;  ///< why there is no visual curve (empty when there is one)
  double verify_time_s = 0.0;                 ///< GICP time, all queries [s]
};

/// Runs the three detectors over `keyframes` (odometry poses) and sweeps their thresholds. `progress(fraction)`
/// may be null. Errors: an invalid config, sizes that differ.
Status EvaluateLoopPr(const std::vector<graph::KeyframeCloud>& keyframes, const std::vector<Pose3>& T_truth_base,
                      const LoopPrConfig& config, LoopPrResult* result,
                      const std::function<void(double)>& progress = nullptr);

/// The PR curve of (score, is_true) detections: one point per distinct score, precision / recall as above, from
/// the strictest gate to the widest: ascending scores (detection: score <= threshold), or descending ones when
/// higher_is_better (detection: score >= threshold). Exposed for the tests.
std::vector<PrPoint> SweepPr(std::vector<std::pair<double, bool>> detections, int positives,
                             bool higher_is_better = false);

/// The highest recall of a curve's points without a false detection (0 for an empty curve).
double RecallAtPrecision1(const std::vector<PrPoint>& curve);

/// The truth pose (recording/truth/base.tum, T_world_base) at every keyframe's time, index-aligned. Errors name
/// the file, or the keyframe the truth does not cover.
Status TruthAtKeyframes(const std::string& recording, const std::vector<graph::KeyframeCloud>& keyframes,
                        std::vector<Pose3>* T_truth_base);

}  // namespace rotolidar::bench
