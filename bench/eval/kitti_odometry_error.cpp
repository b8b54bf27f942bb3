#include "bench/eval/kitti_odometry_error.hpp"

#include <algorithm>
#include <cmath>

#include "bench/eval/trajectory_metrics.hpp"

namespace rotolidar::bench {
namespace {

/// The first pose whose path from `first` exceeds `length_m`; dist.size() when none (the devkit's
/// lastFrameFromSegmentLength; the path length never decreases, so a binary search finds it).
size_t LastOfSegment(const std::vector<double>& dist, size_t first, double length_m) {
  return size_t(std::upper_bound(dist.begin() + first, dist.end(), dist[first] + length_m) - dist.begin());
}

/// The devkit's rotationError: the angle of R(E), with the cosine clamped to [-1, 1] [rad].
double RotationAngle(const Pose3& E) {
  const double c = 0.5 * (E.linear().trace() - 1.0);
  return std::acos(std::clamp(c, -1.0, 1.0));
}

void SummariseByLength(const KittiOdometryOptions& options, KittiOdometryErrors* out) {
  double t_sum = 0.0, r_sum = 0.0;
  for (double length : options.lengths_m) {
    KittiLengthError e;
    e.length_m = length;
    for (const KittiSegmentError& s : out->segments) {
      if (s.length_m != length) continue;
      ++e.segments;
      e.t_rel_percent += s.t_err_per_m;
      e.r_rel_deg_per_100m += s.r_err_rad_per_m;
    }
    if (e.segments == 0) continue;
    t_sum += e.t_rel_percent;
    r_sum += e.r_rel_deg_per_100m;
    e.t_rel_percent *= 100.0 / double(e.segments);
    e.r_rel_deg_per_100m *= kDegPer100mPerRadPerM / double(e.segments);
    out->by_length.push_back(e);
  }
  const double n = double(out->segments.size());
  out->t_rel_percent = 100.0 * t_sum / n;
  out->r_rel_deg_per_100m = kDegPer100mPerRadPerM * r_sum / n;
}

}  // namespace

bool KittiOdometryOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = "KittiOdometryOptions: " + m;
    return false;
  };
  if (lengths_m.empty()) return fail("lengths_m is empty");
  for (double l : lengths_m)
    if (!(l > 0.0) || !std::isfinite(l)) return fail("every segment length must be > 0 m");
  if (step_frames < 1) return fail("step_frames must be >= 1");
  return true;
}

Status ComputeKittiOdometryErrors(const Trajectory& ref, const Trajectory& est, const KittiOdometryOptions& options,
                                  KittiOdometryErrors* out) {
  *out = KittiOdometryErrors();
  std::string why;
  if (!options.Validate(&why)) return Status::Error(why);
  if (ref.size() != est.size())
    return Status::Error("KITTI segment errors need associated trajectories of equal size (reference " +
                         std::to_string(ref.size()) + " poses, estimate " + std::to_string(est.size()) + ")");
  const std::vector<double> dist = AccumulatedDistances(ref);
  for (size_t first = 0; first < ref.size(); first += options.step_frames) {
    for (double length : options.lengths_m) {
      const size_t last = LastOfSegment(dist, first, length);
      if (last == ref.size()) continue;
      const Pose3 delta_ref = ref[first].T_ref_body.inverse() * ref[last].T_ref_body;
      const Pose3 delta_est = est[first].T_ref_body.inverse() * est[last].T_ref_body;
      const Pose3 E = delta_est.inverse() * delta_ref;
      KittiSegmentError s;
      s.first = first;
      s.last = last;
      s.length_m = length;
      s.t_err_per_m = E.translation().norm() / length;
      s.r_err_rad_per_m = RotationAngle(E) / length;
      const double dt = ref[last].t_s - ref[first].t_s;
      s.speed_mps = dt > 0.0 ? length / dt : 0.0;
      out->segments.push_back(s);
    }
  }
  if (out->segments.empty())
    return Status::Error("KITTI segment errors: the reference path (" + std::to_string(dist.empty() ? 0.0 : dist.back()) +
                         " m) is not longer than the shortest segment length");
  SummariseByLength(options, out);
  return Status::Ok();
}

}  // namespace rotolidar::bench
