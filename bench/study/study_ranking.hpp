#pragma once
// Ranking a study's configurations (docs/studies.md, "Ranking"): points that differ only in seed form a group;
// groups are compared within a partition of the conditions they ran under (the swept `scene` and `carrier`
// axes: a rig is chosen per scene type, not across them), on the study's rank_by metrics.
//
// Score: for each rank_by metric the groups of a partition are ranked by their mean over seeds (1 = best;
// lower is better for errors and times, higher for coverage, completeness, map points and the real-time
// factor); a group's score is the sum of its ranks over the metrics (a Borda count), ties broken by the first
// metric's mean. A group with any failed seed ranks after every group without one: a configuration that
// sometimes fails is not "best" on the seeds that survived.
#include <string>
#include <vector>

#include "bench/study/study_runner.hpp"

namespace rotolidar::bench {

/// One metric over a group's seeds (finite values of non-failed points).
struct MetricSpread {
  size_t n = 0;
  double mean = 0, sd = 0, min = 0, max = 0;  ///< sd: sample standard deviation (0 when n < 2)
};

struct RankedGroup {
  std::string partition;  ///< "scene=lab, carrier=handheld"; "all points" when neither axis is swept
  std::string design;     ///< the other swept axes without the seed, "profile=trapezoid, speed=2.6"; "base"
  std::string group;      ///< GroupWithoutSeed of its points (study_seeds.hpp)
  size_t seeds = 0, failed = 0;
  std::vector<MetricSpread> metrics;  ///< one per rank_by metric
  int score = 0;  ///< sum of per-metric ranks
  int rank = 0;   ///< 1 = best within its partition
  /// Welch's t of the first metric's mean against the partition's best group (0 for the best, NaN when
  /// either has fewer than 2 values or both have zero spread). |t| < 2: not distinguishable from the best.
  double t_vs_best = 0;
};

/// True when a larger value of the metric is better (coverage_*, completeness_*, map_points,
/// slam_realtime_factor); errors, distances and times: false.
bool HigherIsBetter(const std::string& metric);

/// The groups of the study ranked within each partition; partitions in order of first appearance, groups by
/// rank. rank_by: StudyMetrics() names (validated by StudyConfig::Validate); empty = no ranking (empty result).
std::vector<RankedGroup> RankStudyGroups(const StudyResult& result, const std::vector<std::string>& rank_by);

}  // namespace rotolidar::bench
