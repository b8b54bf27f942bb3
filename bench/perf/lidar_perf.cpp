#include "bench/perf/lidar_perf.hpp"
