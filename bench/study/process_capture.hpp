#pragma once
// Running a short external command (sbatch, scontrol, scancel) and capturing what it prints: posix_spawnp with
// an argument vector (no shell, so no quoting of file names or options is ever needed), stdin from /dev/null,
// stdout and stderr read through pipes until the command exits. The child inherits this process's environment
// (SLURM_CONF, PATH).
#include <string>
#include <vector>

#include "core/util/status.hpp"

namespace rotolidar::bench {

struct CapturedOutput {
  int exit_code = -1;  ///< exit status; 128 + N when killed by signal N; -1 when it could not start
  std::string out;     ///< everything it wrote to stdout
  std::string err;     ///< everything it wrote to stderr
};

/// argv for posix_spawn: pointers into `args` (which must outlive the result), then a null pointer.
std::vector<char*> SpawnArgv(const std::vector<std::string>& args);

/// The full path of `program` found on $PATH (or `program` itself when it contains a '/' and is executable);
/// "" when there is none.
std::string FindOnPath(const std::string& program);

/// Runs argv (argv[0] looked up on $PATH) and waits for it. Fails only when it cannot be started (the message
/// names the program); a non-zero exit is reported in output->exit_code, not as an error.
Status RunCaptured(const std::vector<std::string>& argv, CapturedOutput* output);

}  // namespace rotolidar::bench
