// Rig-sample datagrams (contract and layout in rig_protocol.hpp).
#include "core/wire/rig_protocol.hpp"

#include <cmath>
#include <cstring>
#include <string>

namespace rotolidar {
namespace {

constexpr uint8_t kMagic[4] = {'R', 'L', 'R', 'S'};

template <typename T>
void Put(uint8_t* at, T value) {  // little-endian hosts only (x86-64, ARM64); checked below
  std::memcpy(at, &value, sizeof(T));
}
template <typename T>
T Get(const uint8_t* at) {
  T value;
  std::memcpy(&value, at, sizeof(T));
  return value;
}
static_assert(sizeof(double) == 8, "float64 fields");

std::string At(std::size_t offset, const char* field) {
  return "rig datagram: byte " + std::to_string(offset) + " (" + field + "): ";
}

Status DecodeRecord(const uint8_t* r, std::size_t offset, RigSample* sample) {
  const uint8_t type = r[0];
  const int64_t t_ns = Get<int64_t>(r + 8);
  // Divided by the exactly representable 1e9: the double nearest to the decimal t_ns / 10^9, the value a CSV
  // with nanosecond times reads back (so a live session and its recording feed the estimator the same times).
  const double t_s = static_cast<double>(t_ns) / 1e9;
  if (type == static_cast<uint8_t>(RigSample::Type::kImu)) {
    sample->type = RigSample::Type::kImu;
    sample->imu.t_s = t_s;
    for (int i = 0; i < 6; ++i) {
      const double v = Get<double>(r + 16 + 8 * i);
      if (!std::isfinite(v))
        return Status::Error(At(offset + 16 + 8 * i, i < 3 ? "gyro" : "accel") + "not a finite number");
      (i < 3 ? sample->imu.gyro_radps : sample->imu.accel_mps2)[i % 3] = v;
    }
    return Status::Ok();
  }
  if (type == static_cast<uint8_t>(RigSample::Type::kEncoder)) {
    sample->type = RigSample::Type::kEncoder;
    sample->encoder.t_s = t_s;
    sample->encoder.count = Get<uint32_t>(r + 4);
    return Status::Ok();
  }
  return Status::Error(At(offset, "record type") + std::to_string(type) + " is neither 1 (IMU) nor 2 (encoder)");
}

}  // namespace

Status EncodeRigDatagram(const RigDatagram& datagram, std::vector<uint8_t>* bytes) {
  const std::size_t n = datagram.samples.size();
  if (n == 0 || n > kRigMaxRecords)
    return Status::Error("rig datagram: " + std::to_string(n) + " records (1.." + std::to_string(kRigMaxRecords) +
                         ")");
  bytes->assign(kRigHeaderBytes + n * kRigRecordBytes, 0);
  uint8_t* b = bytes->data();
  std::memcpy(b, kMagic, 4);
  b[4] = kRigProtocolVersion;
  b[5] = static_cast<uint8_t>(n);
  Put<uint32_t>(b + 8, datagram.sequence);
  for (std::size_t i = 0; i < n; ++i) {
    const RigSample& s = datagram.samples[i];
    uint8_t* r = b + kRigHeaderBytes + i * kRigRecordBytes;
    const double t_ns = std::round(s.t_s() * 1e9);
    if (!(std::fabs(t_ns) < 9.2e18)) return Status::Error("rig datagram: record " + std::to_string(i) +
                                                          ": time " + std::to_string(s.t_s()) + " s does not fit");
    r[0] = static_cast<uint8_t>(s.type);
    Put<int64_t>(r + 8, static_cast<int64_t>(t_ns));
    if (s.type == RigSample::Type::kEncoder) {
      Put<uint32_t>(r + 4, s.encoder.count);
    } else {
      for (int k = 0; k < 3; ++k) Put<double>(r + 16 + 8 * k, s.imu.gyro_radps[k]);
      for (int k = 0; k < 3; ++k) Put<double>(r + 40 + 8 * k, s.imu.accel_mps2[k]);
    }
  }
  return Status::Ok();
}

Status DecodeRigDatagram(const uint8_t* data, std::size_t size, RigDatagram* datagram) {
  if (size < kRigHeaderBytes) return Status::Error(At(0, "header") + std::to_string(size) + " bytes, need 16");
  if (std::memcmp(data, kMagic, 4) != 0) return Status::Error(At(0, "magic") + "not \"RLRS\"");
  if (data[4] != kRigProtocolVersion)
    return Status::Error(At(4, "version") + std::to_string(data[4]) + ", this reader knows 1");
  const std::size_t n = data[5];
  if (n == 0 || n > kRigMaxRecords) return Status::Error(At(5, "record count") + std::to_string(n));
  if (size != kRigHeaderBytes + n * kRigRecordBytes)
    return Status::Error(At(0, "size") + std::to_string(size) + " bytes, " + std::to_string(n) + " records need " +
                         std::to_string(kRigHeaderBytes + n * kRigRecordBytes));
  datagram->sequence = Get<uint32_t>(data + 8);
  datagram->samples.assign(n, RigSample{});
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t offset = kRigHeaderBytes + i * kRigRecordBytes;
    if (Status s = DecodeRecord(data + offset, offset, &datagram->samples[i]); !s) return s;
  }
  return Status::Ok();
}

}  // namespace rotolidar
