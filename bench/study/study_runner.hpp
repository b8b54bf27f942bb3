#pragma once
// Running a trade study: the sweep expanded into points, each point run (by default as a child `rotolidar demo`
// process, so one point's crash cannot take the sweep down) on a pool of local workers, finished points skipped
// on a rerun (resume), and every point's metrics.json read back into one row of results.
//
// Folder layout under the study's out_dir:
//   points/<point id>/sim_config.yaml   the point's full sim config (written before it runs)
//   points/<point id>/log.txt           the child's stdout + stderr
//   points/<point id>/metrics.json      demo's metrics (written by renaming: its presence = finished)
//   points/<point id>/point_status.json the study's record of the run: exit code, wall time (and, from the
//                                       Slurm backend, the task's Slurm job id, state and exit code)
//   points/<point id>/slurm_status.json the Slurm array task's own record (slurm_backend.hpp)
//   slurm/                              the Slurm backend's submissions (slurm_backend.hpp)
//   points/<point id>/recording/, slam/ demo's outputs
// A point is finished when its metrics.json exists, parses as JSON and its sim_config.yaml is the one the study
// would write now (a changed study reruns the points whose config changed).
#include <atomic>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "bench/study/study_config.hpp"

namespace rotolidar::bench {

/// A metric a point does not have (a failed point, a key missing from its metrics.json).
inline constexpr double kStudyNaN = std::numeric_limits<double>::quiet_NaN();

/// One point of the full factorial.
struct StudyPoint {
  size_t index = 0;  ///< position in expansion order (variant, scene, carrier, axis, profile, speed, seed)
  /// Folder name: the swept axes' values, e.g. "variant-rotating__speed-2.6__seed-1" ("base" when nothing is
  /// swept). Depends only on the values, not on the index, so adding values to an axis keeps old folders.
  std::string id;
  std::vector<std::pair<std::string, std::string>> swept;  ///< (axis, value) of the swept axes, in axis order
  std::string variant;  ///< variant name; "" when variants are not swept
  sim::SimConfig sim;   ///< the point's full config (valid)
};

/// The points of config's sweep, in expansion order. Fails (naming the point) when a point's config does not
/// validate (e.g. a stop_and_go profile at speed 0) or two points would share a folder name.
Status ExpandStudy(const StudyConfig& config, std::vector<StudyPoint>* points);

/// The exact text of the point's sim_config.yaml (sim::EmitSimConfig of point.sim): what the study writes before
/// the point runs and compares on a rerun.
std::string PointConfigText(const StudyPoint& point);

/// What running one point gave.
struct PointRunOutcome {
  int exit_code = 0;  ///< 0 = success; a process's exit status, 128 + signal number, or -1 (could not start)
  std::string message;  ///< why it failed (empty on success)
};

/// Runs one point whose sim_config.yaml is already in point_dir; on success it leaves point_dir/metrics.json.
/// Called from several worker threads at once: it must be thread-safe.
using PointRunner = std::function<PointRunOutcome(const StudyPoint& point, const std::string& point_dir)>;

/// The default runner: `executable demo --out point_dir --config point_dir/sim_config.yaml [--slam-config P]`
/// as a child process (posix_spawn), stdin from /dev/null, stdout and stderr to point_dir/log.txt, waited for.
/// `executable` "" = this process's own executable (/proc/self/exe resolved).
PointRunner MakeDemoProcessRunner(const std::string& executable, const std::string& slam_config_path);

enum class PointState {
  kRan,      ///< run now and finished
  kResumed,  ///< finished by an earlier run: skipped
  kFailed,   ///< run now and failed (no usable metrics.json)
};
const char* PointStateName(PointState state);  ///< "ran", "resumed", "failed"

struct StudyPointResult {
  StudyPoint point;
  PointState state = PointState::kFailed;
  int exit_code = 0;
  double runtime_s = std::numeric_limits<double>::quiet_NaN();  ///< wall time of the run; NaN = unknown
  std::vector<double> metrics;  ///< one per StudyMetrics() entry, NaN where metrics.json lacks it
  std::string message;          ///< failure reason
};

struct StudyResult {
  std::vector<StudyPointResult> points;  ///< in expansion order
  size_t ran = 0, resumed = 0, failed = 0;
  size_t not_run = 0;  ///< of `failed`: never started because StudyRunOptions::stop was set
};

struct StudyRunOptions {
  std::string out_dir = "runs/study";
  int jobs = 0;  ///< parallel points; <= 0 = the hardware's thread count
  /// Called (serialized) with one line per event: "[study] k/N points done", failures. Null = silent.
  std::function<void(const std::string&)> progress;
  /// Polled before each point starts: when set, no new point starts; running ones finish (a terminal's Ctrl-C
  /// also reaches the children, which then fail with their signal). Points never started are failed rows
  /// ("not run: the study was stopped") that the next invocation runs (resume).
  const std::atomic<bool>* stop = nullptr;
};

/// Expands the sweep, writes each pending point's sim_config.yaml, runs the pending points with `runner` on
/// options.jobs threads, and collects every point's row. A failed point does not stop the others: it is
/// recorded (state kFailed, its exit code) and the study still succeeds. Fails only when the sweep does not
/// expand or out_dir cannot be written.
Status RunStudy(const StudyConfig& config, const StudyRunOptions& options, const PointRunner& runner,
                StudyResult* result);

/// The first half of RunStudy, shared with the Slurm backend: one row per point in expansion order; a finished
/// point (see the folder layout above) is read back as kResumed, every other point gets its sim_config.yaml
/// (any stale metrics.json removed), stays kFailed with NaN metrics and is listed (row index) in *pending.
Status PrepareStudyPoints(const std::vector<StudyPoint>& points, const std::string& out_dir, StudyResult* result,
                          std::vector<size_t>* pending);

/// The last step of RunStudy: copies each row's runtime_s into its runtime_s metric and recounts ran, resumed,
/// failed and not_run from the rows' states.
void FinishStudyResult(StudyResult* result);

/// metrics.json's values for every StudyMetrics() entry (NaN where absent or not a number); runtime_s from
/// the study's own measurement is filled by the caller. Fails when the file is missing or is not JSON.
Status ReadPointMetrics(const std::string& metrics_json_path, std::vector<double>* values);

/// Writes `content` to `path` through a temporary file in the same folder and a rename, so readers see
/// either the old file or the whole new one.
Status WriteFileAtomically(const std::string& path, const std::string& content);

}  // namespace rotolidar::bench
