#pragma once
// `rotolidar bench lidar` and `rotolidar bench decode`: speed of the VLP-16 twin's ray casting and of the core's
// packet decoder, as ratios to real time (one VLP-16 second = 18,084 firing sequences = 289,344 firings in
// single-return mode). Single-threaded: the work runs on the calling thread only (Embree traces rays on the
// calling thread; its scene build, which may use threads, is outside the timing). Each repetition is timed on the
// wall clock and on the thread's CPU clock; the medians are reported (the CPU clock is the better "one core"
// figure on a shared machine, the wall clock on an idle one).
#include <ostream>
#include <string>
#include <vector>

#include "core/wire/vlp16.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

/// Wall and thread-CPU seconds of one timed run.
struct Timing {
  double wall_s = 0.0;
  double cpu_s = 0.0;
};

/// Medians over repetitions (of a non-empty list).
Timing MedianTiming(std::vector<Timing> runs);

struct LidarBenchOptions {
  std::string scene = "box_room";  ///< scene name or path (as `rotolidar sim --scene`)
  double seconds = 1.0;            ///< simulated seconds per repetition
  int repetitions = 5;
  double rpm = 600.0;
  Vlp16ReturnMode return_mode = Vlp16ReturnMode::kStrongest;
  int beam_rings = 0;              ///< 0 = central ray only (the default twin)
  bool truth = false;              ///< also collect per-firing truth (what tests do; the sim does not)
  bool pose_per_firing = false;    ///< call the rig's pose function for every firing instead of per sequence
  uint64_t seed = 1;
  /// "" = the options above alone; ideal | typical | harsh = the preset's range physics (sim/lidar/lidar_realism.hpp),
  /// whose beam_rings replaces the one above.
  std::string realism;
  bool Validate(std::string* error) const;
};

struct LidarBenchResult {
  double simulated_s = 0.0;      ///< per repetition
  long firings = 0;              ///< per repetition
  long rays = 0;                 ///< per repetition (firings x sub-rays, first surface only)
  double returned_fraction = 0.0;  ///< firings with a non-zero distance_2mm
  Timing cast;                   ///< Vlp16Caster::Fire only (median)
  Timing cast_and_encode;        ///< Fire + Vlp16PacketEncoder (median)
};

/// Casts `seconds` of the default rig (DefaultSimConfig) moved kinematically (carrier target path, constant-speed
/// rotor at the profile speed; no physics) through the scene,
/// packet by packet as the sim runner does, `repetitions` times (a fresh caster each time).
Status RunLidarBench(const LidarBenchOptions& options, LidarBenchResult* result);
void PrintLidarBench(const LidarBenchOptions& options, const LidarBenchResult& result, std::ostream& os);

struct DecodeBenchOptions {
  std::string input;     ///< "" = simulate `seconds` of the default rig in memory; else a pcap file (or raw)
  bool raw = false;      ///< input is concatenated 1206-byte payloads
  double seconds = 2.0;  ///< simulated stream length when input is ""
  Vlp16ReturnMode mode = Vlp16ReturnMode::kStrongest;  ///< of the simulated stream
  int repetitions = 5;
  bool split = false;    ///< also cut revolutions (RevolutionSplitter) in the timed loop
  bool Validate(std::string* error) const;
};

struct DecodeBenchResult {
  long data_packets = 0;
  long position_packets = 0;
  long points = 0;             ///< per repetition
  double stream_s = 0.0;       ///< real time the data packets span: packets x sequences per packet x 55.296 us
  Timing decode;               ///< median
};

/// Loads or simulates the packets, then decodes them all `repetitions` times (a fresh decoder each time).
Status RunDecodeBench(const DecodeBenchOptions& options, DecodeBenchResult* result);
void PrintDecodeBench(const DecodeBenchOptions& options, const DecodeBenchResult& result, std::ostream& os);

}  // namespace rotolidar::bench
