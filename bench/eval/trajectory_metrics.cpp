#include "bench/eval/trajectory_metrics.hpp"

#include <algorithm>
#include <cmath>

namespace rotolidar::bench {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

/// Index of the first pose of `traj` nearest in time to t (numpy argmin of |t_j - t| over a sorted array).
size_t NearestIndex(const Trajectory& traj, double t) {
  const auto it = std::lower_bound(traj.begin(), traj.end(), t,
                                   [](const StampedPose& p, double v) { return p.t_s < v; });
  size_t hi = static_cast<size_t>(it - traj.begin());
  if (hi == traj.size()) --hi;
  if (hi == 0) return 0;
  size_t lo = hi - 1;
  if (std::abs(traj[lo].t_s - t) > std::abs(traj[hi].t_s - t)) return hi;
  while (lo > 0 && traj[lo - 1].t_s == traj[lo].t_s) --lo;  // argmin returns the first of equal minima
  return lo;
}

double ErrorOf(const Pose3& E, PoseRelation relation) {
  switch (relation) {
    case PoseRelation::kTranslation: return E.translation().norm();
    case PoseRelation::kRotationAngleDeg: return std::abs(Eigen::AngleAxisd(E.linear()).angle()) * kRadToDeg;
    case PoseRelation::kRotationAngleRad: return std::abs(Eigen::AngleAxisd(E.linear()).angle());
    case PoseRelation::kRotationPart: return (E.linear() - Eigen::Matrix3d::Identity()).norm();
    case PoseRelation::kFull: return (E.matrix() - Eigen::Matrix4d::Identity()).norm();
  }
  return 0.0;
}

void PairsByIndex(size_t n, size_t delta, bool all_pairs, std::vector<IdPair>* pairs) {
  if (all_pairs) {
    for (size_t i = 0; i + delta < n; ++i) pairs->emplace_back(i, i + delta);
    return;
  }
  for (size_t i = 0; i + delta < n; i += delta) pairs->emplace_back(i, i + delta);
}

void PairsByPathConsecutive(const Trajectory& poses, double delta, std::vector<IdPair>* pairs) {
  std::vector<size_t> ids;
  double current_path = 0.0;
  for (size_t i = 0; i < poses.size(); ++i) {
    if (i > 0) {
      current_path += (poses[i].T_ref_body.translation() - poses[i - 1].T_ref_body.translation()).norm();
    }
    if (current_path >= delta) {
      ids.push_back(i);
      current_path = 0.0;
    }
  }
  for (size_t k = 1; k < ids.size(); ++k) pairs->emplace_back(ids[k - 1], ids[k]);
}

// For each i: numpy argmin over j > i of |(acc_j - acc_i) - delta|; the sequence is non-decreasing in j, so
// the minimum is at the first j reaching delta or just before it (first of any equal run).
void PairsByPathAll(const Trajectory& poses, double delta, double tol, std::vector<IdPair>* pairs) {
  const std::vector<double> acc = AccumulatedDistances(poses);
  const size_t n = acc.size();
  for (size_t i = 0; i + 1 < n; ++i) {
    auto err = [&](size_t j) { return std::abs((acc[j] - acc[i]) - delta); };
    const auto it = std::lower_bound(acc.begin() + i + 1, acc.end(), delta,
                                     [&](double a, double d) { return (a - acc[i]) < d; });
    size_t best = static_cast<size_t>(it - acc.begin());
    if (best == n) --best;
    if (best > i + 1) {
      size_t lo = best - 1;
      while (lo > i + 1 && acc[lo - 1] == acc[lo]) --lo;
      if (err(lo) <= err(best)) best = lo;
    }
    if (err(best) > tol) continue;
    pairs->emplace_back(i, best);
  }
}

}  // namespace

std::vector<double> AccumulatedDistances(const Trajectory& poses) {
  std::vector<double> acc(poses.size(), 0.0);
  for (size_t i = 1; i < poses.size(); ++i) {
    acc[i] = acc[i - 1] + (poses[i].T_ref_body.translation() - poses[i - 1].T_ref_body.translation()).norm();
  }
  return acc;
}

bool ParsePoseRelation(const std::string& name, PoseRelation* out) {
  if (name == "trans_part" || name == "trans") *out = PoseRelation::kTranslation;
  else if (name == "angle_deg" || name == "rot") *out = PoseRelation::kRotationAngleDeg;
  else if (name == "angle_rad") *out = PoseRelation::kRotationAngleRad;
  else if (name == "rot_part") *out = PoseRelation::kRotationPart;
  else if (name == "full") *out = PoseRelation::kFull;
  else return false;
  return true;
}

const char* PoseRelationName(PoseRelation relation) {
  switch (relation) {
    case PoseRelation::kTranslation: return "translation part";
    case PoseRelation::kRotationAngleDeg: return "rotation angle in degrees";
    case PoseRelation::kRotationAngleRad: return "rotation angle in radians";
    case PoseRelation::kRotationPart: return "rotation part";
    case PoseRelation::kFull: return "full transformation";
  }
  return "?";
}

