// VLP-16 packets in pcap files via libpcap; frame layout in pcap.hpp.
#include "core/wire/pcap.hpp"

#include <pcap/pcap.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

#include "core/wire/vlp16.hpp"
#include "core/util/log.hpp"

namespace rotolidar {
namespace {

constexpr std::size_t kEthBytes = 14, kIpBytes = 20, kUdpBytes = 8;
constexpr std::size_t kMaxUdpPayload = 65507;
constexpr int kDltLinuxSll = 113;
const uint8_t kSensorMac[6] = {0x60, 0x76, 0x88, 0x00, 0x00, 0x01};
const uint8_t kSensorIp[4] = {192, 168, 1, 201};

void PutU16Be(uint16_t v, uint8_t* p) {
  p[0] = static_cast<uint8_t>(v >> 8);
  p[1] = static_cast<uint8_t>(v & 0xFF);
}
uint16_t GetU16Be(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }

std::vector<uint8_t> BuildFrame(const LidarPacket& packet, uint16_t ip_id) {
  const std::size_t n = packet.payload.size();
  std::vector<uint8_t> frame(kEthBytes + kIpBytes + kUdpBytes + n, 0);
  uint8_t* eth = frame.data();
  std::memset(eth, 0xFF, 6);  // broadcast destination
  std::memcpy(eth + 6, kSensorMac, 6);
  PutU16Be(0x0800, eth + 12);
  uint8_t* ip = eth + kEthBytes;
  ip[0] = 0x45;  // IPv4, 5 words
  PutU16Be(static_cast<uint16_t>(kIpBytes + kUdpBytes + n), ip + 2);
  PutU16Be(ip_id, ip + 4);
  PutU16Be(0x4000, ip + 6);  // don't fragment
  ip[8] = 64;                // TTL
  ip[9] = 17;                // UDP
  std::memcpy(ip + 12, kSensorIp, 4);
  std::memset(ip + 16, 0xFF, 4);
  PutU16Be(Ipv4HeaderChecksum(ip, kIpBytes), ip + 10);
  uint8_t* udp = ip + kIpBytes;
  PutU16Be(packet.udp_port, udp);
  PutU16Be(packet.udp_port, udp + 2);
  PutU16Be(static_cast<uint16_t>(kUdpBytes + n), udp + 4);
  if (n > 0) std::memcpy(udp + kUdpBytes, packet.payload.data(), n);
  return frame;
}

}  // namespace

uint16_t Ipv4HeaderChecksum(const uint8_t* header, std::size_t bytes) {
  uint32_t sum = 0;
  for (std::size_t i = 0; i + 1 < bytes; i += 2) sum += GetU16Be(header + i);
  if (bytes % 2) sum += static_cast<uint32_t>(header[bytes - 1]) << 8;
  while (sum >> 16) sum = (sum & 0xFFFF) + (sum >> 16);
  return static_cast<uint16_t>(~sum & 0xFFFF);
}

// ---------------------------------------------------------------------------------------------------------------
// A destructor cannot return the flush's outcome: call Close() to handle it; here it is only logged.
PcapWriter::~PcapWriter() {
  if (Status s = Close(); !s) LOG_ERROR(s.message << " (closed by the destructor)");
}

Status PcapWriter::Open(const std::string& path, double epoch_unix_s) {
  if (Status s = Close(); !s) return s;
  pcap_t* pcap = pcap_open_dead(DLT_EN10MB, 65535);
  if (pcap == nullptr) return Status::Error(path + ": pcap_open_dead failed");
  pcap_dumper_t* dumper = pcap_dump_open(pcap, path.c_str());
  if (dumper == nullptr) {
    const std::string err = pcap_geterr(pcap);
    pcap_close(pcap);
    return Status::Error(path + ": cannot create pcap file: " + err);
  }
  pcap_ = pcap;
  dumper_ = dumper;
  path_ = path;
  epoch_unix_s_ = epoch_unix_s;
  written_ = 0;
  return Status::Ok();
}

Status PcapWriter::Write(const LidarPacket& packet) {
  if (dumper_ == nullptr) return Status::Error("PcapWriter: Write before Open");
  if (packet.payload.size() > kMaxUdpPayload) {
    return Status::Error(path_ + ": packet " + std::to_string(written_) + ": payload of " +
                         std::to_string(packet.payload.size()) + " bytes exceeds one UDP datagram");
  }
  const double t = epoch_unix_s_ + packet.t_capture_s;
  if (!(t >= 0.0) || !std::isfinite(t)) {
    return Status::Error(path_ + ": packet " + std::to_string(written_) + ": record time " + std::to_string(t) +
                         " s (epoch_unix_s + t_capture_s) is negative or not finite");
  }
  int64_t us = static_cast<int64_t>(std::llround(t * 1e6));
  const std::vector<uint8_t> frame = BuildFrame(packet, ip_id_++);
  pcap_pkthdr header{};
  header.ts.tv_sec = static_cast<time_t>(us / 1000000);
  header.ts.tv_usec = static_cast<suseconds_t>(us % 1000000);
  header.caplen = header.len = static_cast<bpf_u_int32>(frame.size());
  pcap_dump(reinterpret_cast<u_char*>(dumper_), &header, frame.data());
  ++written_;
  return Status::Ok();
}

Status PcapWriter::Close() {
  Status status;
  if (dumper_ != nullptr) {
    auto* dumper = static_cast<pcap_dumper_t*>(dumper_);
    if (pcap_dump_flush(dumper) != 0) status = Status::Error(path_ + ": write error while flushing pcap file");
    pcap_dump_close(dumper);
    dumper_ = nullptr;
  }
  if (pcap_ != nullptr) {
    pcap_close(static_cast<pcap_t*>(pcap_));
    pcap_ = nullptr;
  }
  return status;
}

// ---------------------------------------------------------------------------------------------------------------
PcapReader::~PcapReader() { Close(); }

void PcapReader::Close() {
  if (pcap_ != nullptr) pcap_close(static_cast<pcap_t*>(pcap_));
  pcap_ = nullptr;
}

Status PcapReader::Open(const std::string& path, double epoch_unix_s) {
  Close();
  char errbuf[PCAP_ERRBUF_SIZE] = {0};
  pcap_t* pcap = pcap_open_offline(path.c_str(), errbuf);
  if (pcap == nullptr) return Status::Error(path + ": cannot open pcap file: " + errbuf);
  link_type_ = pcap_datalink(pcap);
  if (link_type_ != DLT_EN10MB && link_type_ != kDltLinuxSll) {
    pcap_close(pcap);
    return Status::Error(path + ": unsupported link type " + std::to_string(link_type_) +
                         " (expected Ethernet or Linux cooked capture)");
  }
  pcap_ = pcap;
  path_ = path;
  epoch_unix_s_ = epoch_unix_s;
  records_ = skipped_ = 0;
  traffic_ = PcapTraffic();
  return Status::Ok();
}

Status PcapReader::NoVlp16DataError() const {
  return Status::Error(path_ + ": no VLP-16 data packets (" + std::to_string(kVlp16PacketBytes) +
                       "-byte payloads on UDP port " + std::to_string(kVlp16DataPort) + "): saw " +
                       traffic_.Describe());
}

std::string PcapTraffic::Describe() const {
  if (records == 0) return "no packets (the file holds a pcap header only)";
  std::vector<std::pair<std::pair<uint16_t, std::size_t>, std::size_t>> kinds(udp.begin(), udp.end());
  std::stable_sort(kinds.begin(), kinds.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::size_t datagrams = 0;
  for (const auto& kind : kinds) datagrams += kind.second;
  std::string text = std::to_string(datagrams) + " UDP packets";
  constexpr std::size_t kMaxKinds = 8;
  for (std::size_t i = 0; i < kinds.size() && i < kMaxKinds; ++i) {
    text += (i == 0 ? ": port " : ", port ") + std::to_string(kinds[i].first.first) + " x " +
            std::to_string(kinds[i].second) + " (payload " + std::to_string(kinds[i].first.second) + " B)";
  }
  if (kinds.size() > kMaxKinds) text += " and " + std::to_string(kinds.size() - kMaxKinds) + " more port/size kinds";
  if (other_frames > 0) text += "; " + std::to_string(other_frames) + " other frames (not UDP over IPv4)";
  return text;
}

bool PcapReader::Next(LidarPacket* packet, Status* status) {
  *status = Status::Ok();
  if (pcap_ == nullptr) {
    *status = Status::Error("PcapReader: Next before Open");
    return false;
  }
  for (;;) {
    pcap_pkthdr* header = nullptr;
    const u_char* data = nullptr;
    const int rc = pcap_next_ex(static_cast<pcap_t*>(pcap_), &header, &data);
    if (rc == PCAP_ERROR_BREAK) return false;  // end of file
    const std::size_t index = records_;
    if (rc != 1) {
      *status = Status::Error(path_ + ": record " + std::to_string(index) + ": " +
                              pcap_geterr(static_cast<pcap_t*>(pcap_)));
      return false;
    }
    ++records_;
    ++traffic_.records;
    bool is_vlp = false;
    const Status s = ParseFrame(data, header->caplen, header->len, packet, &is_vlp);
    if (!s) {
      *status = Status::Error(path_ + ": record " + std::to_string(index) + ": " + s.message);
      return false;
    }
    if (!is_vlp) {
      ++skipped_;
      continue;
    }
    packet->t_capture_s = static_cast<double>(header->ts.tv_sec) - epoch_unix_s_ + header->ts.tv_usec * 1e-6;
    return true;
  }
}

Status PcapReader::ParseFrame(const uint8_t* frame, std::size_t caplen, std::size_t len, LidarPacket* packet,
                              bool* is_vlp) {
  auto bad = [](std::size_t offset, const std::string& what) {
    return Status::Error("frame byte offset " + std::to_string(offset) + ": " + what);
  };
  *is_vlp = false;
  std::size_t ip = 0;
  uint16_t ethertype = 0;
  if (link_type_ == DLT_EN10MB) {
    if (caplen < kEthBytes) return bad(0, "truncated Ethernet header (" + std::to_string(caplen) + " bytes)");
    ethertype = GetU16Be(frame + 12);
    ip = kEthBytes;
    if (ethertype == 0x8100) {  // 802.1Q tag
      if (caplen < kEthBytes + 4) return bad(12, "truncated 802.1Q tag");
      ethertype = GetU16Be(frame + 16);
      ip = kEthBytes + 4;
    }
  } else {  // Linux cooked capture: 16-byte header, protocol at 14
    if (caplen < 16) return bad(0, "truncated Linux cooked header");
    ethertype = GetU16Be(frame + 14);
    ip = 16;
  }
  if (ethertype != 0x0800) {  // not IPv4: skipped
    ++traffic_.other_frames;
    return Status::Ok();
  }
  if (caplen < ip + kIpBytes) return bad(ip, "truncated IPv4 header");
  if ((frame[ip] >> 4) != 4) return bad(ip, "IP version " + std::to_string(frame[ip] >> 4) + " (expected 4)");
  const std::size_t ihl = 4u * (frame[ip] & 0x0F);
  const std::size_t total = GetU16Be(frame + ip + 2);
  if (ihl < kIpBytes || caplen < ip + ihl) return bad(ip, "IPv4 header length " + std::to_string(ihl));
  const uint16_t frag = GetU16Be(frame + ip + 6);
  // Not UDP, or a later fragment (which carries no UDP header): skipped.
  if (frame[ip + 9] != 17 || (frag & 0x1FFF) != 0) {
    ++traffic_.other_frames;
    return Status::Ok();
  }
  const std::size_t udp = ip + ihl;
  if (caplen < udp + kUdpBytes) return bad(udp, "truncated UDP header");
  const uint16_t port = GetU16Be(frame + udp + 2);
  const std::size_t udp_len = GetU16Be(frame + udp + 4);
  const std::size_t n = udp_len >= kUdpBytes ? udp_len - kUdpBytes : 0;
  ++traffic_.udp[{port, n}];
  if (port != kVlp16DataPort && port != kVlp16PositionPort) return Status::Ok();  // other traffic: skipped
  if (frag & 0x2000) return bad(ip + 6, "fragmented IPv4 datagram to port " + std::to_string(port));
  if (total < ihl + kUdpBytes || ip + total > caplen) {
    return bad(ip + 2, "IPv4 total length " + std::to_string(total) + " inconsistent with captured " +
                           std::to_string(caplen - ip) + " bytes (wire length " + std::to_string(len) + ")");
  }
  if (udp_len < kUdpBytes || udp + udp_len > ip + total) {
    return bad(udp + 4, "UDP length " + std::to_string(udp_len) + " inconsistent with IPv4 total length " +
                            std::to_string(total));
  }
  const std::size_t expected = port == kVlp16DataPort ? kVlp16PacketBytes : kVlp16PositionPacketBytes;
  if (n != expected) {
    return bad(udp + kUdpBytes, "UDP payload of " + std::to_string(n) + " bytes on port " + std::to_string(port) +
                                    " (expected " + std::to_string(expected) + ")");
  }
  packet->udp_port = port;
  packet->payload.assign(frame + udp + kUdpBytes, frame + udp + kUdpBytes + n);
  *is_vlp = true;
  traffic_.vlp16_data += port == kVlp16DataPort ? 1 : 0;
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------------------------
Status ReadRawVlp16Payloads(const std::string& path, std::vector<LidarPacket>* packets) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open raw VLP-16 payload file");
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return Status::Error(path + ": read error");
  const std::size_t whole = bytes.size() / kVlp16PacketBytes;
  if (bytes.size() % kVlp16PacketBytes != 0) {
    return Status::Error(path + ": byte offset " + std::to_string(whole * kVlp16PacketBytes) + ": trailing " +
                         std::to_string(bytes.size() % kVlp16PacketBytes) +
                         " bytes do not make a whole 1206-byte packet");
  }
  std::vector<LidarPacket> out(whole);
  for (std::size_t i = 0; i < whole; ++i) {
    out[i].udp_port = kVlp16DataPort;
    out[i].t_capture_s = 0.0;
    out[i].payload.assign(bytes.begin() + i * kVlp16PacketBytes, bytes.begin() + (i + 1) * kVlp16PacketBytes);
  }
  *packets = std::move(out);
  return Status::Ok();
}

}  // namespace rotolidar
