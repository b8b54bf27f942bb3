// `rotolidar replay`: plays a recording's VLP-16 packets onto UDP at N x real time, as the sensor would send them
// (data packets to --port, position packets to --position-port), so that a live consumer (`rotolidar live`, the
// ROS driver, VeloView) can be tested against a recording; from a recording folder also its IMU and encoder
// samples (--rig-port), as the rig's microcontroller would. Progress on stderr once per wall second.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <vector>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/live/udp_replay.hpp"
#include "core/io/recording.hpp"
#include "core/wire/pcap.hpp"
#include "core/wire/udp_sender.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench {
namespace {

/// Packets in file order from a pcap (streamed) or a raw payload file (loaded; the raw format has no capture
/// times, so each packet gets the rig time of its own VLP-16 timestamp, unwrapped across hours).
class ReplaySource {
 public:
  Status Open(const std::string& input, bool raw) {
    raw_ = raw;
    if (!raw) return reader_.Open(input);
    if (Status s = ReadRawVlp16Payloads(input, &packets_); !s) return s;
    Vlp16Decoder clock(LidarIntrinsics{}, Vlp16DecoderConfig{});
    for (std::size_t i = 0; i < packets_.size(); ++i) {
      Vlp16RawPacket fields;
      const Status s = ParseVlp16DataPacket(packets_[i].payload.data(), packets_[i].payload.size(), &fields);
      if (!s) return Status::Error(input + ": packet " + std::to_string(i) + ": " + s.message);
      packets_[i].t_capture_s = clock.UnwrapToRigTime(fields.timestamp_us);
    }
    return Status::Ok();
  }
  /// PcapReader::Next's contract.
  bool Next(LidarPacket* packet, Status* status) {
    if (!raw_) return reader_.Next(packet, status);
    *status = Status::Ok();
    if (next_ >= packets_.size()) return false;
    *packet = packets_[next_++];
    return true;
  }
  /// Packets in a raw file; unknown (0) for a pcap, which is streamed.
  std::size_t known_total() const { return packets_.size(); }

 private:
  bool raw_ = false;
  PcapReader reader_;
  std::vector<LidarPacket> packets_;
  std::size_t next_ = 0;
};

struct ReplayStats {
  std::size_t sent = 0, data = 0, position = 0, malformed = 0;
  double first_t_s = 0.0, last_t_s = 0.0;
};

void PrintProgress(const ReplayStats& st, const PacketPacer& pacer, std::size_t total, bool final) {
  char line[200];
  const double span_s = st.last_t_s - st.first_t_s, wall_s = pacer.ElapsedS();
  std::snprintf(line, sizeof(line), "replay: %zu%s%s packets (%zu data, %zu position), %.2f s of recording in "
                "%.2f s wall = %.1f x real time, max lateness %.1f ms%s",
                st.sent, total ? " / " : "", total ? std::to_string(total).c_str() : "", st.data, st.position,
                span_s, wall_s, wall_s > 0.0 ? span_s / wall_s : 0.0, 1e3 * pacer.max_lateness_s(),
                final ? "\n" : "\r");
  std::cerr << line << std::flush;
}

/// A recording folder: packets and (with --rig-port) rig samples, merged in time order (bench/live/udp_replay.hpp).
int ReplayFolder(const OptionParser& p, const std::string& dir, const UdpSenderConfig& lidar, double rate) {
  UdpReplayConfig config;
  config.host = lidar.host;
  config.data_port = lidar.data_port;
  config.position_port = lidar.position_port;
  config.rate = rate;
  long rig_port = 0, seed = 1;
  for (const Status& s : {p.GetInt("rig-port", &rig_port), p.GetInt("seed", &seed),
                          p.GetDouble("drop", &config.drop_fraction)})
    if (!s) return Usage(s.message);
  if (rig_port < 0 || rig_port > 65535) return Usage("replay: --rig-port must be 0..65535");
  config.rig_port = static_cast<uint16_t>(rig_port);
  config.seed = static_cast<uint64_t>(seed);
  std::string why;
  if (!config.Validate(&why)) return Usage("replay: " + why);
  Recording rec;
  if (Status s = LoadRecording(dir, &rec); !s) return std::cerr << "error: " << s.message << "\n", 1;
  auto print = [](const UdpReplayStats& st, bool final) {
    std::fprintf(stderr, "replay: %zu data + %zu position packets (%zu dropped), %zu rig samples in %zu datagrams; "
                 "%.2f s of recording in %.2f s wall%s", st.data_sent, st.position_sent, st.data_dropped,
                 st.samples_sent, st.rig_datagrams, st.span_s, st.wall_s, final ? "\n" : "\r");
  };
  UdpReplayStats stats;
  const Status s = ReplayOverUdp(rec, config, &stats, nullptr, [&](const UdpReplayStats& st) { print(st, false); });
  print(stats, true);
  if (!s) return std::cerr << "error: " << s.message << "\n", 1;
  std::fprintf(stderr, "replay: %.1f x real time, max lateness %.1f ms\n",
               stats.wall_s > 0 ? stats.span_s / stats.wall_s : 0.0, 1e3 * stats.max_lateness_s);
  return 0;
}

}  // namespace

