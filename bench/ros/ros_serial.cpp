#include "bench/ros/ros_serial.hpp"

#include <cstring>

namespace rotolidar::bench::rosmsg {

Status RosTimeFromNs(int64_t ns, const std::string& what, RosTime* out) {
  constexpr int64_t kMaxNs = static_cast<int64_t>(UINT32_MAX) * 1000000000LL + 999999999LL;
  if (ns < 0 || ns > kMaxNs)
    return Status::Error(what + ": time " + std::to_string(ns) + " ns is outside ROS time (1970..2106)");
  out->sec = static_cast<uint32_t>(ns / 1000000000LL);
  out->nsec = static_cast<uint32_t>(ns % 1000000000LL);
  return Status::Ok();
}

void RosWriter::U32(uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

void RosWriter::F32(float v) {
  uint32_t bits = 0;
  std::memcpy(&bits, &v, 4);
  U32(bits);
}

void RosWriter::F64(double v) {
  uint64_t bits = 0;
  std::memcpy(&bits, &v, 8);
  for (int i = 0; i < 8; ++i) bytes_.push_back(static_cast<uint8_t>(bits >> (8 * i)));
}

void RosWriter::String(const std::string& s) {
  U32(static_cast<uint32_t>(s.size()));
  Bytes(reinterpret_cast<const uint8_t*>(s.data()), s.size());
}

bool RosReader::Need(const char* field, std::size_t n) {
  if (!status_.ok) return false;
  if (n <= size_ - pos_) return true;
  status_ =
      Status::Error("field '" + std::string(field) + "' at byte " + std::to_string(pos_) + ": message ends (needs " +
                    std::to_string(n) + " bytes, " + std::to_string(size_ - pos_) + " left)");
  return false;
}

uint8_t RosReader::U8(const char* field) {
  if (!Need(field, 1)) return 0;
  return data_[pos_++];
}

uint32_t RosReader::U32(const char* field) {
  if (!Need(field, 4)) return 0;
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(data_[pos_ + i]) << (8 * i);
  pos_ += 4;
  return v;
}

float RosReader::F32(const char* field) {
  const uint32_t bits = U32(field);
  float v = 0.0f;
  std::memcpy(&v, &bits, 4);
  return v;
}

double RosReader::F64(const char* field) {
  if (!Need(field, 8)) return 0.0;
  uint64_t bits = 0;
  for (int i = 0; i < 8; ++i) bits |= static_cast<uint64_t>(data_[pos_ + i]) << (8 * i);
  pos_ += 8;
  double v = 0.0;
  std::memcpy(&v, &bits, 8);
  return v;
}

RosTime RosReader::Time(const char* field) {
  RosTime t;
  t.sec = U32(field);
  t.nsec = U32(field);
  if (status_.ok && t.nsec >= 1000000000u) {
    status_ = Status::Error("field '" + std::string(field) + "' at byte " + std::to_string(pos_ - 4) + ": nsec " +
                            std::to_string(t.nsec) + " is not below 1e9");
  }
  return t;
}

std::string RosReader::String(const char* field) {
  const uint32_t n = U32(field);
  if (!Need(field, n)) return {};
  std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
  pos_ += n;
  return s;
}

uint32_t RosReader::Count(const char* field, std::size_t min_element_bytes) {
  const std::size_t at = pos_;
  const uint32_t n = U32(field);
  if (!status_.ok) return 0;
  if (min_element_bytes > 0 && n > (size_ - pos_) / min_element_bytes) {
    status_ = Status::Error("field '" + std::string(field) + "' at byte " + std::to_string(at) + ": length " +
                            std::to_string(n) + " cannot fit in the " + std::to_string(size_ - pos_) + " bytes left");
    return 0;
  }
  return n;
}

void RosReader::Bytes(const char* field, std::size_t n, uint8_t* out) {
  if (!Need(field, n)) return;
  if (n > 0) std::memcpy(out, data_ + pos_, n);
  pos_ += n;
}

Status RosReader::Finish() const {
  if (!status_.ok) return status_;
  if (pos_ != size_)
    return Status::Error(std::to_string(size_ - pos_) + " bytes left after the last field (byte " +
                         std::to_string(pos_) + " of " + std::to_string(size_) + "): not this message layout");
  return Status::Ok();
}

}  // namespace rotolidar::bench::rosmsg
