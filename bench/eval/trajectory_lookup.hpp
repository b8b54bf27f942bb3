#pragma once
// Poses of a time-sorted trajectory at other times: linear in translation, slerp in rotation between the
// bracketing samples (core/types/geometry.hpp Interpolate). The one truth lookup the metrics, the truth
// evaluation and the KITTI export share; no I/O, no state.
#include "core/types/trajectory.hpp"

namespace rotolidar::bench {

/// The pose at t_s of a time-sorted trajectory: interpolated between the bracketing samples (the sample itself at
/// an exact stamp). False when t_s lies outside the trajectory's span.
bool PoseAt(const Trajectory& trajectory, Seconds t_s, Pose3* T);

/// The reference trajectory interpolated at the stamps of `at_times_of`. Stamps outside the reference's span are
/// dropped; `ref` must be sorted and hold >= 2 poses (else the result is empty).
Trajectory InterpolateTrajectory(const Trajectory& ref, const Trajectory& at_times_of);

}  // namespace rotolidar::bench