int CmdReplay(int argc, char** argv) {
  OptionParser p("replay", "Send a recording's VLP-16 packets over UDP at N x real time (paced by their capture "
                           "times): data packets to --port, position packets to --position-port.");
  p.AddPositional("INPUT", "a recording folder (its lidar.pcap), a .pcap file, or raw payloads with --raw");
  p.Add("host", "127.0.0.1", "-", "destination IPv4 address (loopback by default)");
  p.Add("port", "2368", "-", "destination port of data packets");
  p.Add("position-port", "8308", "-", "destination port of position packets");
  p.Add("rate", "1", "x", "speed relative to real time; 0 = as fast as possible");
  p.AddFlag("raw", "INPUT is concatenated 1206-byte payloads (paced by their VLP-16 timestamps)");
  p.Add("rig-port", "0", "-", "a recording folder only: also send its IMU and encoder samples to this port in the "
                            "rig-sample protocol (docs/live.md; `rotolidar live` listens on 2370); 0 = do not");
  p.Add("drop", "0", "-", "a recording folder only: share of data packets not sent (simulated loss), [0, 1)");
  p.Add("seed", "1", "-", "run seed of the random stream that picks the dropped packets");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  UdpSenderConfig config;
  config.host = p.Get("host");
  long port = 0, position_port = 0;
  double rate = 1.0;
  for (const Status& s : {p.GetInt("port", &port), p.GetInt("position-port", &position_port),
                          p.GetDouble("rate", &rate)}) {
    if (!s) return Usage(s.message);
  }
  if (port < 1 || port > 65535) return Usage("replay: --port must be 1..65535");
  if (position_port < 1 || position_port > 65535) return Usage("replay: --position-port must be 1..65535");
  if (!(rate >= 0.0)) return Usage("replay: --rate must be >= 0");
  config.data_port = static_cast<uint16_t>(port);
  config.position_port = static_cast<uint16_t>(position_port);
  std::string input = p.Get("INPUT");
  if (std::filesystem::is_directory(input)) return ReplayFolder(p, input, config, rate);
  if (p.IsSet("rig-port") || p.IsSet("drop")) return Usage("replay: --rig-port and --drop need a recording folder");

  ReplaySource source;
  if (Status s = source.Open(input, p.Flag("raw")); !s) return std::cerr << "error: " << s.message << "\n", 1;
  UdpPacketSender sender;
  if (Status s = sender.Open(config); !s) return Usage(s.message);
  PacketPacer pacer(rate);
  ReplayStats st;
  LidarPacket packet;
  Status status;
  double next_report_s = 1.0;
  for (;;) {
    if (!source.Next(&packet, &status)) {
      if (status) break;
      ++st.malformed;  // the reader reports and moves past a malformed record
      std::cerr << "\nwarning: " << status.message << " (skipped)\n";
      continue;
    }
    if (st.sent == 0) st.first_t_s = st.last_t_s = packet.t_capture_s;
    st.last_t_s = std::max(st.last_t_s, packet.t_capture_s);
    pacer.WaitUntilDue(packet.t_capture_s);
    if (Status s = sender.Send(packet); !s) return std::cerr << "\nerror: " << s.message << "\n", 1;
    ++st.sent;
    ++(packet.udp_port == kVlp16PositionPort ? st.position : st.data);
    if (pacer.ElapsedS() >= next_report_s) {
      PrintProgress(st, pacer, source.known_total(), false);
      next_report_s += 1.0;
    }
  }
  PrintProgress(st, pacer, source.known_total(), true);
  if (st.sent == 0) return std::cerr << "error: " << input << ": no VLP-16 packets\n", 1;
  return 0;
}

}  // namespace rotolidar::bench
