#pragma once
// Scan preprocessing before feature extraction (seed Section 3.1): a range gate in the sensor frame, statistical
// outlier removal (seed Eq. 1-2, PCL's StatisticalOutlierRemoval) and an attribute-preserving voxel filter.
// Every stage keeps the surviving points in their input order (so rings stay in firing order) and reports how many
// points it removed: nothing is dropped silently. Maths and defaults: docs/features.md.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/types/messages.hpp"
#include "core/types/scan_point.hpp"
#include "core/types/time.hpp"

namespace rotolidar {

/// The largest K of RingStatisticalOutlierFilter (its neighbourhoods hold a few dozen candidates).
constexpr int kMaxRingSorK = 32;

/// Where SOR looks for each point's K nearest neighbours when it uses the scan's ring order (docs/features.md):
/// the same-ring returns within ring_window firings on each side, and on each of the adjacent_rings rings below and
/// above, the 2 * adjacent_window + 1 returns around the one fired closest in time. The K nearest of these
/// candidates (by distance in p_base) give the statistic.
struct SorNeighbourhood {
  int ring_window = 6;      ///< same-ring candidates per side [firings]
  int adjacent_rings = 1;   ///< rings searched below and above
  int adjacent_window = 2;  ///< candidates per side of the time-closest return on an adjacent ring [firings]
};

/// Preprocessing stages and their parameters. Stages run in the order range -> SOR -> voxel.
struct PreprocessConfig {
  bool enable_range = true;
  double min_range_m = 0.8;   ///< drop returns closer to the lidar than this (rig body, operator) [m]
  double max_range_m = 60.0;  ///< drop returns farther than this [m]
  bool enable_sor = true;
  int sor_k = 8;              ///< K: neighbours whose mean distance is each point's statistic (<= 32 ring mode)
  double sor_std_mul = 3.0;   ///< a point is an outlier when its statistic > mu + sor_std_mul * sigma
  /// Statistic = mean K-NN distance / range_m (scale-free: a LiDAR's point spacing grows with range). false = PCL's
  /// plain StatisticalOutlierRemoval, the seed's rule, which on a real indoor VLP-16 scan removes nearly every
  /// return beyond 8 m and none of the near ones (docs/features.md).
  bool sor_range_normalized = true;
  /// true: K nearest among the ring-order candidates (sor_neighbourhood: 22 candidates per point, linear time);
  /// false: exact K nearest over the whole scan (PCL's kd-tree; slower, cost and agreement: docs/features.md,
  /// 'Neighbour search'). Ring mode needs ring and t_s on the points (any input order).
  bool sor_ring_neighbours = true;
  SorNeighbourhood sor_neighbourhood;
  bool enable_voxel = false;  ///< off by default: downsampling before Eq. 3 distorts curvature (docs/features.md)
  double voxel_m = 0.1;       ///< voxel edge length [m]
  /// False (and *error names the field, e.g. "preprocess.sor_k must be >= 1 (got 0)") if a value is invalid;
  /// all values are checked, enabled or not.
  bool Validate(std::string* error) const;
};

/// Kept points plus what each stage removed. num_input = sum of all removed counts + points.size().
struct PreprocessResult {
  std::vector<ScanPoint> points;  ///< survivors, in input order
  std::size_t num_input = 0;
  std::size_t removed_nonfinite = 0;  ///< non-finite position or range (always removed: no stage accepts them)
  std::size_t removed_range = 0;
  std::size_t removed_sor = 0;
  std::size_t removed_voxel = 0;
};

/// Runs the enabled stages. ROTOLIDAR_CHECKs config.Validate() (an invalid config is a programmer error here:
/// validate configs where they are loaded). A deterministic pure function: safe to call concurrently.
PreprocessResult Preprocess(const std::vector<ScanPoint>& points, const PreprocessConfig& config);
/// The same, filtering `points` in place (no copy of the scan).
PreprocessResult Preprocess(std::vector<ScanPoint>&& points, const PreprocessConfig& config);

// ---- single stages: each compacts *points in place (order kept) and returns the number removed ----

/// Removes points with a non-finite position or range.
std::size_t RemoveNonFinite(std::vector<ScanPoint>* points);

/// Keeps min_range_m <= range_m <= max_range_m (sensor-frame range, so rig self-hits go whatever the rotor angle).
std::size_t RangeFilter(double min_range_m, double max_range_m, std::vector<ScanPoint>* points);

/// Statistical outlier removal on p_base (seed Eq. 1-2): d_i = mean distance to the K nearest neighbours, divided
/// by range_m when range_normalized; mu and sigma (sample) over all d_i; removes d_i > mu + std_mul * sigma (PCL's
/// one-sided rule; see docs/features.md for the seed's two-sided wording). range_normalized = false runs PCL's
/// StatisticalOutlierRemoval itself; true uses PCL's kd-tree with the same statistics. With K >= the number of
/// points every point is kept (no statistic). Finite positions required; normalised, a range <= 0 is an outlier.
std::size_t StatisticalOutlierFilter(int k, double std_mul, bool range_normalized, std::vector<ScanPoint>* points);

/// The same rule as StatisticalOutlierFilter with each point's K nearest neighbours searched among its ring-order
/// candidates (SorNeighbourhood) instead of the whole scan: d_i = mean distance to the K nearest candidates (all of
/// them when fewer than K). A point with no candidate has no statistic and is kept; normalised, a range <= 0 is an
/// outlier. Cost linear in the number of points. k >= 1 and hood's fields >= 0 (ROTOLIDAR_CHECK).
std::size_t RingStatisticalOutlierFilter(int k, double std_mul, bool range_normalized, const SorNeighbourhood& hood,
                                         std::vector<ScanPoint>* points);

/// The statistic behind RingStatisticalOutlierFilter, indexed like `points`: each point's mean distance [m] to its
/// K nearest ring-order candidates (all of them when fewer than K), NaN when it has none. Same checks.
/// vectorised (the default): positions away from the ring ends are done 4 at a time in SSE lanes with the same float
/// operations, bit-identical to false (one position at a time, the reference the tests compare with).
std::vector<float> RingNeighbourMeanDistances(const std::vector<ScanPoint>& points, int k, const SorNeighbourhood& hood,
                                              bool vectorised = true);

/// One real point per occupied voxel of edge voxel_m (grid aligned at the origin): the point nearest the voxel's
/// centroid (what PCL's VoxelGrid would output), ties to the lower index. Keeps ring, time and range attributes.
std::size_t VoxelFilter(double voxel_m, std::vector<ScanPoint>* points);

/// The index selection behind VoxelFilter, for any position list: ascending indices of the kept points.
/// Non-finite positions are never kept. voxel_m must be > 0 (ROTOLIDAR_CHECK).
std::vector<std::size_t> VoxelRepresentatives(const std::vector<Eigen::Vector3f>& positions, double voxel_m);

}  // namespace rotolidar
