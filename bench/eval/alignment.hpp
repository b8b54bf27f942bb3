#pragma once
// Trajectory alignment on positions, as evo does before APE (`-a`, `-a -s`; evo/core/geometry.py
// umeyama_alignment), plus a 4-DOF position + yaw alignment for gravity-aligned estimators (VIO/LIO).
//
// All functions find the similarity x -> scale * R * x + t that maps the estimate's positions p_est onto the
// reference's p_ref in the least-squares sense (Umeyama 1991). "ref" is the reference frame of the reference
// trajectory; the result's T_ref_est maps estimate-frame points into it (after scaling them by `scale`).
// Failure (degenerate geometry, size mismatch) is returned in the result, never thrown.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/types/geometry.hpp"
#include "core/types/trajectory.hpp"

namespace rotolidar::bench {

enum class Alignment {
  kNone,    ///< identity
  kSe3,     ///< rotation + translation (evo `-a`)
  kSim3,    ///< rotation + translation + scale (evo `-a -s`)
  kPosYaw,  ///< translation + rotation about z of the reference frame only (4-DOF)
};

/// "none", "se3", "sim3", "posyaw" -> alignment; false (out untouched) otherwise.
bool ParseAlignment(const std::string& name, Alignment* out);
const char* AlignmentName(Alignment alignment);

struct AlignmentResult {
  bool success = false;
  std::string message;                       ///< why it failed; empty on success
  Pose3 T_ref_est = Pose3::Identity();       ///< rotation R and translation t [m]
  double scale = 1.0;                        ///< 1 unless Sim(3)
};

/// Aligns p_est onto p_ref (same size, index i of both is one association).
/// Se3 / Sim3: Umeyama; fails when fewer than 3 points or the cross-covariance has rank < 2 (evo's rule,
/// with a relative threshold 1e-12 on the singular values), or for Sim3 when p_est has zero spread.
/// PosYaw: closed-form yaw about z, then t; fails with fewer than 2 points or no horizontal spread.
/// None: identity, always succeeds (even for empty input).
AlignmentResult AlignPositions(const std::vector<Eigen::Vector3d>& p_est, const std::vector<Eigen::Vector3d>& p_ref,
                               Alignment alignment);

/// Positions of a trajectory, in order.
std::vector<Eigen::Vector3d> Positions(const Trajectory& traj);

/// evo's trajectory.align: each pose T becomes [R * R_T | scale * R * t_T + t] (rotations are not scaled).
Trajectory ApplyAlignment(const AlignmentResult& alignment, const Trajectory& traj);

}  // namespace rotolidar::bench
