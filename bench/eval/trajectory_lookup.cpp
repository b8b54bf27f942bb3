// Trajectory lookup at other times (contract in trajectory_lookup.hpp).
#include "bench/eval/trajectory_lookup.hpp"

#include <algorithm>

namespace rotolidar::bench {

bool PoseAt(const Trajectory& trajectory, Seconds t_s, Pose3* T) {
  if (trajectory.empty() || !(t_s >= trajectory.front().t_s) || !(t_s <= trajectory.back().t_s)) return false;
  const auto it = std::lower_bound(trajectory.begin(), trajectory.end(), t_s,
                                   [](const StampedPose& p, Seconds t) { return p.t_s < t; });
  if (it->t_s == t_s || it == trajectory.begin()) {
    *T = it->T_ref_body;
    return true;
  }
  const StampedPose& a = *(it - 1);
  const StampedPose& b = *it;
  *T = Interpolate(a.T_ref_body, b.T_ref_body, (t_s - a.t_s) / (b.t_s - a.t_s));
  return true;
}

Trajectory InterpolateTrajectory(const Trajectory& ref, const Trajectory& at_times_of) {
  Trajectory out;
  if (ref.size() < 2) return out;
  for (const StampedPose& q : at_times_of) {
    const auto it = std::lower_bound(ref.begin(), ref.end(), q.t_s,
                                     [](const StampedPose& p, Seconds t) { return p.t_s < t; });
    if (it == ref.end()) continue;
    if (it == ref.begin()) {
      if (it->t_s == q.t_s) out.push_back(*it);
      continue;
    }
    const StampedPose& a = *(it - 1);
    const StampedPose& b = *it;
    const double s = (q.t_s - a.t_s) / (b.t_s - a.t_s);
    out.push_back({q.t_s, Interpolate(a.T_ref_body, b.T_ref_body, s)});
  }
  return out;
}

}  // namespace rotolidar::bench
