#include "core/graph/loop_gate.hpp"

#include <algorithm>
#include <cmath>

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
                                        double search_radius_m, const loop::LidarDescriptorConfig& config) {
  loop::DescriptorMatch best = loop::DescriptorDistance(query, match);
  // The query in the candidate's gravity-aligned frame at the guess; offsets are horizontal in that frame.
  std::vector<Eigen::Vector3d> levelled;
  levelled.reserve(query_base.size());
  for (const Eigen::Vector3d& p : query_base) levelled.push_back(R_level_match * (T_match_query_guess * p));
  const int steps = int(std::floor(std::max(0.0, search_radius_m)));  // 1 m grid
  std::vector<Eigen::Vector3d> shifted(levelled.size());
  for (int ix = -steps; ix <= steps; ++ix)
    for (int iy = -steps; iy <= steps; ++iy) {
      if (ix * ix + iy * iy > steps * steps) continue;
      const Eigen::Vector3d d(ix, iy, 0.0);
      for (size_t k = 0; k < levelled.size(); ++k) shifted[k] = levelled[k] + d;
      const double distance =
          loop::DescriptorDistance(LevelledDescriptor(shifted, Eigen::Matrix3d::Identity(), config), match).distance;
      best.distance = std::min(best.distance, distance);
    }
  return best;
}

double DescriptorSearchRadius(double path_m, const LoopClosureConfig& config) {
  return std::min(config.max_guess_offset_m + config.max_guess_offset_per_m * path_m,
                  0.5 * config.max_revisit_distance_m);
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
