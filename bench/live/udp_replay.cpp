// Recording -> UDP (contract in udp_replay.hpp).
#include "bench/live/udp_replay.hpp"

#include <cmath>

#include "core/util/rng.hpp"
#include "core/wire/rig_udp.hpp"
#include "core/wire/udp_sender.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench {

bool UdpReplayConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (data_port == 0 || position_port == 0) return fail("data_port, position_port: must be 1..65535");
  if (rig_batch < 1 || rig_batch > kRigMaxRecords) return fail("rig_batch: must be 1..20");
  if (!(rate >= 0.0) || !std::isfinite(rate)) return fail("rate: must be >= 0");
  if (!(drop_fraction >= 0.0 && drop_fraction < 1.0)) return fail("drop_fraction: must be in [0, 1)");
  return true;
}

namespace {

/// The next message of a recording in time order: samples up to a packet's capture time go before it.
struct Cursor {
  const Recording& rec;
  std::size_t packet = 0, imu = 0, encoder = 0;
  bool Done() const {
    return packet >= rec.lidar_packets.size() && imu >= rec.imu.size() && encoder >= rec.encoder.size();
  }
  /// 0 = packet, 1 = IMU, 2 = encoder; the earliest (ties: encoder, IMU, then the packet, as slam feeds them).
  int Next(Seconds* t_s) const {
    const double inf = 1e300;
    const double tp = packet < rec.lidar_packets.size() ? rec.lidar_packets[packet].t_capture_s : inf;
    const double ti = imu < rec.imu.size() ? rec.imu[imu].t_s : inf;
    const double te = encoder < rec.encoder.size() ? rec.encoder[encoder].t_s : inf;
    if (te <= ti && te <= tp) return *t_s = te, 2;
    if (ti <= tp) return *t_s = ti, 1;
    return *t_s = tp, 0;
  }
};

}  // namespace

Status ReplayOverUdp(const Recording& rec, const UdpReplayConfig& config, UdpReplayStats* stats,
                     const std::atomic<bool>* stop, const std::function<void(const UdpReplayStats&)>& progress) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error("replay: " + why);
  *stats = UdpReplayStats{};
  UdpSenderConfig lidar;
  lidar.host = config.host;
  lidar.data_port = config.data_port;
  lidar.position_port = config.position_port;
  UdpPacketSender sender;
  if (Status s = sender.Open(lidar); !s) return s;
  RigSampleSender rig;
  if (config.rig_port != 0)
    if (Status s = rig.Open(config.host, config.rig_port); !s) return s;
  RandomStream drop(config.seed, "replay.drop");
  PacketPacer pacer(config.rate);
  Cursor cursor{rec};
  Seconds t_first = 0.0, t = 0.0;
  double next_progress_s = 1.0;
  for (bool first = true; !cursor.Done() && !(stop && *stop); first = false) {
    const int kind = cursor.Next(&t);
    if (first) t_first = t;
    stats->span_s = t - t_first;
    pacer.WaitUntilDue(t);
    if (kind == 0) {
      const LidarPacket& packet = rec.lidar_packets[cursor.packet++];
      const bool data = packet.udp_port != kVlp16PositionPort;
      if (data && config.drop_fraction > 0.0 && drop.Uniform() < config.drop_fraction) {
        ++stats->data_dropped;
        continue;
      }
      if (Status s = sender.Send(packet); !s) return s;
      ++(data ? stats->data_sent : stats->position_sent);
    } else if (config.rig_port != 0) {
      RigSample sample;
      if (kind == 1) sample.imu = rec.imu[cursor.imu];
      else sample.type = RigSample::Type::kEncoder, sample.encoder = rec.encoder[cursor.encoder];
      if (Status s = rig.Add(sample, config.rig_batch); !s) return s;
      ++stats->samples_sent;
    }
    if (kind == 1) ++cursor.imu;
    if (kind == 2) ++cursor.encoder;
    if (progress && pacer.ElapsedS() >= next_progress_s) {
      stats->wall_s = pacer.ElapsedS();
      progress(*stats);
      next_progress_s += 1.0;
    }
  }
  if (config.rig_port != 0)
    if (Status s = rig.Flush(); !s) return s;
  stats->rig_datagrams = rig.datagrams_sent();
  stats->wall_s = pacer.ElapsedS();
  stats->max_lateness_s = pacer.max_lateness_s();
  return Status::Ok();
}

}  // namespace rotolidar::bench
