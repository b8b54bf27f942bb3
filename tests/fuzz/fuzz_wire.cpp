// Fuzz targets of core/wire: pcap files, VLP-16 data and position packets, raw payload streams, rig datagrams.
#include "tests/fuzz/fuzz_target.hpp"

#include "core/wire/packet_orderer.hpp"
#include "core/wire/pcap.hpp"
#include "core/wire/rig_protocol.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::fuzz {
namespace {

ROTOLIDAR_FUZZ_TARGET(pcap) {
  PcapReader reader;
  if (!reader.Open(WriteInput(data, size, "input.pcap"))) return 0;
  LidarPacket packet;
  Status status;
  for (int i = 0; i < 100000 && (reader.Next(&packet, &status) || !status); ++i) {
  }
  return 0;
}

// A data packet: parsed, decoded and put through the orderer, whatever its bytes.
ROTOLIDAR_FUZZ_TARGET(vlp16_data) {
  Vlp16RawPacket raw;
  (void)ParseVlp16DataPacket(data, size, &raw);
  Vlp16Decoder decoder(LidarIntrinsics{}, Vlp16DecoderConfig{});
  LidarPacket packet;
  packet.payload.assign(data, data + size);
  std::vector<LidarPoint> points;
  (void)decoder.Decode(packet, &points);
  PacketOrderer orderer;
  std::vector<LidarPacket> out;
  orderer.Push(packet, &out);
  orderer.Flush(&out);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(vlp16_position) {
  Vlp16PositionPacket position;
  (void)ParseVlp16PositionPacket(data, size, &position);
  Vlp16Decoder decoder(LidarIntrinsics{}, Vlp16DecoderConfig{});
  LidarPacket packet;
  packet.udp_port = kVlp16PositionPort;
  packet.payload.assign(data, data + size);
  std::vector<LidarPoint> points;
  (void)decoder.Decode(packet, &points);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(raw_payloads) {
  std::vector<LidarPacket> packets;
  if (!ReadRawVlp16Payloads(WriteInput(data, size, "input.bin"), &packets)) return 0;
  Vlp16Decoder decoder(LidarIntrinsics{}, Vlp16DecoderConfig{});
  std::vector<LidarPoint> points;
  for (const LidarPacket& p : packets) (void)decoder.Decode(p, &points);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(rig_datagram) {
  RigDatagram datagram;
  (void)DecodeRigDatagram(data, size, &datagram);
  return 0;
}

}  // namespace
}  // namespace rotolidar::fuzz
