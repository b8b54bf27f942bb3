#pragma once
// A trajectory: time-stamped poses of one body frame in a fixed frame.
#include <vector>

#include "core/types/geometry.hpp"
#include "core/types/time.hpp"

namespace rotolidar {

/// T_ref_body at time t_s: maps points from the body frame (e.g. base) into the reference frame (e.g. world).
struct StampedPose {
  Seconds t_s = 0.0;
  Pose3 T_ref_body = Pose3::Identity();
};

using Trajectory = std::vector<StampedPose>;  ///< sorted by time (non-decreasing: real datasets repeat stamps)

}  // namespace rotolidar
