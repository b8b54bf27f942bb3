#pragma once
// Feature-based scan-to-map registration (seed Sec. 3 / LOAM mapping): scan edge points are matched to lines and
// scan planar points to planes fitted to their k nearest map features, and T_map_scan is solved with Ceres
// (analytic point-to-line / point-to-plane Jacobians, core/registration/residuals.hpp) under a robust loss.
// Outer loop: find correspondences at the current pose -> Ceres solve -> repeat until the update is small (or the
// loop has closed into a 2-cycle of two correspondence sets, which no further rebuild leaves: then it stops with
// the state max_correspondence_rebuilds would have left, converged = false; docs/registration.md).
// Degeneracy (core/registration/degeneracy.hpp): the converged full solve's Hessian is analysed; if a direction
// is degenerate and remapping is enabled, the outer loop runs again from the guess with every update projected
// onto the well-observed subspace (solution remapping), so degenerate directions keep the guess's value.
//
// Frames: scan features are in the scan frame (base at scan start, FeatureSet); the map is in the map (world)
// frame; the result is T_map_scan. Tangent ordering of the Hessian: [dt (m, map frame); dtheta (rad, map frame)],
// the manifold's Plus t <- t + dt, R <- Exp(dtheta) R. Thread-safety: Register is re-entrant for distinct maps;
// LocalMap itself is not thread-safe. Failure: result.converged = false with result.message; never throws on
// data (an invalid config is a programmer error: ROTOLIDAR_CHECK).
#include <string>
#include <vector>

#include "core/features/feature_set.hpp"
#include "core/registration/degeneracy.hpp"
#include "core/registration/local_fits.hpp"
#include "core/registration/local_map.hpp"
#include "core/types/geometry.hpp"

namespace rotolidar {

enum class RobustLoss { kNone, kHuber, kCauchy };

struct ScanToMapConfig {
  int max_solver_iterations = 8;          ///< Ceres Levenberg-Marquardt iterations per correspondence set
  int max_correspondence_rebuilds = 12;   ///< outer iterations (correspondences re-found at the current pose)
  int num_neighbours = 5;                 ///< k map neighbours per scan point (LOAM: 5)
  /// A point's neighbour set (and its line / plane fit) is reused by later outer iterations while the transformed
  /// point stays within this distance of where the set was searched [m]. 0: only while the set is provably
  /// still the k nearest (half the gap between the k-th and (k+1)-th distance); above it the set is an
  /// approximation, as LOAM's, which re-searches every 5th iteration only. >= 0. Default 0.05 m (a quarter of the
  /// map's 0.2 m voxels): half the register time of 0 at about the same ATE (why: docs/registration.md,
  /// 'Neighbour reuse').
  double neighbour_reuse_m = 0.05;
  double max_neighbour_distance_m = 1.0;  ///< the k-th neighbour must be this close to the transformed point [m]
  double min_line_eigen_ratio = 3.0;      ///< edge: lambda_max >= ratio * lambda_mid of the neighbours (LOAM: 3)
  double max_plane_eigen_ratio = 0.25;    ///< plane: lambda_min <= ratio * lambda_mid (rejects collinear sets)
  double max_plane_deviation_m = 0.2;     ///< plane: every neighbour within this of the fitted plane (LOAM: 0.2)
  /// Plane residuals are weighted by max(|cos incidence|, plane_incidence_min_cos)^plane_incidence_exponent, the
  /// incidence between the ray to the scan point and the map plane's normal: a return's range noise grows on
  /// oblique surfaces, by how much depends on the sensor and its window. 0.5 down-weights a grazing ground
  /// point 3.2x: on the harsh twin (range noise x cos^-2.5) the car's median ATE over 10 seeds falls 10x, on
  /// typical (noise flat along the normal) ATE moves within its seed spread (docs/registration.md, 'oblique
  /// planes').
  /// 0: every plane residual weighs the same. [0, 4].
  double plane_incidence_exponent = 0.5;
  double plane_incidence_min_cos = 0.1;   ///< floor of |cos incidence| in the weight, (0, 1] (0.1: 84 deg)
  RobustLoss loss = RobustLoss::kHuber;
  double loss_scale_m = 0.1;              ///< residual [m] where the robust loss departs from least squares
  double convergence_translation_m = 1e-3;  ///< converged when one outer update moves less than this ...
  double convergence_rotation_rad = 1e-4;   ///< ... and turns less than this
  /// Plane matches respect the side of the surface the map saw (LocalMap views): neighbours seen from the other
  /// side than the scan point are dropped (thin walls: the back face must not match the front face's plane).
  bool visibility_check = true;
  int min_correspondences = 20;           ///< fewer edge + planar matches -> not converged
  int num_threads = 1;                    ///< Ceres evaluation threads
  DegeneracyConfig degeneracy;
  bool Validate(std::string* error) const;  ///< false with the offending field named in *error
};

struct ScanToMapResult {
  bool converged = false;    ///< an outer update fell below the convergence thresholds
  bool remapped = false;     ///< the result of the second, remapped solve (degenerate scene, remap enabled)
  int iterations = 0;        ///< outer iterations (correspondence rebuilds) run, both solves summed
  int solver_iterations = 0; ///< Ceres iterations, summed
  int neighbour_searches = 0;  ///< map kNN searches, both solves (neighbour sets reused in between not counted)
  int edge_inliers = 0;      ///< accepted point-to-line correspondences of the last rebuild
  int planar_inliers = 0;    ///< accepted point-to-plane correspondences of the last rebuild
  double initial_cost = 0.0; ///< Ceres cost 1/2 sum rho(|r|^2) at the guess, first correspondences [m^2]
  double final_cost = 0.0;   ///< the same at the solution, last correspondences [m^2]
  double rmse_m = 0.0;       ///< RMS residual (no robust loss; plane ones incidence-weighted) at the solution [m]
  Pose3 T_map_scan = Pose3::Identity();
  /// J^T J at the solution (robust-weighted as Ceres applies the loss, plane rows incidence-weighted), 6x6 in the
  /// tangent [dt; dtheta]. Residuals are metres, so information = hessian / sigma_point^2 for a point noise
  /// sigma_point [m] (of a head-on plane point).
  Matrix6d hessian = Matrix6d::Zero();
  /// Eigen-analysis of `hessian` at the solution (for a remapped result: at the remapped solution).
  DegeneracyInfo degeneracy;
  std::string message;        ///< empty on success; otherwise why it failed
};

/// Registers the scan's edge and planar points (scan frame) against `map`, starting from T_map_scan_guess.
ScanToMapResult Register(const FeatureSet& scan, const LocalMap& map, const Pose3& T_map_scan_guess,
                         const ScanToMapConfig& config);

}  // namespace rotolidar
