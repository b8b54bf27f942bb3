#pragma once
// ROS 1 wire serialisation primitives (the format of a message body in a bag or on TCPROS): little-endian
// integers and IEEE floats, `time` as {uint32 sec, uint32 nsec}, strings and variable arrays prefixed by a uint32
// length, fixed arrays without prefix. No ROS headers: this is plain byte work, shared by the hand-written
// messages of bench/ros/ros_messages.hpp.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/util/status.hpp"

namespace rotolidar::bench::rosmsg {

/// A ROS time: seconds and nanoseconds since the Unix epoch (nsec < 1e9).
struct RosTime {
  uint32_t sec = 0;
  uint32_t nsec = 0;
  int64_t ToNs() const { return static_cast<int64_t>(sec) * 1000000000LL + nsec; }
  bool operator==(const RosTime& o) const { return sec == o.sec && nsec == o.nsec; }
};
/// Nanoseconds since the Unix epoch -> RosTime; fails (naming `what`) when ns is negative or past 2106.
Status RosTimeFromNs(int64_t ns, const std::string& what, RosTime* out);

/// Appends ROS 1 serialised fields to a byte buffer.
class RosWriter {
 public:
  void U8(uint8_t v) { bytes_.push_back(v); }
  void U32(uint32_t v);
  void F32(float v);
  void F64(double v);
  void Time(const RosTime& t) { U32(t.sec), U32(t.nsec); }
  void String(const std::string& s);
  void Bytes(const uint8_t* data, std::size_t n) { bytes_.insert(bytes_.end(), data, data + n); }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

/// Reads ROS 1 serialised fields with bounds checks. The first failure sticks: later reads return zeros and
/// status() reports the failure as "field 'NAME' at byte OFFSET: ..." (needs N bytes, M left / a length that
/// cannot fit). Fields are named by their message path, e.g. "angular_velocity.x".
class RosReader {
 public:
  RosReader(const uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  uint8_t U8(const char* field);
  uint32_t U32(const char* field);
  float F32(const char* field);
  double F64(const char* field);
  RosTime Time(const char* field);
  std::string String(const char* field);
  /// Reads a variable array's uint32 length and checks that `count * min_element_bytes` bytes remain.
  uint32_t Count(const char* field, std::size_t min_element_bytes);
  /// Copies n raw bytes (uint8[] data).
  void Bytes(const char* field, std::size_t n, uint8_t* out);
  bool ok() const { return status_.ok; }
  std::size_t offset() const { return pos_; }
  std::size_t remaining() const { return size_ - pos_; }
  /// The sticky error, or an error when bytes are left after the last field (a different message layout).
  Status Finish() const;
  const Status& status() const { return status_; }

 private:
  bool Need(const char* field, std::size_t n);
  const uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  Status status_;
};

}  // namespace rotolidar::bench::rosmsg
