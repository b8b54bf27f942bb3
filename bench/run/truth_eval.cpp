#include "bench/run/truth_eval.hpp"

#include <algorithm>

#include "core/io/trajectory_io.hpp"

namespace rotolidar::bench {

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

Status EvaluateAgainstTruth(const std::string& recording_dir, const Trajectory& estimate, EvalResult* result) {
  Trajectory truth;
  const std::string path = recording_dir + "/truth/base.tum";
  if (Status s = ReadTrajectory(path, TrajectoryFormat::kTum, &truth); !s) return s;
  const Trajectory ref = InterpolateTrajectory(truth, estimate);
  Trajectory est;
  for (const StampedPose& p : estimate)
    if (p.t_s >= truth.front().t_s && p.t_s <= truth.back().t_s) est.push_back(p);
  if (ref.size() != est.size() || ref.size() < 3)
    return Status::Error(path + ": truth does not cover the estimate (" + std::to_string(ref.size()) + " poses)");
  *result = ComputeApe(ref, est, Alignment::kSe3);
  return result->status;
}

}  // namespace rotolidar::bench
