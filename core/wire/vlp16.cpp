// VLP-16 wire format: raw data/position packet fields and the encoder the sim uses (decoder: vlp16_decoder.cpp).
#include "core/wire/vlp16.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
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

const std::vector<std::pair<const char*, Vlp16ReturnMode>>& EnumWords(Vlp16ReturnMode*) {
  static const std::vector<std::pair<const char*, Vlp16ReturnMode>> words{
      {"strongest", Vlp16ReturnMode::kStrongest}, {"last", Vlp16ReturnMode::kLast}, {"dual", Vlp16ReturnMode::kDual}};
  return words;
}

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

int64_t UnixDaysFromCivil(int year, int month, int day) {
  // Howard Hinnant's days_from_civil: days since 1970-01-01 of a proleptic Gregorian date.
  const int y = year - (month <= 2 ? 1 : 0);
  const int era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = static_cast<unsigned>((153 * (month + (month > 2 ? -3 : 9)) + 2) / 5 + day - 1);
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return static_cast<int64_t>(era) * 146097 + static_cast<int64_t>(doe) - 719468;
}

namespace {

void CivilFromDays(int64_t z, int* year, int* month, int* day) {
  z += 719468;  // the inverse of UnixDaysFromCivil (same source)
  const int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  *day = static_cast<int>(doy - (153 * mp + 2) / 5 + 1);
  *month = static_cast<int>(mp < 10 ? mp + 3 : mp - 9);
  *year = static_cast<int>(yoe + era * 400 + (*month <= 2 ? 1 : 0));
}

unsigned NmeaChecksum(const std::string& body) {
  unsigned x = 0;
  for (char c : body) x ^= static_cast<unsigned char>(c);
  return x;
}

/// ddmm.mmmm (latitude, 2 degree digits) or dddmm.mmmm (longitude, 3).
std::string NmeaAngle(double deg, int degree_digits) {
  const double a = std::abs(deg);
  int whole = static_cast<int>(a);
  double minutes = (a - whole) * 60.0;
  if (minutes >= 59.99995) whole += 1, minutes = 0.0;  // would print as 60.0000
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%0*d%07.4f", degree_digits, whole, minutes);
  return buf;
}

}  // namespace

std::string FormatGprmc(double utc_unix_s, bool valid, double latitude_deg, double longitude_deg) {
  const int64_t t = static_cast<int64_t>(std::floor(std::max(0.0, utc_unix_s)));
  const int64_t days = t / 86400, sec = t % 86400;
  int year = 1970, month = 1, day = 1;
  CivilFromDays(days, &year, &month, &day);
  char buf[128];
  std::snprintf(buf, sizeof(buf), "GPRMC,%02d%02d%02d,%c,%s,%c,%s,%c,000.0,000.0,%02d%02d%02d,,,%c",
                static_cast<int>(sec / 3600), static_cast<int>(sec / 60 % 60), static_cast<int>(sec % 60),
                valid ? 'A' : 'V', NmeaAngle(latitude_deg, 2).c_str(), latitude_deg < 0 ? 'S' : 'N',
                NmeaAngle(longitude_deg, 3).c_str(), longitude_deg < 0 ? 'W' : 'E', day, month, year % 100,
                valid ? 'A' : 'N');
  const std::string body = buf;
  char tail[8];
  std::snprintf(tail, sizeof(tail), "*%02X\r\n", NmeaChecksum(body));
  return "$" + body + tail;
}

Status ParseGprmcUtc(const std::string& sentence, double* utc_unix_s) {
  auto fail = [&](const std::string& what) { return Status::Error("RMC sentence: " + what); };
  if (sentence.size() < 7 || sentence[0] != '$' || sentence.compare(3, 3, "RMC") != 0) {
    return fail("does not start with $--RMC");
  }
  std::string body = sentence.substr(1);
  const std::size_t star = body.find('*');
  if (star != std::string::npos) {
    unsigned given = 0;
    if (std::sscanf(body.c_str() + star + 1, "%2x", &given) != 1) return fail("unreadable checksum");
    body.resize(star);
    if (given != NmeaChecksum(body)) return fail("checksum mismatch");
  }
  std::vector<std::string> fields(1);
  for (char c : body) {
    if (c == ',') fields.emplace_back();
    else if (c != '\r' && c != '\n') fields.back() += c;
  }
  if (fields.size() < 10) return fail("has " + std::to_string(fields.size()) + " fields (need >= 10)");
  int hh = 0, mm = 0, dd = 0, mo = 0, yy = 0;
  double ss = 0.0;
  if (fields[1].size() < 6 || std::sscanf(fields[1].c_str(), "%2d%2d%lf", &hh, &mm, &ss) != 3 || hh > 23 ||
      mm > 59 || !(ss >= 0.0 && ss < 61.0)) {
    return fail("field 1 (UTC time hhmmss) '" + fields[1] + "'");
  }
  if (fields[9].size() != 6 || std::sscanf(fields[9].c_str(), "%2d%2d%2d", &dd, &mo, &yy) != 3 || dd < 1 ||
      dd > 31 || mo < 1 || mo > 12) {
    return fail("field 9 (date ddmmyy) '" + fields[9] + "'");
  }
  const int year = yy < 80 ? 2000 + yy : 1900 + yy;
  *utc_unix_s = static_cast<double>(UnixDaysFromCivil(year, mo, dd)) * 86400.0 + hh * 3600.0 + mm * 60.0 + ss;
  return Status::Ok();
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

Vlp16PacketEncoder::Vlp16PacketEncoder(Vlp16ReturnMode mode, double lidar_clock_offset_s, double clock_drift_ppm)
    : mode_(mode), lidar_clock_offset_s_(lidar_clock_offset_s), clock_drift_ppm_(clock_drift_ppm) {
  packet_.return_mode = static_cast<uint8_t>(mode);
  packet_.product_id = kVlp16ProductId;
}

std::optional<LidarPacket> Vlp16PacketEncoder::Add(const Vlp16FiringSequence& sequence) {
  const int i = pending_;
  const int firing = i % 2;
  if (i == 0) {  // the drift as an offset that grows with rig time (exactly the constant offset at drift 0)
    const double offset_s = lidar_clock_offset_s_ - clock_drift_ppm_ * 1e-6 * sequence.t_s;
    packet_.timestamp_us = Vlp16TimestampUs(sequence.t_s, offset_s);
  }
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
