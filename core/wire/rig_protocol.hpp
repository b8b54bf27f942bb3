#pragma once
// The rig-sample protocol: how a rig's IMU and motor-encoder samples reach a live estimator over UDP (a
// microcontroller that reads the encoder and the IMU can send it; `rotolidar replay --rig-port` sends it from a
// recording). Spec: docs/live.md. One datagram, all fields little-endian:
//
//   offset size  field
//        0    4  magic "RLRS" (52 4C 52 53)
//        4    1  version = 1
//        5    1  record count N, 1..kRigMaxRecords
//        6    2  reserved, 0
//        8    4  sequence number uint32: +1 per datagram from one sender (wraps); gaps = lost datagrams
//       12    4  reserved, 0
//   16+64*i   64 record i:
//        +0   1  type: 1 = IMU, 2 = encoder
//        +1   3  reserved, 0
//        +4   4  encoder count uint32 (type 2; 0 for IMU): single-turn absolute reading, < counts_per_rev
//        +8   8  time int64 [ns] on the rig clock (core/types/time.hpp)
//       +16  48  IMU (type 1; zeros for encoder): gyro x y z [rad/s], accel x y z [m/s^2], IEEE-754 float64,
//                in the imu frame (the ImuSample contract)
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/types/messages.hpp"
#include "core/util/status.hpp"

namespace rotolidar {

inline constexpr std::size_t kRigHeaderBytes = 16;
inline constexpr std::size_t kRigRecordBytes = 64;
inline constexpr std::size_t kRigMaxRecords = 20;  ///< 1296-byte datagrams: below a 1500-byte Ethernet MTU
inline constexpr uint8_t kRigProtocolVersion = 1;
/// The port `rotolidar live` listens on for rig samples by default (not a registered service).
inline constexpr uint16_t kRigSamplePort = 2370;

/// One record: an IMU sample or an encoder sample.
struct RigSample {
  enum class Type : uint8_t { kImu = 1, kEncoder = 2 };
  Type type = Type::kImu;
  ImuSample imu;          ///< type kImu
  EncoderSample encoder;  ///< type kEncoder
  Seconds t_s() const { return type == Type::kImu ? imu.t_s : encoder.t_s; }
};

struct RigDatagram {
  uint32_t sequence = 0;
  std::vector<RigSample> samples;
};

/// Encodes 1..kRigMaxRecords samples (times rounded to the nanosecond). Fails on an empty or oversized batch
/// or a time that does not fit int64 ns.
Status EncodeRigDatagram(const RigDatagram& datagram, std::vector<uint8_t>* bytes);
/// Decodes one datagram. Errors name the byte offset and the field (magic, version, count, size, type, time,
/// non-finite IMU value) and leave *datagram unspecified.
Status DecodeRigDatagram(const uint8_t* data, std::size_t size, RigDatagram* datagram);

}  // namespace rotolidar
