#include "core/wire/packet_gaps.hpp"

#include <cmath>

namespace rotolidar {
namespace {
constexpr int64_t kHourUs = 3600LL * 1000000LL;
constexpr double kSingleReturnPeriodUs = 12 * 2 * 55.296;
constexpr uint8_t kDualReturnMode = 0x39;
}  // namespace

bool Vlp16DataTimestamp(const uint8_t* payload, std::size_t size, uint32_t* timestamp_us, uint8_t* return_mode) {
  if (size != 1206) return false;
  const uint8_t* b = payload + 1200;
  *timestamp_us = uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
  *return_mode = payload[1204];
  return true;
}

double Vlp16PacketPeriodUs(uint8_t return_mode) {
  return return_mode == kDualReturnMode ? 0.5 * kSingleReturnPeriodUs : kSingleReturnPeriodUs;
}

std::size_t Vlp16GapCounter::Add(uint32_t timestamp_us, uint8_t return_mode) {
  if (!have_last_) {
    have_last_ = true;
    last_us_ = timestamp_us;
    return 0;
  }
  int64_t step = static_cast<int64_t>(timestamp_us) - static_cast<int64_t>(last_us_);
  if (step < -kHourUs / 2) step += kHourUs;  // the hour wrapped between the two
  if (step > kHourUs / 2) step -= kHourUs;
  if (step <= 0) {
    ++out_of_order_;
    return 0;
  }
  last_us_ = timestamp_us;
  const double periods = static_cast<double>(step) / Vlp16PacketPeriodUs(return_mode);
  // Timestamps jitter by a microsecond or two; a step of k periods (k >= 2) means k - 1 missing packets.
  const long k = std::lround(periods);
  const std::size_t missing = k >= 2 ? static_cast<std::size_t>(k - 1) : 0;
  lost_ += missing;
  return missing;
}

}  // namespace rotolidar
