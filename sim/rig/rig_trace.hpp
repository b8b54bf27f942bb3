#pragma once
// A sliding window of the rig's TRUE state as the physics produced it, for consumers that need the state at
// arbitrary times between physics steps: the VLP-16 caster (every laser firing has its own time) and the truth
// writer. Sim-only (truth); never reaches core/.
//
// Interpolation: linear in translation and rotor angle, slerp in rotation. With a 1-2 ms physics step the error
// is far below the LiDAR's 2 mm quantisation: a 2 Hz gait bounce of 2 cm (|a| ~ 3.2 m/s^2) deviates from its
// chord by at most |a| dt^2 / 8 = 1.6 um at dt = 2 ms.
#include <deque>

#include "core/types/geometry.hpp"
#include "core/types/time.hpp"

namespace rotolidar::sim {

/// The true rig state at one physics step.
struct RigTraceSample {
  Seconds t_s = 0.0;
  Pose3 T_world_base = Pose3::Identity();
  double theta_rad = 0.0;  ///< unwrapped rotor angle [rad]
};

/// Not thread-safe. Samples must be appended with strictly increasing times.
class RigTrace {
 public:
  /// Appends a sample; ROTOLIDAR_CHECKs that t_s is later than the last sample's.
  void Append(const RigTraceSample& sample);
  /// Drops samples no longer needed to interpolate at times >= t_s (keeps the one at or before t_s).
  void DropBefore(Seconds t_s);
  /// True when [t0_s, t1_s] lies within the covered span [front, back].
  bool Covers(Seconds t0_s, Seconds t1_s) const;
  /// The interpolated state at t_s; ROTOLIDAR_CHECKs coverage (callers check Covers first).
  RigTraceSample At(Seconds t_s) const;
  Seconds t_front_s() const;
  Seconds t_back_s() const;
  bool empty() const { return samples_.empty(); }
  size_t size() const { return samples_.size(); }

 private:
  std::deque<RigTraceSample> samples_;
};

}  // namespace rotolidar::sim
