// Time-ordering of live streams (contract in live_merger.hpp).
#include "bench/live/live_merger.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
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
  if (!std::isfinite(lidar_clock_offset_s) || !std::isfinite(min_capture_s)) {
    if (error) *error = "lidar_clock_offset_s, min_capture_s: not finite";
    return false;
  }
  return true;
}

LiveMerger::LiveMerger(const LiveMergerConfig& config)
    : config_(config), released_packet_s_(config.min_capture_s) {}

bool LiveMerger::DataCaptureTime(const LidarPacket& packet, double* t_s) const {
  if (packet.udp_port == kVlp16PositionPort || packet.payload.size() != kVlp16PacketBytes) return false;
  Vlp16RawPacket raw;
  if (!ParseVlp16DataPacket(packet.payload.data(), packet.payload.size(), &raw)) return false;
  // The twin's capture rule (core/wire/vlp16.hpp): last firing sequence + 15 firings + transmit latency.
  int64_t unwrapped_us = raw.timestamp_us;  // microseconds past the hour, unwrapped against the anchor
  if (have_anchor_) {
    const double hour_s = 3600.0, ref_s = anchor_rig_s_ - config_.lidar_clock_offset_s;
    unwrapped_us += static_cast<int64_t>(std::llround(std::floor(ref_s / hour_s) * hour_s * 1e6));
    if (unwrapped_us * 1e-6 - ref_s > hour_s / 2) unwrapped_us -= 3600000000LL;
    if (ref_s - unwrapped_us * 1e-6 > hour_s / 2) unwrapped_us += 3600000000LL;
  }
  *t_s = unwrapped_us * 1e-6 + config_.lidar_clock_offset_s + Vlp16PacketPeriodUs(raw.return_mode) * 1e-6 -
         55.296e-6 + 15 * kVlp16FiringPeriodS + kVlp16TransmitLatencyS;
  return true;
}

void LiveMerger::AddPacket(LidarPacket packet) {
  double rig_s = std::numeric_limits<double>::quiet_NaN();
  if (DataCaptureTime(packet, &rig_s)) {
    have_anchor_ = true;
    anchor_rig_s_ = rig_s;
    anchor_host_s_ = packet.t_capture_s;
  }
  packets_.push_back({std::move(packet), rig_s});
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
  Held held = std::move(packets_.front());
  packets_.pop_front();
  LiveItem item;
  item.kind = LiveItem::Kind::kPacket;
  item.packet = std::move(held.packet);
  const double rig_s = std::isnan(held.rig_s) ? HostToRig(item.packet.t_capture_s) : held.rig_s;
  // Never before the previous packet's (the recording is in capture order), nor before the recording's epoch.
  item.packet.t_capture_s = std::max(rig_s, released_packet_s_);
  released_packet_s_ = item.packet.t_capture_s;
  EmitSamplesUpTo(item.packet.t_capture_s, out);
  out->push_back(std::move(item));
  ++counts_.packets;
}

void LiveMerger::Release(double now_host_s, std::vector<LiveItem>* out) {
  while (!packets_.empty() && have_anchor_) {
    const Held& front = packets_.front();
    const double rig_s = std::isnan(front.rig_s) ? HostToRig(front.packet.t_capture_s) : front.rig_s;
    const bool reached = SamplesReachedS() >= rig_s;
    if (!reached && now_host_s - front.packet.t_capture_s < config_.hold_s) break;
    if (!reached) ++counts_.hold_timeouts;
    EmitPacket(out);
  }
  // Without packets to wait for, samples go once they are hold_s old.
  if (packets_.empty() && have_anchor_) EmitSamplesUpTo(HostToRig(now_host_s) - config_.hold_s, out);
  if (!have_anchor_ && !samples_.empty() && samples_.rbegin()->first - samples_.begin()->first > 10.0) {
    EmitSamplesUpTo(samples_.rbegin()->first - 10.0, out);  // no LiDAR yet: keep at most 10 s of samples
  }
}

void LiveMerger::ReleaseAll(std::vector<LiveItem>* out) {
  while (!packets_.empty()) EmitPacket(out);
  EmitSamplesUpTo(1e300, out);
}

}  // namespace rotolidar::bench
