#pragma once
// Statistics over seeds: an accuracy claim is a median and a p90 over seeds, not one lucky seed. Points that
// differ only in their seed form a group; per group and metric: how many seeds gave a value, the median, the p90
// (nearest rank), the best and the worst. Written as study_seeds.csv and a table in study.html (docs/studies.md).
#include <string>
#include <vector>

#include "bench/study/study_runner.hpp"

namespace rotolidar::bench {

/// One metric over the seeds of one group. Values come from points that did not fail and have the metric
/// (finite); failed points are counted apart, so a group whose seeds diverge or crash cannot look good.
struct SeedStatistics {
  std::string group;      ///< the points' id without the seed axis ("base" when only the seed is swept)
  std::string metric;     ///< a StudyMetrics() name
  size_t seeds = 0;       ///< points in the group
  size_t failed = 0;      ///< of those, failed runs
  size_t values = 0;      ///< finite values used below
  double median = 0.0, p90 = 0.0, min = 0.0, max = 0.0;  ///< nearest-rank percentiles; 0 when values == 0
};

/// Groups in expansion order (the first point of each group), metrics in StudyMetrics() order.
std::vector<SeedStatistics> StudySeedStatistics(const StudyResult& result);

/// The point's id with its seed axis removed ("variant-a__seed-3" -> "variant-a"; "seed-3" -> "base").
std::string GroupWithoutSeed(const StudyPoint& point);

/// study_seeds.csv: group, metric, seeds, failed, values, median, p90, min, max (one row per SeedStatistics).
std::string StudySeedsCsv(const std::vector<SeedStatistics>& stats);

/// Nearest-rank percentile of the finite values (q in [0, 1]; q = 0.5 the median, 0.9 the p90): the value at
/// rank ceil(q * n) in ascending order (1-based; rank 1 for q = 0). NaN for no values.
double NearestRankPercentile(std::vector<double> values, double q);

}  // namespace rotolidar::bench
