#pragma once
// VLP-16 packets in pcap files (libpcap), framed as the sensor puts them on the wire so that Wireshark and VeloView
// open them: Ethernet (src 60:76:88:00:00:01 = Velodyne OUI, dst broadcast) + IPv4 (192.168.1.201 ->
// 255.255.255.255, valid header checksum, TTL 64, DF) + UDP (src port = dst port = 2368 data / 8308 position,
// checksum 0 = none, legal for IPv4). Also the headerless raw format (concatenated 1206-byte payloads).
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/types/messages.hpp"
#include "core/util/status.hpp"

namespace rotolidar {

/// Writes LidarPackets as pcap records (microsecond precision). Record time = epoch_unix_s + t_capture_s, rounded
/// to the nearest microsecond. Not thread-safe; closes itself on destruction.
class PcapWriter {
 public:
  PcapWriter() = default;
  ~PcapWriter();
  PcapWriter(const PcapWriter&) = delete;
  PcapWriter& operator=(const PcapWriter&) = delete;

  /// Creates/truncates `path`. epoch_unix_s: the Unix time of rig time 0 [s] (0 keeps rig times as record times).
  Status Open(const std::string& path, double epoch_unix_s = 0.0);
  /// Fails when not open, when the payload exceeds 65507 bytes, or when the record time would be negative.
  Status Write(const LidarPacket& packet);
  /// Flushes and closes; reports a write error of the underlying file. Idempotent.
  Status Close();
  std::size_t written() const { return written_; }

 private:
  void* pcap_ = nullptr;    // pcap_t*
  void* dumper_ = nullptr;  // pcap_dumper_t*
  std::string path_;
  double epoch_unix_s_ = 0.0;
  uint16_t ip_id_ = 0;
  std::size_t written_ = 0;
};

/// What a PcapReader has seen so far, VLP-16 or not: the answer to "why did this capture give no points?".
struct PcapTraffic {
  std::size_t records = 0;        ///< records read
  std::size_t other_frames = 0;   ///< records that are not UDP over IPv4 (ARP, IPv6, TCP, later IP fragments)
  /// UDP datagrams by (destination port, payload size [bytes] from the UDP header), every port.
  std::map<std::pair<uint16_t, std::size_t>, std::size_t> udp;
  std::size_t vlp16_data = 0;     ///< of those: 1206-byte payloads to port 2368 (VLP-16 data packets)
  /// "1000 UDP packets: port 7502 x 900 (payload 12608 B), port 7503 x 100 (payload 48 B)" (most frequent first,
  /// at most 8 kinds, then how many more), "; 3 other frames (not UDP over IPv4)" when there are any; "no
  /// packets (the file holds a pcap header only)" when nothing was read.
  std::string Describe() const;
};

/// Streams LidarPackets out of a pcap/pcapng file (Ethernet, 802.1Q-tagged Ethernet or Linux cooked capture).
/// UDP/IPv4 frames to port 2368 or 8308 become packets (udp_port = the destination port, t_capture_s = record time -
/// epoch_unix_s); everything else (ARP, IPv6, TCP, other ports) is skipped and counted. Not thread-safe.
class PcapReader {
 public:
  PcapReader() = default;
  ~PcapReader();
  PcapReader(const PcapReader&) = delete;
  PcapReader& operator=(const PcapReader&) = delete;

  /// Fails (message names the file) when the file cannot be opened or its link type is not supported.
  Status Open(const std::string& path, double epoch_unix_s = 0.0);
  /// true: *packet holds the next VLP-16 packet. false with status->ok: end of file. false with !status->ok: the
  /// current record is malformed (truncated frame, bad IPv4/UDP header or length, fragmented datagram, payload size
  /// other than 1206 on 2368 or 512 on 8308); the message names the file, the record index (0-based) and the byte
  /// offset in the frame. The reader has moved past it: calling Next again continues with the next record.
  bool Next(LidarPacket* packet, Status* status);
  std::size_t records() const { return records_; }  ///< records read so far
  std::size_t skipped() const { return skipped_; }  ///< non-VLP-16 frames skipped
  const PcapTraffic& traffic() const { return traffic_; }  ///< every record read so far, by kind
  /// "<path>: no VLP-16 data packets (1206-byte payloads on UDP port 2368): saw <traffic().Describe()>": the
  /// error for a capture that held no VLP-16 data (read it to the end first).
  Status NoVlp16DataError() const;
  void Close();

 private:
  Status ParseFrame(const uint8_t* frame, std::size_t caplen, std::size_t len, LidarPacket* packet, bool* is_vlp);

  void* pcap_ = nullptr;  // pcap_t*
  std::string path_;
  double epoch_unix_s_ = 0.0;
  int link_type_ = 0;
  std::size_t records_ = 0;
  std::size_t skipped_ = 0;
  PcapTraffic traffic_;
};

/// Reads a file of concatenated raw 1206-byte data payloads (no headers; the vlp16_einride format). Packets get
/// udp_port 2368 and t_capture_s 0. Fails when the file cannot be read or its size is not a multiple of 1206
/// (message names the byte offset of the trailing partial packet); *packets is replaced only on success.
Status ReadRawVlp16Payloads(const std::string& path, std::vector<LidarPacket>* packets);

/// RFC 1071 ones'-complement checksum of an IPv4 header (`bytes` = header length); a valid header including its
/// checksum field sums to 0.
uint16_t Ipv4HeaderChecksum(const uint8_t* header, std::size_t bytes);

}  // namespace rotolidar
