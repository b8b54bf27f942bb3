#pragma once
// Degeneracy of scan-to-map registration (Zhang, Kaess, Singh, ICRA 2016, "On degeneracy of optimization-based
// state estimation problems"): eigen-analysis of the registration Hessian H = J^T J, detection of directions the
// scan geometry does not observe (eigenvalue below a threshold), and "solution remapping": the update is projected
// onto the well-observed eigen-subspace so that degenerate directions keep their prior value (the motion prior /
// IMU then owns them).
//
// Tangent ordering: delta = [dt (m, map frame); dtheta (rad, map frame)] (core/registration/residuals.hpp).
// Units: translation and rotation differ, so raw eigenvalues of H depend on arbitrary scaling. We measure every
// direction by the motion it causes on the matched points: with lever arms r_i = R p_i (scan point relative to
// the scan origin, map orientation), a small delta moves point i by A_i delta, A_i = [I, -[r_i]x], and
//   G = (1/N) sum_i A_i^T A_i                (the "displacement metric": delta^T G delta = mean squared motion)
// The analysis solves the generalised problem  (H / N) v = lambda G v.  lambda is dimensionless: the squared
// residual change per squared point motion, per correspondence. A plane sees the motion along its normal, so a
// direction seen by all planes head-on has lambda ~ 1 and one seen by nobody has lambda ~ 0 (plus a noise floor
// from the map's normal noise: docs/registration.md, 'Degeneracy'); this holds for rotations about any axis and
// for any scan size or scale. Eigenvectors are G-orthonormal (v^T G v = 1: a unit step moves points by 1 m RMS).
// Pure Eigen; thread-safe (no state).
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rotolidar {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct DegeneracyConfig {
  bool remap = true;  ///< project updates onto the well-observed subspace (false: detect and report only)
  /// A direction is degenerate when its generalised eigenvalue lambda (see above, dimensionless) is below this.
  /// Finite, >= 0. Default 0.005: low enough that an axis seen only through a far end wall is measured (then
  /// gated as weak, below) rather than left to the prior (why: docs/registration.md, 'Degeneracy').
  double min_eigenvalue = 0.005;
  /// Weak directions (min_eigenvalue <= lambda < weak_eigenvalue) rest on a few points: a far end wall, or a
  /// person walking by. Their estimate is an innovation against the guess (the motion prior); it is kept only
  /// when it moves the matched points by at most weak_gate_m RMS along the direction (|v^T G delta|), otherwise
  /// the direction is treated as degenerate (remapped; the prior / IMU keeps it).
  double weak_eigenvalue = 0.05;
  /// [m] RMS point motion along a weak direction, guess -> solution. 0.1: a person's trail in the map pulled an
  /// axis by 5-30 cm per scan, while an IMU-held axis may drift past a few cm during a weak stretch and must still
  /// be corrected when the LiDAR sees it again (docs/registration.md, 'Degeneracy').
  double weak_gate_m = 0.1;
  bool Validate(std::string* error) const;  ///< false with the offending field named in *error
};

/// Per-scan degeneracy report.
struct DegeneracyInfo {
  bool degenerate = false;                        ///< at least one eigenvalue below the threshold
  Vector6d eigenvalues = Vector6d::Zero();        ///< lambda, ascending (dimensionless)
  Matrix6d eigenvectors = Matrix6d::Identity();   ///< columns v, G-orthonormal, original tangent [dt; dtheta]
  /// Degenerate directions (the eigenvectors below threshold), original tangent, scaled to unit Euclidean norm.
  std::vector<Vector6d> degenerate_directions;
  /// Remapping matrix, original tangent: delta_applied = projection * delta_full = sum over well-observed v of
  /// v v^T G delta (G-orthogonal projection: removes exactly the degenerate components). Identity if none.
  Matrix6d projection = Matrix6d::Identity();
  Matrix6d displacement_metric = Matrix6d::Identity();  ///< the G the analysis used
};

/// G = (1/N) sum A_i^T A_i for lever arms r_i = R p_i [m] (see above). Empty input -> identity.
Matrix6d DisplacementMetric(const std::vector<Eigen::Vector3d>& lever_arms_m);

/// Eigen-analysis of the registration Hessian (6x6, symmetric, original tangent, e.g. ScanToMapResult::hessian)
/// against the displacement metric G of the same correspondences. num_correspondences = N >= 1 and G symmetric
/// positive definite are programmer errors otherwise (ROTOLIDAR_CHECK).
DegeneracyInfo AnalyzeDegeneracy(const Matrix6d& hessian, const Matrix6d& displacement_metric,
                                 int num_correspondences, const DegeneracyConfig& config);

/// The remapping matrix that removes the `num_smallest` lowest eigen-directions of `info` (whatever their
/// eigenvalues): sum over the other eigenvectors of v v^T G. num_smallest in [0, 6]; 0 gives the identity.
Matrix6d ProjectionWithout(const DegeneracyInfo& info, int num_smallest);

/// Marks at least the num lowest eigen-directions of *info degenerate (flag, directions, projection); a no-op
/// when that many or more already are. num in [0, 6].
void MarkDegenerate(int num, DegeneracyInfo* info);

/// How many of the lowest eigen-directions to remap given the solve's update delta_from_guess (original tangent,
/// solution boxminus guess): those below min_eigenvalue and the weak ones whose component |v^T G delta| exceeds
/// weak_gate_m, together with every direction below them (remapping removes a lowest-k set).
int GatedDegenerateCount(const DegeneracyInfo& info, const Vector6d& delta_from_guess, const DegeneracyConfig& config);

/// Solution remapping: the well-observed part of a full tangent update (projection * delta).
Vector6d RemapUpdate(const DegeneracyInfo& info, const Vector6d& delta);

}  // namespace rotolidar
