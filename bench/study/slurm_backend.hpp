#pragma once
// `rotolidar study STUDY.yaml --backend slurm`: the study's pending points as one `sbatch --array` job on a
// Slurm cluster, each array task running the local backend's command (`rotolidar demo --out POINT_DIR --config
// POINT_DIR/sim_config.yaml`, slurm_script.hpp) into the same per-point folders. out_dir must be on a file
// system that the cluster's nodes share with this machine, and so must the rotolidar executable.
//
// Files under out_dir/slurm/:
//   job.json                   the last submission: job id, submission folder, point id per array index,
//                              whether it has been collected
//   submit_<k>/points.txt      array task i runs the point on line i + 1
//   submit_<k>/task.sh         the array task script
//   submit_<k>/logs/%A_%a.out  Slurm's own output of each task (the point's log is points/<id>/log.txt)
// The runner talks to Slurm only through sbatch and scontrol found on PATH, with the environment it was given
// (SLURM_CONF selects the cluster); no accounting database is needed.
//
// A point is finished exactly as with the local backend (its metrics.json and sim_config.yaml), so resume works
// across backends: a point that failed on Slurm (its Slurm state and exit code are in its point_status.json and
// the study's page) is submitted again by the next `--backend slurm` run, or run by the next local run.
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "bench/study/study_config.hpp"
#include "bench/study/study_runner.hpp"

namespace rotolidar::bench {

struct SlurmRunOptions {
  std::string out_dir = "runs/study";
  StudySlurmConfig slurm;   ///< sbatch options (the study file's, with the command line's overrides)
  std::string executable;   ///< the rotolidar binary the tasks run; "" = this process's (/proc/self/exe)
  /// Called with one line per event (submission, state counts when they change, failures). Null = silent.
  std::function<void(const std::string&)> progress;
  /// Polled while waiting: when set, the runner stops waiting (the job keeps running; `--collect` gathers it).
  const std::atomic<bool>* stop = nullptr;
};

/// The record of a submission (out_dir/slurm/job.json).
struct SlurmSubmission {
  std::string job_id;
  std::string dir;                     ///< out_dir/slurm/submit_<k>
  std::vector<std::string> point_ids;  ///< array index -> point id
  bool collected = false;
};

/// Reads out_dir/slurm/job.json; *exists = false (and Ok) when there is none.
Status ReadSlurmSubmission(const std::string& out_dir, SlurmSubmission* submission, bool* exists);

/// Prepares the points (as RunStudy) and submits the pending ones as one array job; records it in job.json. An
/// earlier submission into out_dir that finished but was never collected is collected first (its points'
/// states recorded in their point_status.json). *submitted = false when no point is pending (nothing is
/// submitted). Fails when sbatch is not on PATH, when sbatch refuses the job (its message is passed on), or when
/// an earlier submission into out_dir is still pending or running (it must be collected or cancelled first).
Status SubmitSlurmStudy(const StudyConfig& config, const SlurmRunOptions& options, SlurmSubmission* submission,
                        bool* submitted);

/// Waits until every task of the recorded submission is in a final state (polling scontrol every
/// slurm.poll_interval_s), then builds the study's rows: points of the submission that left a metrics.json and
/// a zero exit status are kRan (runtime from the task's own record), the others kFailed with the Slurm state
/// and exit code (a task with no record of its own, e.g. killed at its time limit, gets the state Slurm last
/// reported); points outside the submission are kResumed when finished, else kFailed ("not submitted").
/// Writes each submitted point's point_status.json and marks job.json collected. *stopped = true (and the rows
/// untouched) when options.stop was set while waiting.
Status CollectSlurmStudy(const StudyConfig& config, const SlurmRunOptions& options, StudyResult* result,
                         bool* stopped);

/// Whether the job has tasks that are not in a final state, by scontrol; false when Slurm no longer knows it.
/// Fails when scontrol is not on PATH or fails otherwise.
Status SlurmJobActive(const std::string& job_id, bool* active);

}  // namespace rotolidar::bench
