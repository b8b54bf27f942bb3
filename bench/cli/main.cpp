// rotolidar: the command-line entry point. Subcommands are thin wrappers around library functions.
#include <cstring>
#include <iostream>
#include <string>

#include "bench/cli/commands.hpp"

namespace {

struct Command {
  const char* name;
  int (*run)(int, char**);
  const char* summary;
};

const Command kCommands[] = {
    {"demo", rotolidar::bench::CmdDemo, "simulate the rig, run SLAM, report the error vs truth (no arguments needed)"},
    {"sim", rotolidar::bench::CmdSim, "simulate the rig and write a recording folder"},
    {"slam", rotolidar::bench::CmdSlam, "run the SLAM core on a recording folder"},
    {"eval", rotolidar::bench::CmdEval, "compare trajectories (APE/RPE, evo's definitions)"},
    {"decode", rotolidar::bench::CmdDecode, "decode VLP-16 packets (pcap or raw) to CSV and PLY points"},
    {"bench", rotolidar::bench::CmdBench, "speed benchmarks (ratios to real time) and the IMU Allan check"},
    {"calibrate", rotolidar::bench::CmdCalibrate, "lever arm and tilt of the lidar on the rotor, from a static stretch"},
    {"replay", rotolidar::bench::CmdReplay, "send a recording over UDP at N x real time, as the rig would"},
    {"live", rotolidar::bench::CmdLive, "SLAM live from the rig over UDP; records everything it receives"},
    {"scene", rotolidar::bench::CmdScene, "inspect scenes: list, show (top and perspective pictures)"},
    {"export", rotolidar::bench::CmdExport, "write a recording as a KITTI odometry sequence (bins, times, calib, poses)"},
    {"kitti-twin", rotolidar::bench::CmdKittiTwin, "simulate KITTI's HDL-64E car on a KITTI path; write a KITTI sequence"},
    {"mapeval", rotolidar::bench::CmdMapEval, "map metrics vs the scene: coverage, density, distance, elements"},
    {"study", rotolidar::bench::CmdStudy, "trade studies: sweep sim parameters, run each point, table + plots"},
    {"vocab", rotolidar::bench::CmdVocab, "ORB bag-of-words vocabularies for loop closure: train, info"},
    {"import", rotolidar::bench::CmdImport, "convert a ROS 1 bag (VelodyneScan, Imu, JointState, Image) to a recording"},
    {"export-bag", rotolidar::bench::CmdExportBag, "write a slam run (or --recording REC) as a ROS 1 bag for RViz"},
};

void PrintUsage(std::ostream& os) {
  os << "usage: rotolidar <command> [options]   (rotolidar <command> --help for its options)\n\ncommands:\n";
  for (const Command& c : kCommands) os << "  " << c.name << std::string(std::strlen(c.name) < 10 ? 10 - std::strlen(c.name) : 1, ' ') << c.summary << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    PrintUsage(std::cout);
    return argc < 2 ? 2 : 0;
  }
  for (const Command& c : kCommands) {
    if (argv[1] == std::string(c.name)) {
      try {
        return c.run(argc - 2, argv + 2);
      } catch (const std::exception& e) {
        std::cerr << "internal error: " << e.what() << "\n";
        return 3;
      }
    }
  }
  std::cerr << "error: unknown command '" << argv[1] << "'\n";
  PrintUsage(std::cerr);
  return 2;
}
