#include "bench/run/truth_eval.hpp"

#include "bench/eval/trajectory_lookup.hpp"
#include "core/io/trajectory_io.hpp"

namespace rotolidar::bench {

Status EvaluateAgainstTruth(const std::string& recording_dir, const Trajectory& estimate, EvalResult* result) {
  Trajectory truth;
  const std::string path = recording_dir + "/truth/base.tum";
  if (Status s = ReadTrajectory(path, TrajectoryFormat::kTum, &truth); !s) return s;
  return EvaluateAgainstTruth(truth, path, estimate, result);
}

Status EvaluateAgainstTruth(const Trajectory& truth, const std::string& path, const Trajectory& estimate,
                            EvalResult* result) {
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
