// Time-ordering of live streams (contract in live_merger.hpp).
#include "bench/live/live_merger.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/wire/packet_gaps.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench {

Seconds LiveItem::t_s() const {
  switch (kind) {
    case Kind::kImu: return imu.t_s;
    case Kind::kEncoder: return encoder.t_s;
    default: return packet.t_capture_s;
  }
}

bool LiveMergerConfig::Validate(std::string* error) const {
  if (!(hold_s >= 0.0 && hold_s <= 10.0)) {
    if (error) *error = "hold_s: " + std::to_string(hold_s) + " s is outside [0, 10]";
    return false;
  }
  if (!std::isfinite(lidar_clock_offset_s)) {
    if (error) *error = "lidar_clock_offset_s: not finite";
    return false;
  }
  if (!(delay_window_s > 0.0)) {
    if (error) *error = "delay_window_s: must be > 0";
    return false;
  }
  return true;
}

LiveMerger::LiveMerger(const LiveMergerConfig& config) : config_(config) {}

void LiveMerger::TrackDelay(const LidarPacket& packet) {
  if (packet.payload.size() != kVlp16PacketBytes) return;
  Vlp16RawPacket raw;
  if (!ParseVlp16DataPacket(packet.payload.data(), packet.payload.size(), &raw)) return;
  // Rig time of the capture if the network added nothing (the twin's rule, core/wire/vlp16.hpp).
  const double t_sent = raw.timestamp_us * 1e-6 + config_.lidar_clock_offset_s +
                        Vlp16PacketPeriodUs(raw.return_mode) * 1e-6 - 55.296e-6 + 15 * kVlp16FiringPeriodS +
                        kVlp16TransmitLatencyS;
  const double delay = packet.t_capture_s - t_sent;
  if (!have_delay_ || packet.t_capture_s - window_start_host_s_ > config_.delay_window_s) {
    previous_min_s_ = have_delay_ ? window_min_s_ : delay;
    window_min_s_ = delay;
    window_start_host_s_ = packet.t_capture_s;
  }
  window_min_s_ = std::min(window_min_s_, delay);
  delay_s_ = std::min(window_min_s_, previous_min_s_);
  have_delay_ = true;
}

void LiveMerger::AddPacket(LidarPacket packet) {
  TrackDelay(packet);
  auto at = packets_.end();  // nearly always the end: two sockets interleave by host time
  while (at != packets_.begin() && std::prev(at)->t_capture_s > packet.t_capture_s) --at;
  packets_.insert(at, std::move(packet));
}

void LiveMerger::AddSample(const RigSample& sample) {
  if (sample.type == RigSample::Type::kImu) {
    seen_imu_ = true;
    latest_imu_s_ = std::max(latest_imu_s_, sample.imu.t_s);
  } else {
    seen_encoder_ = true;
    latest_encoder_s_ = std::max(latest_encoder_s_, sample.encoder.t_s);
  }
  samples_.emplace(sample.t_s(), sample);
}

Seconds LiveMerger::SamplesReachedS() const {
  if (!seen_imu_ && !seen_encoder_) return -1e300;
  Seconds reached = 1e300;
  if (seen_imu_) reached = std::min(reached, latest_imu_s_);
  if (seen_encoder_) reached = std::min(reached, latest_encoder_s_);
  return reached;
}

void LiveMerger::EmitSamplesUpTo(Seconds t_s, std::vector<LiveItem>* out) {
  while (!samples_.empty() && samples_.begin()->first <= t_s) {
    const RigSample s = samples_.begin()->second;
    samples_.erase(samples_.begin());
    LiveItem item;
    if (s.type == RigSample::Type::kImu) {
      if (s.imu.t_s <= released_imu_s_) { ++counts_.late_samples; continue; }
      released_imu_s_ = s.imu.t_s;
      item.kind = LiveItem::Kind::kImu;
      item.imu = s.imu;
      ++counts_.imu;
    } else {
      if (s.encoder.t_s <= released_encoder_s_) { ++counts_.late_samples; continue; }
      released_encoder_s_ = s.encoder.t_s;
      item.kind = LiveItem::Kind::kEncoder;
      item.encoder = s.encoder;
      ++counts_.encoder;
    }
    out->push_back(std::move(item));
  }
}

void LiveMerger::EmitPacket(std::vector<LiveItem>* out) {
  LiveItem item;
  item.kind = LiveItem::Kind::kPacket;
  item.packet = std::move(packets_.front());
  packets_.pop_front();
  // Rig capture time; never before the previous packet's (the recording is in capture order).
  item.packet.t_capture_s = std::max(HostToRig(item.packet.t_capture_s), released_packet_s_);
  released_packet_s_ = item.packet.t_capture_s;
  EmitSamplesUpTo(item.packet.t_capture_s, out);
  out->push_back(std::move(item));
  ++counts_.packets;
}

void LiveMerger::Release(double now_host_s, std::vector<LiveItem>* out) {
  while (!packets_.empty() && have_delay_) {
    const double host_s = packets_.front().t_capture_s;
    const bool reached = SamplesReachedS() >= HostToRig(host_s);
    if (!reached && now_host_s - host_s < config_.hold_s) break;
    if (!reached) ++counts_.hold_timeouts;
    EmitPacket(out);
  }
  // Without packets to wait for, samples go once they are hold_s old.
  if (packets_.empty() && have_delay_) EmitSamplesUpTo(HostToRig(now_host_s) - config_.hold_s, out);
  if (!have_delay_ && !samples_.empty() && samples_.rbegin()->first - samples_.begin()->first > 10.0) {
    EmitSamplesUpTo(samples_.rbegin()->first - 10.0, out);  // no LiDAR yet: keep at most 10 s of samples
  }
}

void LiveMerger::ReleaseAll(std::vector<LiveItem>* out) {
  while (!packets_.empty()) EmitPacket(out);
  EmitSamplesUpTo(1e300, out);
}

}  // namespace rotolidar::bench
