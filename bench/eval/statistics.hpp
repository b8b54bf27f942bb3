#pragma once
// Summary statistics of an error vector, with evo's definitions (evo/core/metrics.py PE.get_statistic):
// rmse = sqrt(mean(e^2)), sse = sum(e^2), mean, median (numpy: mean of the two middle values for an even
// count), std = population standard deviation sqrt(mean((e - mean)^2)), min, max.
#include <cstddef>
#include <vector>

namespace rotolidar::bench {

struct ErrorStatistics {
  size_t count = 0;  ///< number of errors; 0 means every field below is NaN
  double max = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double min = 0.0;
  double rmse = 0.0;
  double sse = 0.0;
  double std = 0.0;
};

/// Statistics of `errors` (any finite values, order irrelevant). Empty input -> count 0 and NaN fields.
ErrorStatistics ComputeStatistics(const std::vector<double>& errors);

}  // namespace rotolidar::bench
