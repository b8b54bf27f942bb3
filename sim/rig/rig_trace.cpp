#include "sim/rig/rig_trace.hpp"

#include <algorithm>

#include "core/util/log.hpp"

namespace rotolidar::sim {

void RigTrace::Append(const RigTraceSample& sample) {
  ROTOLIDAR_CHECK(samples_.empty() || sample.t_s > samples_.back().t_s, "RigTrace: times must increase");
  samples_.push_back(sample);
}

void RigTrace::DropBefore(Seconds t_s) {
  // Keep the last sample at or before t_s: it brackets t_s from below.
  while (samples_.size() >= 2 && samples_[1].t_s <= t_s) samples_.pop_front();
}

bool RigTrace::Covers(Seconds t0_s, Seconds t1_s) const {
  return !samples_.empty() && t0_s >= samples_.front().t_s && t1_s <= samples_.back().t_s;
}

Seconds RigTrace::t_front_s() const {
  ROTOLIDAR_CHECK(!samples_.empty(), "RigTrace: empty");
  return samples_.front().t_s;
}

Seconds RigTrace::t_back_s() const {
  ROTOLIDAR_CHECK(!samples_.empty(), "RigTrace: empty");
  return samples_.back().t_s;
}

RigTraceSample RigTrace::At(Seconds t_s) const {
  ROTOLIDAR_CHECK(Covers(t_s, t_s), "RigTrace: time outside the covered span");
  // First sample strictly after t_s; its predecessor is at or before t_s.
  auto hi = std::upper_bound(samples_.begin(), samples_.end(), t_s,
                             [](Seconds t, const RigTraceSample& s) { return t < s.t_s; });
  if (hi == samples_.end()) return samples_.back();
  const RigTraceSample& a = *(hi - 1);
  const RigTraceSample& b = *hi;
  const double s = (t_s - a.t_s) / (b.t_s - a.t_s);
  RigTraceSample out;
  out.t_s = t_s;
  out.T_world_base = Interpolate(a.T_world_base, b.T_world_base, s);
  out.theta_rad = a.theta_rad + s * (b.theta_rad - a.theta_rad);
  return out;
}

}  // namespace rotolidar::sim
