#pragma once
// Trajectory error metrics with evo's exact definitions (github.com/MichaelGrupp/evo: evo/core/sync.py,
// evo/core/filters.py, evo/core/metrics.py), so numbers here can be compared one to one with `evo_ape` /
// `evo_rpe`. Poses are T_ref_body (body -> reference frame); errors are per pose (APE) or per pose pair (RPE).
// Failures (no matches, size mismatch, no pairs) are returned as Status with a message; nothing throws.
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

/// What part of an error pose E is measured (evo's PoseRelation).
enum class PoseRelation {
  kTranslation,       ///< ||t(E)|| [m]                      (evo trans_part)
  kRotationAngleDeg,  ///< |angle of R(E)| [deg]             (evo angle_deg)
  kRotationAngleRad,  ///< |angle of R(E)| [rad]             (evo angle_rad)
  kRotationPart,      ///< ||R(E) - I||_F, unitless          (evo rot_part)
  kFull,              ///< ||E - I_4x4||_F, unitless         (evo full)
};

/// "trans_part"|"trans", "angle_deg"|"rot", "angle_rad", "rot_part", "full" -> relation; false otherwise.
bool ParsePoseRelation(const std::string& name, PoseRelation* out);
const char* PoseRelationName(PoseRelation relation);
const char* PoseRelationUnit(PoseRelation relation);  ///< "m", "deg", "rad" or "" (unitless)

enum class DeltaUnit { kFrames, kMeters };
bool ParseDeltaUnit(const std::string& name, DeltaUnit* out);  ///< "frames"|"f", "m"|"meters"
const char* DeltaUnitName(DeltaUnit unit);

using IdPair = std::pair<size_t, size_t>;  ///< (i, j) with i < j, indices into the associated trajectories

/// evo's associate_trajectories: the trajectory with fewer poses (est when equal) is the "short" one; each of
/// its poses is matched with the first pose of the other whose time is nearest, kept when |dt| <= max_diff_s.
/// A pose of the long trajectory may be matched more than once (as in evo). Outputs hold the matched poses in
/// the order of the short trajectory, index i of both being one association. Error when nothing matches.
Status AssociateTrajectories(const Trajectory& ref, const Trajectory& est, double max_diff_s, Trajectory* ref_out,
                             Trajectory* est_out);

/// evo's geometry.accumulated_distances: path length travelled up to each pose [m] (0, then the running sum of
/// step lengths; also the KITTI devkit's trajectoryDistances).
std::vector<double> AccumulatedDistances(const Trajectory& poses);

/// APE per pose of already associated (and aligned) trajectories of equal size:
/// E_i = est_i^-1 * ref_i; kTranslation uses ||p_est_i - p_ref_i|| (= ||t(E_i)||), as evo does.
Status ComputeApeErrors(const Trajectory& ref, const Trajectory& est, PoseRelation relation,
                        std::vector<double>* errors);

struct RpeOptions {
  PoseRelation relation = PoseRelation::kTranslation;
  double delta = 1.0;                  ///< frames (a positive integer) or metres of travelled path
  DeltaUnit delta_unit = DeltaUnit::kFrames;
  bool all_pairs = false;              ///< false: consecutive non-overlapping pairs
  double rel_delta_tol = 0.1;          ///< metres + all_pairs: accept |path - delta| <= delta * rel_delta_tol
  bool pairs_from_reference = false;   ///< pick pairs on the reference path (evo default: on the estimate)
};

/// evo's id_pairs_from_delta on the positions of `poses`:
///  frames, consecutive: (0, d), (d, 2d), ...; frames, all: (i, i + d) for every i.
///  metres, consecutive: ids where the path accumulated since the previous id reaches delta (the first id is the
///    first such pose, not pose 0), pairs between consecutive ids.
///  metres, all: for each i the j > i whose accumulated path from i is nearest delta, kept within the tolerance.
/// Error when delta is invalid or no pair results.
Status ComputeIdPairs(const Trajectory& poses, const RpeOptions& options, std::vector<IdPair>* pairs);

/// RPE per pair: E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j), Q = reference, P = estimate; measured per `relation`.
/// Inputs are associated trajectories of equal size. `pairs` (optional) receives the pairs used.
Status ComputeRpeErrors(const Trajectory& ref, const Trajectory& est, const RpeOptions& options,
                        std::vector<double>* errors, std::vector<IdPair>* pairs = nullptr);

}  // namespace rotolidar::bench
