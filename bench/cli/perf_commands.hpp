#pragma once
// The `rotolidar bench <name>` commands (bench/cli/perf_commands.cpp): each parses the arguments after its name,
// runs the matching bench/perf/ measurement and prints its result to stdout. Exit codes: 0 ok (for allan: the
// noise terms pass), 1 failure, 2 usage error (the message goes to stderr).
namespace rotolidar::bench {

int BenchRig(int argc, char** argv);
int BenchAllan(int argc, char** argv);
int BenchLidar(int argc, char** argv);
int BenchDecode(int argc, char** argv);
int BenchSlam(int argc, char** argv);
int BenchCamera(int argc, char** argv);
int BenchPlaneResiduals(int argc, char** argv);  ///< bench/cli/residual_commands.cpp
int BenchLoops(int argc, char** argv);           ///< bench/cli/loop_commands.cpp

}  // namespace rotolidar::bench
