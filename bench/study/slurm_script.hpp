#pragma once
// The pure parts of the Slurm backend (slurm_backend.hpp), testable without a cluster: the array task's shell
// script, the sbatch command line, and the parsing of `scontrol -o show job` into per-task states.
//
// Facts used (Slurm's documentation: sbatch(1), scontrol(1), squeue(1) "JOB STATE CODES"):
//   - `sbatch --array=0-N%M` runs tasks 0..N with at most M at once; each task sees SLURM_ARRAY_TASK_ID and
//     SLURM_ARRAY_JOB_ID; `--parsable` prints "jobid" or "jobid;cluster".
//   - `scontrol -o show job JOBID` prints one line per job record: for an array, one per started task plus one
//     for the still pending rest, whose ArrayTaskId is a range such as "4-9%2". A record is "Key=Value" words;
//     JobState is a state code (PENDING, RUNNING, COMPLETED, FAILED, TIMEOUT, CANCELLED, ...) and ExitCode is
//     "status:signal". A finished job stays listed for MinJobAge seconds (default 300), then scontrol answers
//     "Invalid job id specified".
//   - A task killed for its time limit gets SIGTERM, then SIGKILL after KillWait: its script may leave nothing.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "bench/study/study_slurm_config.hpp"

namespace rotolidar::bench {

/// `s` in single quotes for a POSIX shell ('\'' for each quote inside): safe for any byte string.
std::string ShellQuote(const std::string& s);

/// What the array task script needs; every path absolute (tasks run on other machines, in another folder).
struct SlurmTaskScriptSpec {
  std::string executable;        ///< the rotolidar binary, on the shared file system
  std::string slam_config_path;  ///< "" = none (as StudyConfig::slam_config_path)
  std::string out_dir;           ///< the study's out_dir (holds points/<id>/)
  std::string points_file;       ///< one point id per line; array task k runs line k + 1
};

/// The sh script of one array task: picks its point id from points_file by SLURM_ARRAY_TASK_ID, runs
/// `EXE demo --out DIR --config DIR/sim_config.yaml [--slam-config P]` (the local backend's command) with stdin
/// from /dev/null and stdout + stderr to DIR/log.txt, then writes DIR/slurm_status.json (job id, task id, exit
/// status, wall time in s; through a rename) and exits with the command's status.
std::string SlurmTaskScript(const SlurmTaskScriptSpec& spec);

/// The sbatch argument vector (without the script's own arguments): --parsable, --job-name, --array=0-(n-1)
/// with %max_parallel when > 0, --output into logs_dir (%A_%a.out; the folder must exist, Slurm does not create
/// it), --time, --mem, --cpus-per-task, --partition when set, then config.sbatch_args, then the script path.
std::vector<std::string> SbatchArgs(const StudySlurmConfig& config, const std::string& job_name, size_t tasks,
                                    const std::string& logs_dir, const std::string& script_path);

/// The job id in sbatch --parsable's output ("123" or "123;cluster", trailing newline allowed); "" if none.
std::string ParseSbatchJobId(const std::string& out);

/// One array task as Slurm last reported it.
struct SlurmTaskRecord {
  std::string state;      ///< JobState, e.g. "RUNNING", "TIMEOUT"
  std::string exit_code;  ///< ExitCode, "status:signal"; "" for a pending task
  std::string reason;     ///< Reason (e.g. "TimeLimit", "None")
};

/// Parses `scontrol -o show job` output into array task index -> record (a pending range fills every index in
/// it). Lines without ArrayTaskId (not an array job) are ignored.
std::map<size_t, SlurmTaskRecord> ParseScontrolJobs(const std::string& text);

/// True for the states after which a task never runs again (COMPLETED, FAILED, TIMEOUT, CANCELLED,
/// OUT_OF_MEMORY, NODE_FAIL, PREEMPTED, BOOT_FAIL, DEADLINE); false for PENDING, RUNNING, COMPLETING, etc.
bool IsFinalSlurmState(const std::string& state);

/// "status:signal" as one exit code like the local backend's: 128 + signal when signal > 0, else status;
/// -1 when malformed or empty.
int SlurmExitCode(const std::string& exit_code);

}  // namespace rotolidar::bench
