#pragma once
// Errors against the sim's ground truth (truth/ of a recording; only bench/ reads it).
#include <string>

#include "bench/run/eval_run.hpp"
#include "core/types/trajectory.hpp"

namespace rotolidar::bench {

/// APE (translation, SE(3) Umeyama) of `estimate` (T_world_base) against <recording>/truth/base.tum, with the
/// truth interpolated at the estimate's own timestamps (exact association, no 10 ms nearest-neighbour slack).
Status EvaluateAgainstTruth(const std::string& recording_dir, const Trajectory& estimate, EvalResult* result);
/// The same against a truth trajectory already read (`truth_path` names it in errors).
Status EvaluateAgainstTruth(const Trajectory& truth, const std::string& truth_path, const Trajectory& estimate,
                            EvalResult* result);

}  // namespace rotolidar::bench
