// VLP-16 data packets in timestamp order (contract in packet_orderer.hpp).
#include "core/wire/packet_orderer.hpp"

#include <cmath>
#include <cstdlib>

#include "core/wire/packet_gaps.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar {
namespace {

constexpr int64_t kHourUs = 3600LL * 1000000LL;
bool TimestampOf(const LidarPacket& p, uint32_t* us) {
  uint8_t mode = 0;
  return p.udp_port != kVlp16PositionPort && Vlp16DataTimestamp(p.payload.data(), p.payload.size(), us, &mode);
}

}  // namespace

bool PacketOrderConfig::Validate(std::string* error) const {
  if (!(window_s >= 0.0 && window_s <= 10.0)) {
    if (error) *error = "window_s: must be in [0, 10] s";
    return false;
  }
  if (!(max_jump_s > window_s)) {
    if (error) *error = "max_jump_s: must be more than window_s";
    return false;
  }
  if (confirm_packets < 1) {
    if (error) *error = "confirm_packets: must be >= 1";
    return false;
  }
  return true;
}

PacketOrderer::PacketOrderer(const PacketOrderConfig& config) : config_(config) {}

int64_t PacketOrderer::Unwrap(uint32_t timestamp_us) const {
  if (!have_stream_) return timestamp_us;
  const int64_t hour = newest_us_ >= 0 ? newest_us_ / kHourUs : (newest_us_ - kHourUs + 1) / kHourUs;
  int64_t key = hour * kHourUs + timestamp_us;
  if (key - newest_us_ > kHourUs / 2) key -= kHourUs;
  if (newest_us_ - key > kHourUs / 2) key += kHourUs;
  return key;
}

void PacketOrderer::Accept(int64_t key, LidarPacket packet) {
  if (have_stream_ && key < newest_us_) ++counts_.reordered;
  if (!have_stream_ || key > newest_us_) newest_us_ = key;
  have_stream_ = true;
  ++stream_packets_;
  held_.emplace(key, std::move(packet));
}

void PacketOrderer::ReleaseOld(std::vector<LidarPacket>* released) {
  const int64_t window_us = static_cast<int64_t>(std::llround(config_.window_s * 1e6));
  while (!held_.empty() && newest_us_ - held_.begin()->first >= window_us) {
    released_us_ = held_.begin()->first;
    have_released_ = true;
    recent_.insert(released_us_);  // to tell a duplicate from a late packet, over the last max_jump_s
    while (!recent_.empty() && *recent_.begin() < released_us_ - static_cast<int64_t>(config_.max_jump_s * 1e6))
      recent_.erase(recent_.begin());
    released->push_back(std::move(held_.begin()->second));
    held_.erase(held_.begin());
  }
}

// A packet far from the stream: held until confirm_packets agreeing ones say the stream really jumped.
void PacketOrderer::TakeSuspect(int64_t key, LidarPacket packet, std::vector<LidarPacket>* released) {
  const int64_t jump_us = static_cast<int64_t>(config_.max_jump_s * 1e6);
  if (!suspects_.empty() && std::llabs(key - suspects_.back().first) > jump_us) {
    counts_.wild += suspects_.size();  // the suspects disagree with each other too
    suspects_.clear();
  }
  suspects_.emplace_back(key, std::move(packet));
  if (static_cast<int>(suspects_.size()) < config_.confirm_packets) return;
  // Confirmed. A stream of fewer packets than the confirmation needs was itself the corrupt one (e.g. the very
  // first packet had a bad stamp): dropped. Otherwise what was held before the jump goes first.
  if (stream_packets_ < static_cast<std::size_t>(config_.confirm_packets)) {
    counts_.wild += held_.size();
    held_.clear();
  }
  for (auto& [k, p] : held_) released->push_back(std::move(p));
  held_.clear();
  have_released_ = false;
  recent_.clear();
  stream_packets_ = 0;
  newest_us_ = suspects_.front().first;
  for (auto& [k, p] : suspects_) Accept(k, std::move(p));
  suspects_.clear();
  ReleaseOld(released);
}

void PacketOrderer::Push(LidarPacket packet, std::vector<LidarPacket>* released) {
  uint32_t stamp = 0;
  if (!TimestampOf(packet, &stamp)) {
    released->push_back(std::move(packet));
    return;
  }
  // Keys of the stream's hour; a suspect is unwrapped against the stream as well.
  const int64_t key = Unwrap(stamp);
  if (have_stream_ && std::llabs(key - newest_us_) > static_cast<int64_t>(config_.max_jump_s * 1e6)) {
    TakeSuspect(key, std::move(packet), released);
    return;
  }
  if (!suspects_.empty()) {  // the stream went on: the suspects were corrupt
    counts_.wild += suspects_.size();
    suspects_.clear();
  }
  if (held_.count(key) || recent_.count(key)) {
    ++counts_.duplicate;
    return;
  }
  if (have_released_ && key < released_us_) {
    ++counts_.late;
    return;
  }
  Accept(key, std::move(packet));
  ReleaseOld(released);
}

void PacketOrderer::Flush(std::vector<LidarPacket>* released) {
  counts_.wild += suspects_.size();
  suspects_.clear();
  for (auto& [key, packet] : held_) released->push_back(std::move(packet));
  held_.clear();
}

}  // namespace rotolidar
