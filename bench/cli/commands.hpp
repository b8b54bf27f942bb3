#pragma once
// The `rotolidar` subcommands. Each takes the arguments after its name and returns a process exit code
// (0 ok, 1 failure, 2 usage error); messages go to stderr, results to stdout.
#include <vector>

#include "core/pipeline/estimator.hpp"

namespace rotolidar::bench {

int CmdDemo(int argc, char** argv);
int CmdSim(int argc, char** argv);
int CmdSlam(int argc, char** argv);
int CmdEval(int argc, char** argv);
int CmdDecode(int argc, char** argv);
int CmdBench(int argc, char** argv);
int CmdReplay(int argc, char** argv);
int CmdLive(int argc, char** argv);      ///< bench/cli/live_commands.cpp
int CmdScene(int argc, char** argv);
int CmdExport(int argc, char** argv);     ///< bench/cli/kitti_commands.cpp
int CmdSlamKitti(int argc, char** argv);  ///< `slam --kitti DIR` (CmdSlam dispatches to it)
int CmdKittiTwin(int argc, char** argv);  ///< bench/cli/kitti_twin_commands.cpp
int CmdMapEval(int argc, char** argv);
int CmdStudy(int argc, char** argv);
int CmdVocab(int argc, char** argv);      ///< bench/cli/vocab_commands.cpp: ORB bag-of-words vocabularies
int CmdImport(int argc, char** argv);     ///< bench/ros/ros_commands.cpp: ROS 1 bag -> recording folder
int CmdExportBag(int argc, char** argv);  ///< bench/ros/ros_commands.cpp: slam run or recording -> ROS 1 bag
int CmdCalibrate(int argc, char** argv);  ///< bench/cli/calib_commands.cpp: T_rotor_lidar from a static stretch

/// One "warning:" line per registration-problem stretch (at most 10, then a count) and a summary line, on
/// stdout; nothing when every registration converged undegenerate (bench/run/scan_health.hpp).
void PrintScanHealth(const std::vector<ScanReport>& scans);

/// A slam config file: a YAML mapping of EstimatorConfig keys (see slam_config.yaml of any run) over *config;
/// an empty path changes nothing. Errors name the file, line and key.
Status LoadSlamConfig(const std::string& path, EstimatorConfig* config);

/// One "loop closure:" summary line on stdout (keyframes, loops, candidates, GICP and graph time).
void PrintLoopClosure(const graph::LoopClosureState& state);

}  // namespace rotolidar::bench
