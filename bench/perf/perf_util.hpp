#pragma once
// Clock and statistics helpers shared by the benchmarks (bench/perf/*_perf.cpp).
#include <time.h>

#include <algorithm>
#include <vector>

namespace rotolidar::bench {

/// CPU time of the whole process, all threads [s] (CLOCK_PROCESS_CPUTIME_ID).
inline double ProcessCpuS() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// The median (the mean of the middle two for an even count); 0 for no values.
inline double PerfMedian(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace rotolidar::bench
