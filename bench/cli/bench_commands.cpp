// `rotolidar bench <name>`: speed benchmarks (ratios to real time), the IMU Allan check, loop detection rates.
#include <algorithm>
#include <cstring>
#include <iostream>

#include "bench/cli/commands.hpp"
#include "bench/cli/perf_commands.hpp"

namespace rotolidar::bench {
namespace {

struct Benchmark {
  const char* name;
  int (*run)(int, char**);
  const char* summary;
};

const Benchmark kBenchmarks[] = {
    {"rig", BenchRig, "rig physics + stepper/PID/encoder + IMU, no LiDAR (target >= 100x real time, 1 core)"},
    {"allan", BenchAllan, "long static run: Allan deviation recovers the IMU's N and K within 10 %"},
    {"lidar", BenchLidar, "VLP-16 ray casting + packet encoding (target >= 20x real time, 1 core)"},
    {"decode", BenchDecode, "VLP-16 packet decoding (target >= 100x real time)"},
    {"slam", BenchSlam, "SLAM core per-scan time per stage, ATE, deskew error (target median <= 10 ms/scan, 1 core)"},
    {"plane-residuals", BenchPlaneResiduals, "range noise: residuals to RANSAC planes, real capture vs twin"},
    {"loops", BenchLoops, "loop detection precision/recall of stage 1, stage 2 and both against truth revisits"},
    {"camera", BenchCamera, "camera twin frames/s per renderer and image size (target 640x480 >= 30 fps, 2 cores)"},
};

void PrintBenchUsage(std::ostream& os) {
  os << "usage: rotolidar bench <name> [options]   (rotolidar bench <name> --help)\n\nbenchmarks:\n";
  for (const Benchmark& b : kBenchmarks) os << "  " << b.name << std::string(std::max<std::size_t>(8, std::strlen(b.name) + 1) - std::strlen(b.name), ' ') << b.summary << "\n";
}

}  // namespace

int CmdBench(int argc, char** argv) {
  if (argc < 1 || std::strcmp(argv[0], "--help") == 0 || std::strcmp(argv[0], "-h") == 0) {
    PrintBenchUsage(argc < 1 ? std::cerr : std::cout);
    return argc < 1 ? 2 : 0;
  }
  for (const Benchmark& b : kBenchmarks)
    if (std::strcmp(argv[0], b.name) == 0) return b.run(argc - 1, argv + 1);
  std::cerr << "error: unknown benchmark '" << argv[0] << "'\n";
  PrintBenchUsage(std::cerr);
  return 2;
}

}  // namespace rotolidar::bench