const char* PoseRelationUnit(PoseRelation relation) {
  switch (relation) {
    case PoseRelation::kTranslation: return "m";
    case PoseRelation::kRotationAngleDeg: return "deg";
    case PoseRelation::kRotationAngleRad: return "rad";
    default: return "";
  }
}

bool ParseDeltaUnit(const std::string& name, DeltaUnit* out) {
  if (name == "frames" || name == "f") *out = DeltaUnit::kFrames;
  else if (name == "m" || name == "meters") *out = DeltaUnit::kMeters;
  else return false;
  return true;
}

const char* DeltaUnitName(DeltaUnit unit) { return unit == DeltaUnit::kFrames ? "frames" : "m"; }

Status AssociateTrajectories(const Trajectory& ref, const Trajectory& est, double max_diff_s, Trajectory* ref_out,
                             Trajectory* est_out) {
  const bool est_longer = est.size() > ref.size();
  const Trajectory& shorter = est_longer ? ref : est;
  const Trajectory& longer = est_longer ? est : ref;
  Trajectory short_out, long_out;
  if (!longer.empty()) {
    for (const auto& sp : shorter) {
      const size_t j = NearestIndex(longer, sp.t_s);
      if (std::abs(longer[j].t_s - sp.t_s) <= max_diff_s) {
        short_out.push_back(sp);
        long_out.push_back(longer[j]);
      }
    }
  }
  if (short_out.empty()) {
    return Status::Error("association: no matching timestamps between reference (" + std::to_string(ref.size()) +
                         " poses) and estimate (" + std::to_string(est.size()) + " poses) with max. time diff " +
                         std::to_string(max_diff_s) + " s");
  }
  *ref_out = est_longer ? std::move(short_out) : std::move(long_out);
  *est_out = est_longer ? std::move(long_out) : std::move(short_out);
  return Status::Ok();
}

Status ComputeApeErrors(const Trajectory& ref, const Trajectory& est, PoseRelation relation,
                        std::vector<double>* errors) {
  if (ref.size() != est.size()) {
    return Status::Error("APE: trajectories must have the same number of poses (" + std::to_string(ref.size()) +
                         " vs " + std::to_string(est.size()) + ")");
  }
  errors->resize(ref.size());
  for (size_t i = 0; i < ref.size(); ++i) {
    if (relation == PoseRelation::kTranslation) {
      (*errors)[i] = (est[i].T_ref_body.translation() - ref[i].T_ref_body.translation()).norm();
    } else {
      (*errors)[i] = ErrorOf(est[i].T_ref_body.inverse() * ref[i].T_ref_body, relation);
    }
  }
  return Status::Ok();
}

Status ComputeIdPairs(const Trajectory& poses, const RpeOptions& options, std::vector<IdPair>* pairs) {
  pairs->clear();
  const double delta = options.delta;
  if (!(delta > 0.0) || !std::isfinite(delta)) return Status::Error("RPE: delta must be positive");
  if (options.delta_unit == DeltaUnit::kFrames) {
    if (delta != std::floor(delta)) return Status::Error("RPE: delta must be an integer for delta unit frames");
    PairsByIndex(poses.size(), static_cast<size_t>(delta), options.all_pairs, pairs);
  } else if (options.all_pairs) {
    PairsByPathAll(poses, delta, delta * options.rel_delta_tol, pairs);
  } else {
    PairsByPathConsecutive(poses, delta, pairs);
  }
  if (pairs->empty()) {
    return Status::Error("RPE: delta = " + std::to_string(delta) + " (" + DeltaUnitName(options.delta_unit) +
                         ") produced an empty index list among " + std::to_string(poses.size()) +
                         " poses - try lower values or a less strict tolerance");
  }
  return Status::Ok();
}

Status ComputeRpeErrors(const Trajectory& ref, const Trajectory& est, const RpeOptions& options,
                        std::vector<double>* errors, std::vector<IdPair>* pairs) {
  if (ref.size() != est.size()) {
    return Status::Error("RPE: trajectories must have the same number of poses (" + std::to_string(ref.size()) +
                         " vs " + std::to_string(est.size()) + ")");
  }
  std::vector<IdPair> ids;
  if (Status s = ComputeIdPairs(options.pairs_from_reference ? ref : est, options, &ids); !s) return s;
  errors->resize(ids.size());
  for (size_t k = 0; k < ids.size(); ++k) {
    const auto [i, j] = ids[k];
    const Pose3 Q_rel = ref[i].T_ref_body.inverse() * ref[j].T_ref_body;
    const Pose3 P_rel = est[i].T_ref_body.inverse() * est[j].T_ref_body;
    (*errors)[k] = ErrorOf(Q_rel.inverse() * P_rel, options.relation);
  }
  if (pairs) *pairs = std::move(ids);
  return Status::Ok();
}

}  // namespace rotolidar::bench
