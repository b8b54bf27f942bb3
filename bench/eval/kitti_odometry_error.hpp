#pragma once
// The KITTI odometry benchmark's relative errors (the devkit's evaluate_odometry.cpp, Geiger et al., CVPR 2012):
// from every 10th pose, for each segment length L in {100, 200, ..., 800} m of path travelled on the reference,
// the pose error over the segment E = (P_i^-1 P_j)^-1 (Q_i^-1 Q_j) (Q = reference, P = estimate; j = the first
// pose whose reference path from i exceeds L) gives a translation error ||t(E)|| / L and a rotation error
// angle(R(E)) / L. The benchmark's numbers are their means over all segments: t_rel [%] and r_rel [deg/100 m],
// the numbers KISS-ICP, LOAM and ORB-SLAM2 report on KITTI. Alignment-free (relative), but not scale-free.
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

/// r_rel's unit: rad/m -> deg/100 m.
constexpr double kDegPer100mPerRadPerM = 100.0 * 180.0 / M_PI;

struct KittiOdometryOptions {
  std::vector<double> lengths_m{100, 200, 300, 400, 500, 600, 700, 800};  ///< segment lengths [m] (devkit)
  size_t step_frames = 10;  ///< a segment starts at every step-th pose (devkit: 10 frames = 1 s at 10 Hz)
  bool Validate(std::string* error) const;
};

struct KittiSegmentError {
  size_t first = 0, last = 0;     ///< pose indices: the segment's start and the first pose past length_m
  double length_m = 0.0;          ///< nominal segment length L [m]
  double t_err_per_m = 0.0;       ///< ||t(E)|| / L [m/m]
  double r_err_rad_per_m = 0.0;   ///< angle(R(E)) / L [rad/m]
  double speed_mps = 0.0;         ///< L / (t_last - t_first) [m/s] (the devkit's speed, from the stamps)
};

struct KittiLengthError {
  double length_m = 0.0;
  size_t segments = 0;
  double t_rel_percent = 0.0;        ///< mean of t_err_per_m over this length's segments x 100
  double r_rel_deg_per_100m = 0.0;   ///< mean of r_err_rad_per_m x 100 m x 180/pi
};

struct KittiOdometryErrors {
  std::vector<KittiSegmentError> segments;  ///< in the devkit's order: by start pose, then by length
  std::vector<KittiLengthError> by_length;  ///< one entry per configured length that had a segment
  double t_rel_percent = 0.0;               ///< the benchmark's translation error: mean over all segments [%]
  double r_rel_deg_per_100m = 0.0;          ///< the benchmark's rotation error [deg / 100 m]
};

/// Segment errors of associated trajectories of equal size (pose i of one is pose i of the other). Fails when
/// the sizes differ, the options are invalid or the reference path is shorter than the shortest length.
Status ComputeKittiOdometryErrors(const Trajectory& ref, const Trajectory& est, const KittiOdometryOptions& options,
                                  KittiOdometryErrors* out);

}  // namespace rotolidar::bench
