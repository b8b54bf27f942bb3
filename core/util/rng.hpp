#pragma once
// Deterministic random streams. Every random source (IMU noise, range noise, camera noise, ...) owns a stream
// seeded from the run seed plus the stream's name, so adding a sensor never shifts another sensor's noise, and
// the same run seed gives the same bytes on every platform (no std::*_distribution, whose output is
// implementation-defined: we draw normals ourselves from a 64-bit generator).
#include <cstdint>
#include <string_view>

namespace rotolidar {

/// 64-bit FNV-1a of a name, mixed with the run seed by SplitMix64.
uint64_t StreamSeed(uint64_t run_seed, std::string_view stream_name);

/// A named random stream: xoshiro256** generator with portable uniform and normal draws.
class RandomStream {
 public:
  RandomStream(uint64_t run_seed, std::string_view stream_name);
  explicit RandomStream(uint64_t seed);

  uint64_t NextU64();
  double Uniform();                       ///< in [0, 1)
  double Normal();                        ///< standard normal (Marsaglia polar method)
  double Normal(double mean, double sigma) { return mean + sigma * Normal(); }

 private:
  uint64_t s_[4];
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace rotolidar
