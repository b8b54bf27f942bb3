#pragma once
// Sensor clocks of the twin: each sensor stamps its data on its own clock, which runs off the rig (host) clock
// by a constant offset and a rate error (drift), and the host stamps each captured LiDAR UDP packet after a
// network receive delay. Everything here is identity by default, so a run without clock errors is unchanged.
// Times are on the rig clock [s] (docs/frames.md); drift is in parts per million [ppm].
#include <cstdint>
#include <string>

#include "core/types/time.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::sim {

/// One sensor clock relative to the rig clock: stamp(t) = t + offset_s + drift_ppm * 1e-6 * t, for rig time t [s].
struct SensorClock {
  double offset_s = 0.0;   ///< stamp minus rig time at rig time 0 [s]
  double drift_ppm = 0.0;  ///< rate error: the clock gains drift_ppm microseconds per second of rig time [ppm]

  /// The stamp this clock writes for an event at rig time t_rig_s. Exactly t_rig_s when both fields are 0.
  Seconds Stamp(Seconds t_rig_s) const { return t_rig_s + offset_s + drift_ppm * 1e-6 * t_rig_s; }
  /// False with `name` and the field in *error unless both are finite, |offset_s| <= 1 s and |drift_ppm| <= 1000.
  bool Validate(const std::string& name, std::string* error) const;
};

/// Host receive delay of the LiDAR's UDP packets: the capture time a pcap record holds is the packet's arrival
/// plus latency_s plus an exponential delay of mean jitter_scale_s (network stack and scheduling jitter).
struct CaptureJitterConfig {
  double latency_s = 0.0;       ///< constant part of the delay [s], in [0, 0.01]
  double jitter_scale_s = 0.0;  ///< mean (= standard deviation) of the exponential part [s], in [0, 0.01]
  bool enabled() const { return latency_s != 0.0 || jitter_scale_s != 0.0; }
  /// False with `name` and the field in *error when a value is non-finite or outside its range.
  bool Validate(const std::string& name, std::string* error) const;
};

/// Applies CaptureJitterConfig to a stream of capture times, in write order. Draws from the named random stream
/// kCaptureJitterStream of the run seed (core/util/rng.hpp), one draw per packet. Capture times never go
/// backwards: a delayed packet holds back the ones behind it (out = max(previous out, t + delay)), so packets
/// keep their order. With a disabled config, Apply returns its input unchanged and draws nothing. Not thread-safe.
class CaptureJitter {
 public:
  static constexpr const char* kCaptureJitterStream = "lidar.capture_jitter";
  CaptureJitter(const CaptureJitterConfig& config, uint64_t run_seed);
  /// The host capture time of a packet that arrives at rig time t_arrival_s; call in write order.
  Seconds Apply(Seconds t_arrival_s);

 private:
  CaptureJitterConfig config_;
  RandomStream stream_;
  Seconds last_s_;
};

}  // namespace rotolidar::sim
