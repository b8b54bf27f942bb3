#pragma once
// Lost VLP-16 data packets, seen from the gaps in their own timestamps. The sensor sends one data packet every
// 12 blocks x 2 firing sequences x 55.296 us = 1327.104 us in a single-return mode and every 663.552 us in dual
// mode (VLP-16 user manual, section 9: 754 / 1508 packets per second), so a timestamp step of k periods means
// k - 1 packets never arrived. Packets have no sequence number: this is the only loss signal UDP gives.
#include <cstddef>
#include <cstdint>

namespace rotolidar {

/// Feed every data packet's (timestamp_us, return_mode byte) in arrival order. Not thread-safe.
class Vlp16GapCounter {
 public:
  /// Returns the packets lost right before this one (0 for the first, for a normal step or for a step back).
  /// A step back (reordered or duplicated packet) is counted in out_of_order() and does not move the reference.
  /// Steps over half an hour are taken as the hour wrapping (the timestamp counts microseconds past the hour).
  std::size_t Add(uint32_t timestamp_us, uint8_t return_mode);
  std::size_t lost() const { return lost_; }
  std::size_t out_of_order() const { return out_of_order_; }

 private:
  bool have_last_ = false;
  uint32_t last_us_ = 0;
  std::size_t lost_ = 0, out_of_order_ = 0;
};

/// The timestamp [us past the hour] and return-mode byte of a 1206-byte data payload (bytes 1200-1204, manual
/// 9.3.1.4), without parsing the rest; false for any other size.
bool Vlp16DataTimestamp(const uint8_t* payload, std::size_t size, uint32_t* timestamp_us, uint8_t* return_mode);

/// Packet period [us] for a return-mode byte (0x39 = dual: half the single-return period).
double Vlp16PacketPeriodUs(uint8_t return_mode);

}  // namespace rotolidar
