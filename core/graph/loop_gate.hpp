#pragma once
// Stage 2 of the loop closer on one candidate, as a function of its inputs: the loop closer runs it on its graph's
// poses; `rotolidar bench loops` runs it on the odometry's to rate the detectors. Steps:
//   1. too far: the candidate lies farther than max_revisit_distance_m plus the drift bound from the query on the
//      given poses (two scans of one place overlap within a few metres; GICP is not run);
//   2. GICP (VerifyLoop) of the query's points onto the candidate's submap from the given relative pose and,
//      failing that, from the descriptor's yaw at zero offset (the poses may have drifted beyond GICP's reach);
//   3. beyond drift: the verified relative pose differs from the given one by more than the drift bound
//      (max_guess_offset_m + max_guess_offset_per_m * path_m; the same for rotation in rad): a look-alike place;
//      or it joins keyframes farther apart than max_loop_distance_m (too little shared view to trust).
// Frames: points in each keyframe's base frame [m]; R_level_* rotate base into the descriptor's gravity-aligned
// frame; T_match_query_guess maps query base into match base.
#include <algorithm>
#include <functional>
#include <vector>

#include "core/graph/loop_closer.hpp"

namespace rotolidar::graph {

struct RevisitCheck {
  /// kTooFar, kGicpFailed, kBeyondDrift, or kAccepted (stage 2 passed; the graph has not seen it yet).
  CandidateRecord::Outcome outcome = CandidateRecord::Outcome::kTooFar;
  double guess_distance_m = 0.0;     ///< |translation| of T_match_query_guess [m]
  loop::LoopVerification verification;  ///< GICP's outcome (default when it did not run)
};

/// A keyframe's LiDAR descriptor: its base-frame points turned into its gravity-aligned frame (R_level_base), so
/// that yaw is the only free rotation (the place index's shift search).
loop::LidarDescriptor LevelledDescriptor(const std::vector<Eigen::Vector3d>& points_base,
                                         const Eigen::Matrix3d& R_level_base, const loop::LidarDescriptorConfig& config);

/// The points of keyframes center - neighbours .. center + neighbours (clamped to [0, count)) in the center's base
/// frame: pose_of(k) gives T_world_base of keyframe k, points_of(k) its base-frame points.
template <class PoseOf, class PointsOf>
std::vector<Eigen::Vector3d> SubmapAround(int center, int neighbours, int count, PoseOf pose_of, PointsOf points_of) {
  const Pose3 T_center_world = pose_of(center).inverse();
  std::vector<Eigen::Vector3d> out;
  for (int k = std::max(0, center - neighbours); k <= std::min(count - 1, center + neighbours); ++k) {
    const Pose3 T_center_k = T_center_world * pose_of(k);
    for (const Eigen::Vector3d& p : points_of(k)) out.push_back(T_center_k * p);
  }
  return out;
}

/// The points keyframe `id`'s LiDAR descriptor describes, in its base frame: its own (`own`, at T_world_own, time
/// t_s) and, with window_s > 0, those of the earlier keyframes id-1, id-2, ... no older than t_s - window_s,
/// placed by pose_of(k) (T_world_base, the odometry). LoopClosureConfig::descriptor_window_s.
template <class TimeOf, class PoseOf, class PointsOf>
std::vector<Eigen::Vector3d> DescribedPoints(int id, const std::vector<Eigen::Vector3d>& own, const Pose3& T_world_own,
                                             double window_s, double t_s, TimeOf time_of, PoseOf pose_of,
                                             PointsOf points_of) {
  std::vector<Eigen::Vector3d> out = own;
  if (!(window_s > 0.0)) return out;
  const Pose3 T_own_world = T_world_own.inverse();
  for (int k = id - 1; k >= 0 && time_of(k) >= t_s - window_s; --k) {
    const Pose3 T_own_k = T_own_world * pose_of(k);
    for (const Eigen::Vector3d& p : points_of(k)) out.push_back(T_own_k * p);
  }
  return out;
}

/// The descriptor distance of a candidate proposed by its pose (the graph neighbour): the smallest of the plain
/// distance and the distances with the query's points moved into the candidate's base frame by the guess plus a
/// horizontal offset on a 1 m grid within search_radius_m (0: the guess alone). Scan Context's polar grid changes
/// fast with an offset between the two scans (0.58-0.97 at 1-9 m on streets) and the guess carries the drift;
/// the search is Scan Context's own yaw search extended to translation (as Scan Context++, Kim et al., T-RO 2021,
/// searches lateral shifts). The yaw stays the plain match's (stage 2's fallback guess is taken at zero offset).
/// Cost: one descriptor per grid offset (~pi r^2 / 1 m^2 of them).
loop::DescriptorMatch DescriptorAtGuess(const std::vector<Eigen::Vector3d>& query_base,
                                        const loop::LidarDescriptor& query, const loop::LidarDescriptor& match,
                                        const Eigen::Matrix3d& R_level_match, const Pose3& T_match_query_guess,
                                        double search_radius_m, const loop::LidarDescriptorConfig& config);

/// DescriptorAtGuess's search radius for a guess over path_m of odometry [m]: the drift bound of CheckRevisit
/// (max_guess_offset_m + max_guess_offset_per_m * path_m), at most half of max_revisit_distance_m.
double DescriptorSearchRadius(double path_m, const LoopClosureConfig& config);

/// One candidate through stage 2. `submap` is called only when GICP runs (it may be costly); `yaw_rad` is the
/// descriptor's yaw of T_match_query; `path_m` the odometry path between the two keyframes [m].
RevisitCheck CheckRevisit(const std::vector<Eigen::Vector3d>& query_base, const Eigen::Matrix3d& R_level_query,
                          const std::function<std::vector<Eigen::Vector3d>()>& submap,
                          const Eigen::Matrix3d& R_level_match, const Pose3& T_match_query_guess, double yaw_rad,
                          double path_m, const LoopClosureConfig& config,
                          const loop::LoopVerificationConfig& verification);

}  // namespace rotolidar::graph
