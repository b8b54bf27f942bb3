#pragma once
// The seed's LiDAR features (Section 3.1, Eq. 3 = LOAM's curvature): per ring, in firing order, each point's
// curvature over +-N same-ring neighbours; each ring split into equal azimuth sectors; per sector the sharpest
// points become edges and the flattest planar points, after LOAM's rejection of occluded and beam-parallel points
// and with neighbour suppression after every pick. Maths, defaults and their derivation: docs/features.md.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/features/feature_set.hpp"
#include "core/preprocess/filters.hpp"
#include "core/types/time.hpp"

namespace rotolidar {

struct FeatureConfig {
  int sectors = 12;               ///< equal sectors of VLP-16 azimuth per ring (seed: 12); sector = floor(az / (360/S))
  int edges_per_sector = 4;       ///< at most this many edge points per (ring, sector) (seed: 4)
  /// At most this many planar points per (ring, sector). The seed takes 4; a rotary VLP-16 scan is a 30 deg fan,
  /// so registration needs more planar points than a full revolution gives at 4 (why 20: docs/estimator.md,
  /// "Defaults that differ from the modules'").
  int planars_per_sector = 20;
  int less_sharp_per_sector = 20; ///< map-side edge set per (ring, sector), a superset of the edges (LOAM: 20)
  int neighbours = 5;             ///< N: curvature window +-N same-ring points, |S| = 2N (LOAM: 5)
  /// Eq. 3 thresholds (dimensionless). c of a bend by angle phi seen at normal incidence with azimuth step da [rad]
  /// is (N+1)/2 * sin(phi/2) * da; with N = 5 at 600 rpm (da = 0.2 deg): 90 deg corner 0.0074, 45 deg 0.0040,
  /// 15 deg 0.0014. Scale both linearly with the head's spin rate.
  double edge_threshold = 0.004;     ///< c above: edge candidate (a 45 deg bend at 0.2 deg steps)
  double planar_threshold = 0.0014;  ///< c below: planar candidate (a 15 deg bend at 0.2 deg steps)
  /// Noise gate: range noise sigma_r makes c noisy with sigma_c(r) = sigma_r sqrt(4N^2 + 2N) / (2N r), so an edge
  /// (and a less-sharp point) also needs c > edge_min_snr * sigma_c(r); below that a point counts as not-sharp.
  /// 1 cm = the real VLP-16's noise measured on $ROTOLIDAR_DATA/vlp16_einride (docs/features.md); the sim's default
  /// is 3 cm. 0 disables the gate (the seed's fixed threshold only).
  double range_sigma_m = 0.01;
  /// 3 with 1 cm would be A-LOAM's unnormalised |sum|^2 > 0.1 m^2 rule; 5 keeps noise out of the edge set on
  /// the rotary rig's near-range returns (docs/features.md).
  double edge_min_snr = 5.0;
  /// The gate's sigma grows on oblique surfaces: sigma_r / max(cos(incidence), range_sigma_min_cos)^exponent,
  /// tan(incidence) the mean of the range slopes over N steps on both sides. The beam's footprint stretches by
  /// 1/cos on an oblique surface and its echo spreads in range with it; the real VLP-16 capture's noise grows
  /// faster still (docs/lidar_model.md). Without it, range noise on oblique walls passes the gate as edges that
  /// pull registration along weakly observed axes (docs/features.md, "Oblique surfaces"). 0 = one sigma for all.
  double range_sigma_incidence_exponent = 1.0;
  double range_sigma_min_cos = 0.26;  ///< cos(75 deg): the beam-parallel rule rejects anything more oblique
  /// Consecutive same-ring points farther apart in azimuth are not neighbours (dropouts, the scan seam): no window
  /// crosses such a gap, no occlusion is declared across it. 2.5x the step at the VLP-16's fastest 1200 rpm.
  double max_neighbour_step_deg = 1.0;
  bool reject_occluded = true;
  /// A depth jump between neighbours: |r_a - r_b| > max(occlusion_min_jump_m, occlusion_jump_ratio * min(r_a, r_b)).
  /// The farther side's N+1 points next to it are rejected (LOAM).
  double occlusion_min_jump_m = 0.3;  ///< A-LOAM's sqrt(0.1) m gap; 7 sigma of the difference of two 3 cm ranges
  double occlusion_jump_ratio = 0.1;  ///< relative jump (88 deg incidence at 0.2 deg steps is needed to reach it)
  bool reject_beam_parallel = true;
  /// Rejected when the surface's incidence angle, estimated from the range slope over N steps on BOTH sides
  /// (tan(beta) = dr / (r dgamma)), exceeds this. A-LOAM's 0.0002 r^2 gap rule is 75.7 deg at 0.2 deg steps.
  double beam_parallel_max_incidence_deg = 75.0;
  /// Scan-side planar set downsampling: one point per voxel of this edge (the one nearest the voxel's centroid,
  /// VoxelRepresentatives) [m]; 0 keeps every selected point (the seed's per-sector counts). A rotary band puts
  /// many planar points within centimetres of each other near the rig; A-LOAM's mapping thins its surface
  /// points to 0.4 m the same way. Finite, >= 0. Default 0.25 m, chosen with neighbour reuse and the rotary
  /// keyframe policy (why: docs/features.md, 'Scan-side thinning').
  double planar_voxel_m = 0.25;
  /// Map-side planar set downsampling [m] (LOAM: 0.2 m); 0 keeps every point. Finite, >= 0. Default 0.3 m,
  /// chosen together with planar_voxel_m (why: docs/features.md, 'Scan-side thinning').
  double less_flat_voxel_m = 0.3;
  int threads = 0;  ///< worker threads; 0 = std::thread::hardware_concurrency(); results never depend on it
  /// False (and *error names the field, e.g. "features.sectors must be in [1, 360] (got 0)") if a value is invalid.
  bool Validate(std::string* error) const;
};

/// What became of each input point (FeatureResult::labels, indexed like the input).
enum class FeatureLabel : uint8_t {
  kInvalid = 0,    ///< non-finite or non-positive range: not ordered into its ring at all
  kNoWindow,       ///< fewer than N contiguous neighbours on a side (ring ends, dropouts): no curvature
  kOccluded,       ///< on the far side of a depth jump (LOAM)
  kBeamParallel,   ///< on a surface nearly parallel to the beam (LOAM)
  kUnused,         ///< valid curvature, selected for no set (between the thresholds, suppressed, or over quota)
  kEdge,           ///< in edge (and in less_sharp)
  kLessSharp,      ///< in less_sharp only
  kPlanar,         ///< in planar (and in the less_flat input)
  kLessFlat,       ///< in the less_flat input only (c below the edge threshold at its range)
};

struct FeatureStats {
  std::size_t num_input = 0;
  std::size_t num_invalid = 0, num_no_window = 0, num_occluded = 0, num_beam_parallel = 0;
  std::size_t num_edge = 0, num_planar = 0, num_less_sharp = 0;  ///< sizes of the FeatureSet clouds
  std::size_t num_less_flat_raw = 0;  ///< less_flat points before voxel downsampling
  std::size_t num_less_flat = 0;      ///< after
};

struct FeatureResult {
  FeatureSet features;
  FeatureStats stats;
  std::vector<FeatureLabel> labels;  ///< one per input point
  std::vector<float> curvature;      ///< one per input point: Eq. 3's c, NaN where there is no window
};

/// Extracts the features of one deskewed scan. `points`: any order (each ring is sorted by firing time here), one
/// return per firing (filter dual returns upstream), p_base in the base frame at t_scan_start_s. Output clouds are
/// in that frame (FeatureSet::t_s = t_scan_start_s), intensity = c. Sets are merged in sector order, then ring
/// order, so the result is bit-identical for every thread count. ROTOLIDAR_CHECKs config.Validate().
/// Thread-safe (no shared state); uses up to config.threads threads internally.
FeatureResult ExtractFeatures(const std::vector<ScanPoint>& points, Seconds t_scan_start_s,
                              const FeatureConfig& config);

/// Eq. 3 for one ring in firing order: c_i = |sum_{j in S} (X_i - X_j)| / (|S| * range_i), S = the N points on
/// each side; NaN where a side has fewer than N points or a step between window points exceeds max_step_deg.
std::vector<float> RingCurvature(const std::vector<ScanPoint>& ring, int neighbours, double max_step_deg);

}  // namespace rotolidar
