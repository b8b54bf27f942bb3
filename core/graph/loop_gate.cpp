#include "core/graph/loop_gate.hpp"

#include <algorithm>

namespace rotolidar::graph {

loop::LidarDescriptor LevelledDescriptor(const std::vector<Eigen::Vector3d>& points_base,
                                         const Eigen::Matrix3d& R_level_base, const loop::LidarDescriptorConfig& config) {
  const Eigen::Matrix3f R = R_level_base.cast<float>();
  std::vector<Eigen::Vector3f> levelled;
  levelled.reserve(points_base.size());
  for (const Eigen::Vector3d& p : points_base) levelled.push_back(R * p.cast<float>());
  return loop::ComputeLidarDescriptor(levelled, config);
}

loop::DescriptorMatch DescriptorAtGuess(const std::vector<Eigen::Vector3d>& query_base,
                                        const loop::LidarDescriptor& query, const loop::LidarDescriptor& match,
                                        const Eigen::Matrix3d& R_level_match, const Pose3& T_match_query_guess,
                                        const loop::LidarDescriptorConfig& config) {
  loop::DescriptorMatch plain = loop::DescriptorDistance(query, match);
  std::vector<Eigen::Vector3d> moved;  // in the match's base frame
  moved.reserve(query_base.size());
  for (const Eigen::Vector3d& p : query_base) moved.push_back(T_match_query_guess * p);
  const loop::DescriptorMatch at_guess =
      loop::DescriptorDistance(LevelledDescriptor(moved, R_level_match, config), match);
  plain.distance = std::min(plain.distance, at_guess.distance);
  return plain;
}

RevisitCheck CheckRevisit(const std::vector<Eigen::Vector3d>& query_base, const Eigen::Matrix3d& R_level_query,
                          const std::function<std::vector<Eigen::Vector3d>()>& submap,
                          const Eigen::Matrix3d& R_level_match, const Pose3& T_match_query_guess, double yaw_rad,
                          double path_m, const LoopClosureConfig& config,
                          const loop::LoopVerificationConfig& verification) {
  RevisitCheck check;
  const double drift_bound_m = config.max_guess_offset_m + config.max_guess_offset_per_m * path_m;
  check.guess_distance_m = T_match_query_guess.translation().norm();
  if (check.guess_distance_m > config.max_revisit_distance_m + drift_bound_m) return check;  // kTooFar
  const std::vector<Eigen::Vector3d> target = submap();
  loop::LoopVerification& v = check.verification;
  v = loop::VerifyLoop(query_base, target, T_match_query_guess, verification);
  if (!v.accepted) {
    Pose3 T_match_query_yaw = Pose3::Identity();  // T_m_q = R_Lm_m^T RotZ(yaw) R_Lq_q: both frames at the base origin
    T_match_query_yaw.linear() = R_level_match.transpose() * RotZ(yaw_rad).linear() * R_level_query;
    v = loop::VerifyLoop(query_base, target, T_match_query_yaw, verification);
  }
  check.outcome = CandidateRecord::Outcome::kGicpFailed;
  if (!v.accepted) return check;
  check.outcome = CandidateRecord::Outcome::kBeyondDrift;
  if (v.T_target_source.translation().norm() > config.max_loop_distance_m) return check;
  const Pose3 offset = T_match_query_guess.inverse() * v.T_target_source;
  if (offset.translation().norm() > drift_bound_m) return check;
  const double max_angle_rad = config.max_guess_offset_rad + config.max_guess_offset_per_m * path_m;
  if (Eigen::AngleAxisd(offset.linear()).angle() > max_angle_rad) return check;
  check.outcome = CandidateRecord::Outcome::kAccepted;
  return check;
}

}  // namespace rotolidar::graph
