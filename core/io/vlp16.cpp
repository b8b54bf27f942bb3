// VLP-16 wire format: raw data/position packet fields and the encoder the sim uses (decoder: vlp16_decoder.cpp).
#include "core/io/vlp16.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

namespace rotolidar {
namespace {

constexpr std::size_t kBlockBytes = 100;
constexpr std::size_t kTimestampOffset = 1200;
constexpr std::size_t kReturnModeOffset = 1204;
constexpr std::size_t kProductIdOffset = 1205;
constexpr std::size_t kPositionTimestampOffset = 198;
constexpr std::size_t kPpsOffset = 202;

uint16_t ReadU16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t ReadU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}
void WriteU16(uint16_t v, uint8_t* p) {
  p[0] = static_cast<uint8_t>(v & 0xFF);
  p[1] = static_cast<uint8_t>(v >> 8);
}
void WriteU32(uint32_t v, uint8_t* p) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>((v >> (8 * i)) & 0xFF);
}

std::string Hex(unsigned v) {
  std::ostringstream os;
  os << "0x" << std::hex << v;
  return os.str();
}

Status FieldError(std::size_t offset, const std::string& what) {
  return Status::Error("VLP-16 data packet: byte offset " + std::to_string(offset) + ": " + what);
}

bool KnownReturnMode(uint8_t mode) {
  return mode == static_cast<uint8_t>(Vlp16ReturnMode::kStrongest) ||
         mode == static_cast<uint8_t>(Vlp16ReturnMode::kLast) ||
         mode == static_cast<uint8_t>(Vlp16ReturnMode::kDual);
}

Status ParseBlock(const uint8_t* p, std::size_t offset, int index, Vlp16RawBlock* block) {
  block->flag = ReadU16(p);
  if (block->flag != kVlp16BlockFlag) {
    return FieldError(offset, "block " + std::to_string(index) + " flag " + Hex(block->flag) +
                                  " (expected bytes FF EE = " + Hex(kVlp16BlockFlag) + ")");
  }
  block->azimuth_centideg = ReadU16(p + 2);
  if (block->azimuth_centideg >= 36000) {
    return FieldError(offset + 2, "block " + std::to_string(index) + " azimuth " +
                                      std::to_string(block->azimuth_centideg) + " >= 36000 (0.01 deg)");
  }
  for (int ch = 0; ch < 32; ++ch) {
    block->distance_2mm[ch] = ReadU16(p + 4 + 3 * ch);
    block->reflectivity[ch] = p[4 + 3 * ch + 2];
  }
  return Status::Ok();
}

}  // namespace

Status ParseVlp16DataPacket(const uint8_t* data, std::size_t size, Vlp16RawPacket* out) {
  if (data == nullptr || size != kVlp16PacketBytes) {
    return FieldError(0, "packet size " + std::to_string(size) + " bytes (expected " +
                             std::to_string(kVlp16PacketBytes) + ")");
  }
  Vlp16RawPacket packet;
  for (int b = 0; b < 12; ++b) {
    const Status s = ParseBlock(data + kBlockBytes * b, kBlockBytes * b, b, &packet.blocks[b]);
    if (!s) return s;
  }
  packet.timestamp_us = ReadU32(data + kTimestampOffset);
  if (packet.timestamp_us >= kVlp16MicrosPerHour) {
    return FieldError(kTimestampOffset,
                      "timestamp " + std::to_string(packet.timestamp_us) + " us >= 3.6e9 (one hour)");
  }
  packet.return_mode = data[kReturnModeOffset];
  if (!KnownReturnMode(packet.return_mode)) {
    return FieldError(kReturnModeOffset, "return mode " + Hex(packet.return_mode) + " (expected 0x37, 0x38, 0x39)");
  }
  packet.product_id = data[kProductIdOffset];
  if (packet.product_id != kVlp16ProductId) {
    return FieldError(kProductIdOffset, "product id " + Hex(packet.product_id) + " (expected 0x22 = VLP-16)");
  }
  *out = packet;
  return Status::Ok();
}

std::vector<uint8_t> SerializeVlp16DataPacket(const Vlp16RawPacket& packet) {
  std::vector<uint8_t> bytes(kVlp16PacketBytes, 0);
  for (int b = 0; b < 12; ++b) {
    uint8_t* p = bytes.data() + kBlockBytes * b;
    const Vlp16RawBlock& block = packet.blocks[b];
    WriteU16(block.flag, p);
    WriteU16(block.azimuth_centideg, p + 2);
    for (int ch = 0; ch < 32; ++ch) {
      WriteU16(block.distance_2mm[ch], p + 4 + 3 * ch);
      p[4 + 3 * ch + 2] = block.reflectivity[ch];
    }
  }
  WriteU32(packet.timestamp_us, bytes.data() + kTimestampOffset);
  bytes[kReturnModeOffset] = packet.return_mode;
  bytes[kProductIdOffset] = packet.product_id;
  return bytes;
}

