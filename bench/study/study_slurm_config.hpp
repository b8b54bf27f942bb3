#pragma once
// The `slurm:` section of a study file: how `rotolidar study STUDY.yaml --backend slurm` submits the study's
// pending points as one `sbatch --array` job (bench/study/slurm_backend.hpp, docs/studies.md). Every key is
// optional; command-line flags override the file. Ignored by the local backend.
//
//   slurm:
//     partition: compute          # sbatch --partition; "" = the cluster's default partition
//     time_per_point: "00:15:00"  # sbatch --time per array task: MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS
//     mem_per_point: 2G           # sbatch --mem per task: a number with an optional K/M/G/T suffix
//     cpus_per_point: 1           # sbatch --cpus-per-task
//     max_parallel: 50            # the array's %N throttle: at most N tasks at once; 0 = no throttle
//     sbatch_args: ["--account=lidar", "--qos=short"]   # extra sbatch options, passed as given
//     poll_interval_s: 10         # how often the waiting runner asks Slurm for the tasks' states
#include <string>
#include <vector>

namespace rotolidar::bench {

struct StudySlurmConfig {
  std::string partition;
  std::string time_per_point = "01:00:00";  ///< a point of a few minutes of simulated time fits easily
  std::string mem_per_point = "4G";         ///< a 10 s handheld point peaked at 0.39 GB (docs/studies.md): head room
  int cpus_per_point = 1;                   ///< a point uses about one core (11 CPU-s in ~10 s, docs/studies.md)
  int max_parallel = 0;
  std::vector<std::string> sbatch_args;
  double poll_interval_s = 10.0;

  /// False with a message naming the field (slurm.<field>) for a malformed time or memory value, cpus < 1,
  /// max_parallel < 0, a poll interval outside [0.05, 3600] s, an empty or non-option ("-" first) sbatch arg,
  /// or a partition with characters other than [A-Za-z0-9_.-,].
  bool Validate(std::string* error) const;
};

}  // namespace rotolidar::bench
