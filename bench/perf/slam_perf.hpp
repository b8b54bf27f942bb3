#pragma once
// `rotolidar bench slam`: speed and accuracy of the SLAM core on a simulated recording.
//
// Simulates `duration_s` of the rig in a scene (sim::RunSimulation, written to `recording_dir`), then runs the
// estimator over it `repetitions` times, single-threaded (features, registration and window: 1 thread), feeding
// messages in time order as a live rig would. With `camera` the sim renders the camera and the estimator fuses it
// (LiDAR-visual-inertial, docs/visual.md): frames are decoded and tracked in the camera path's own thread, on
// top of `threads`, and handed over kCameraFrameLeadS ahead of the packets as `rotolidar slam` does. Reported:
//  - per-scan milliseconds, median and p90, total and per stage (ScanReport::timings: the estimator's own
//    stopwatches, wall clock on the calling thread);
//  - the real-time ratio: the LiDAR data's span divided by the process CPU time spent inside the estimator's
//    Feed/Process/Finish calls (median over repetitions; loading and evaluation excluded; the CPU time of every
//    thread, the camera's PNG decoding included); and the same over wall time;
//  - ATE: translation APE RMSE of T_world_base against truth/base.tum after SE(3) Umeyama (bench/run/truth_eval);
//  - the per-point deskew error against truth (bench/metrics/deskew_error.hpp), first repetition only.
// The first repetition keeps every scan's deskewed points and scores them between scans (copies inside the
// deskew stage, caches evicted): with repetitions > 1 its timings are left out, the others are pooled.
#include <ostream>
#include <string>
#include <vector>

#include "bench/metrics/deskew_error.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct SlamBenchOptions {
  std::string scene = "lab";            ///< scene name (scenes/NAME.yaml) or path
  double duration_s = 20.0;             ///< simulated time [s]
  uint64_t seed = 1;                    ///< run seed of the simulation
  std::string carrier = "handheld";     ///< "handheld" (the scene's default walk) | "scripted_loop"
  int repetitions = 2;                  ///< estimator runs over the same recording (the first one scores)
  int threads = 1;                      ///< estimator threads (features, Ceres); 1 = the "one core" figure
  bool camera = false;                  ///< render the camera and fuse it (visual.enabled)
  std::string recording_dir = "runs/bench_slam/recording";  ///< where the simulated recording is written
  bool Validate(std::string* error) const;  ///< false with the option named in *error
};

/// Median and 90th percentile (nearest rank) of per-scan times [ms].
struct StageTime {
  double median_ms = 0.0, p90_ms = 0.0;
};

struct SlamBenchResult {
  std::size_t scans = 0;            ///< per repetition
  std::size_t points_per_scan = 0;  ///< median decoded points per scan
  double data_s = 0.0;              ///< LiDAR span: last scan end - first scan start [s]
  double cpu_s = 0.0;               ///< median over repetitions of the estimator's process CPU time [s]
  double wall_s = 0.0;              ///< median over repetitions of the estimator's wall time [s]
  StageTime total, deskew, preprocess, features, registration, fusion, map;  ///< over all scans of all reps
  double ate_rmse_m = 0.0;          ///< first repetition
  double ate_max_m = 0.0;
  std::size_t ate_poses = 0;
  DeskewErrorResult deskew_error;   ///< first repetition
  double RealTimeRatio() const { return cpu_s > 0.0 ? data_s / cpu_s : 0.0; }
  double WallRealTimeRatio() const { return wall_s > 0.0 ? data_s / wall_s : 0.0; }
};

/// Simulates, then runs and evaluates the estimator (see the file comment). Errors name the stage that failed.
Status RunSlamBench(const SlamBenchOptions& options, SlamBenchResult* result);
void PrintSlamBench(const SlamBenchOptions& options, const SlamBenchResult& result, std::ostream& os);
Status WriteSlamBenchJson(const std::string& path, const SlamBenchOptions& options, const SlamBenchResult& result);

}  // namespace rotolidar::bench