uint32_t Vlp16TimestampUs(Seconds t_s, double lidar_clock_offset_s) {
  const double us = std::floor((t_s - lidar_clock_offset_s) * 1e6 + 1e-6);
  const int64_t hour = static_cast<int64_t>(kVlp16MicrosPerHour);
  int64_t v = static_cast<int64_t>(us) % hour;
  if (v < 0) v += hour;
  return static_cast<uint32_t>(v);
}

LidarPacket EncodeVlp16PositionPacket(Seconds t_s, double lidar_clock_offset_s, uint8_t pps_status,
                                      const std::string& nmea_gprmc) {
  LidarPacket packet;
  packet.t_capture_s = t_s;
  packet.udp_port = kVlp16PositionPort;
  packet.payload.assign(kVlp16PositionPacketBytes, 0);
  WriteU32(Vlp16TimestampUs(t_s, lidar_clock_offset_s), packet.payload.data() + kPositionTimestampOffset);
  packet.payload[kPpsOffset] = pps_status;
  const std::size_t n = std::min(nmea_gprmc.size(), kVlp16NmeaMaxBytes);
  std::memcpy(packet.payload.data() + kVlp16NmeaOffset, nmea_gprmc.data(), n);
  return packet;
}

Status ParseVlp16PositionPacket(const uint8_t* data, std::size_t size, Vlp16PositionPacket* out) {
  auto error = [](std::size_t offset, const std::string& what) {
    return Status::Error("VLP-16 position packet: byte offset " + std::to_string(offset) + ": " + what);
  };
  if (data == nullptr || size != kVlp16PositionPacketBytes) {
    return error(0, "packet size " + std::to_string(size) + " bytes (expected 512)");
  }
  Vlp16PositionPacket packet;
  packet.timestamp_us = ReadU32(data + kPositionTimestampOffset);
  if (packet.timestamp_us >= kVlp16MicrosPerHour) {
    return error(kPositionTimestampOffset, "timestamp " + std::to_string(packet.timestamp_us) + " us >= 3.6e9");
  }
  packet.pps_status = data[kPpsOffset];
  if (packet.pps_status > 3) {
    return error(kPpsOffset, "PPS status " + std::to_string(packet.pps_status) + " (expected 0..3)");
  }
  const char* nmea = reinterpret_cast<const char*>(data + kVlp16NmeaOffset);
  packet.nmea.assign(nmea, strnlen(nmea, kVlp16NmeaMaxBytes));
  *out = packet;
  return Status::Ok();
}

Vlp16PacketEncoder::Vlp16PacketEncoder(Vlp16ReturnMode mode, double lidar_clock_offset_s)
    : mode_(mode), lidar_clock_offset_s_(lidar_clock_offset_s) {
  packet_.return_mode = static_cast<uint8_t>(mode);
  packet_.product_id = kVlp16ProductId;
}

std::optional<LidarPacket> Vlp16PacketEncoder::Add(const Vlp16FiringSequence& sequence) {
  const int i = pending_;
  const int firing = i % 2;
  if (i == 0) packet_.timestamp_us = Vlp16TimestampUs(sequence.t_s, lidar_clock_offset_s_);
  const bool dual = mode_ == Vlp16ReturnMode::kDual;
  const int block = dual ? 2 * (i / 2) : i / 2;
  for (int laser = 0; laser < 16; ++laser) {
    const int ch = 16 * firing + laser;
    packet_.blocks[block].distance_2mm[ch] = sequence.distance_2mm[laser];
    packet_.blocks[block].reflectivity[ch] = sequence.reflectivity[laser];
    if (dual) {
      packet_.blocks[block + 1].distance_2mm[ch] = sequence.distance2_2mm[laser];
      packet_.blocks[block + 1].reflectivity[ch] = sequence.reflectivity2[laser];
    }
  }
  if (firing == 0) {
    const uint16_t az = static_cast<uint16_t>(sequence.azimuth_centideg % 36000);
    packet_.blocks[block].azimuth_centideg = az;
    if (dual) packet_.blocks[block + 1].azimuth_centideg = az;
  }
  if (++pending_ < SequencesPerPacket()) return std::nullopt;
  pending_ = 0;
  LidarPacket out;
  out.t_capture_s = sequence.t_s + 15 * kVlp16FiringPeriodS + kVlp16TransmitLatencyS;
  out.udp_port = kVlp16DataPort;
  out.payload = SerializeVlp16DataPacket(packet_);
  return out;
}

}  // namespace rotolidar
