#pragma once
// KITTI odometry 00, frames 0-10 ($ROTOLIDAR_DATA/kitti00), and the references the realdata tests compare LiDAR
// odometry with. KITTI's official ground truth is wrong for the first ~13 frames of sequence 00 (a constant
// 0.86 m per frame, while the car accelerates from ~0.68 to ~0.82 m per frame), so the references are two
// independent stereo SLAM results, ORB-SLAM2 and S-PTAM, per frame pair in the LiDAR frame.
#include <cmath>
#include <string>
#include <vector>

#include "core/io/kitti.hpp"
#include "core/types/geometry.hpp"

namespace rotolidar::testdata {

constexpr size_t kKitti00Frames = 11;  ///< kitti00 holds velodyne/000000.bin .. 000010.bin

// Bounds against the stereo references, which are estimates too: ORB-SLAM2 and S-PTAM disagree with each other by
// 0.9-3.7 cm (RMS 2.7 cm) and 0.05-0.24 deg per step on these frames. Per step (either reference): 4.5 cm and
// 0.3 deg, just above that disagreement (measured: <= 2.8 cm / 0.15 deg from ORB-SLAM2, <= 4.0 cm / 0.27 deg from
// S-PTAM, for the registration and the runner). Over the ten steps, each test also requires our RMS distance to
// each reference to stay below the references' RMS distance to each other. A lost or half-converged step (off by
// a good part of the ~0.75 m step) fails both by far.
constexpr double kMaxStereoStepM = 0.045;
constexpr double kMaxStereoStepDeg = 0.3;

inline double Rms(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / double(v.size()));
}

inline double TranslationError(const Pose3& a, const Pose3& b) { return (a.translation() - b.translation()).norm(); }
inline double RotationErrorDeg(const Pose3& a, const Pose3& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

/// LiDAR-frame steps of a cam0 poses file of frames 0-10: T_velo(k)_velo(k+1) = Tr^-1 * P_k^-1 * P_k+1 * Tr, with
/// P_k = T_cam0(0)_cam0(k) and Tr = T_cam0_velo (calib_00.txt). Fails naming the file when it is unreadable or
/// does not hold 11 poses.
inline Status ReadVeloSteps(const std::string& path, const Pose3& T_cam0_velo, std::vector<Pose3>* steps) {
  std::vector<Pose3> cam0;
  if (Status s = ReadKittiPoses(path, &cam0); !s) return s;
  if (cam0.size() != kKitti00Frames)
    return Status::Error(path + ": expected 11 poses, got " + std::to_string(cam0.size()));
  for (size_t k = 0; k + 1 < cam0.size(); ++k)
    steps->push_back(Cam0ToVeloPose(T_cam0_velo, cam0[k].inverse() * cam0[k + 1]));
  return Status::Ok();
}

}  // namespace rotolidar::testdata
