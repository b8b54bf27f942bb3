// Recording checks before a run (contract in input_check.hpp).
#include "bench/run/input_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <yaml-cpp/yaml.h>

#include "core/wire/packet_gaps.hpp"
#include "core/wire/packet_orderer.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench {
namespace {

constexpr double kBlindS = 0.5;            // a stretch without returns this long is a blind sensor [s]
constexpr double kFrozenEncoderS = 0.25;   // a count unchanged this long while the rotor should turn [s]
constexpr std::size_t kSaturatedSamples = 3;  // samples exactly at an axis's extreme value

std::string Fmt(const char* format, double a, double b = 0.0) {
  char text[160];
  std::snprintf(text, sizeof(text), format, a, b);
  return text;
}

/// Count and longest of the steps in `times` above `limit_s`.
template <class Samples>
std::pair<std::size_t, double> Gaps(const Samples& samples, double limit_s) {
  std::size_t count = 0;
  double longest = 0.0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    const double dt = samples[i].t_s - samples[i - 1].t_s;
    if (dt > limit_s) ++count, longest = std::max(longest, dt);
  }
  return {count, longest};
}

void CheckImu(const Recording& rec, const InputCheckConfig& config, std::vector<InputWarning>* out) {
  const std::string file = rec.dir + "/imu.csv";
  if (rec.imu.empty()) {
    out->push_back({"imu.missing", file + ": no IMU samples: the run is LiDAR-only (deskew and fusion without "
                                          "the IMU; expect a much larger error on a moving rig)", 1});
    return;
  }
  const double limit = config.gap_factor / rec.calib.imu.rate_hz;
  const auto [count, longest] = Gaps(rec.imu, limit);
  if (count > 0)
    out->push_back({"imu.gaps", file + ": " + std::to_string(count) + " gap(s) over " + Fmt("%.3f s", limit) +
                                    " (the longest " + Fmt("%.3f s", longest) + ")", count});
}

void CheckEncoder(const Recording& rec, const InputCheckConfig& config, std::vector<InputWarning>* out) {
  const std::string file = rec.dir + "/encoder.csv";
  const auto [count, longest] = Gaps(rec.encoder, config.max_encoder_gap_s);
  if (count > 0)
    out->push_back({"encoder.gaps", file + ": " + std::to_string(count) + " gap(s) over " +
                                        Fmt("%.3f s", config.max_encoder_gap_s) + " (the longest " +
                                        Fmt("%.3f s", longest) + "): the rotor angle across them is a guess",
                    count});
  if (rec.encoder.size() < 2 || rec.calib.motor_speed_radps <= 0.0) return;
  const double turns = rec.calib.motor_speed_radps * (rec.encoder.back().t_s - rec.encoder.front().t_s) / (2 * M_PI);
  uint32_t max_count = 0;
  for (const EncoderSample& e : rec.encoder) max_count = std::max(max_count, e.count);
  const uint32_t cpr = rec.calib.encoder.counts_per_rev;
  if (turns >= 3.0 && max_count < cpr / 4)
    out->push_back({"encoder.resolution", file + ": counts never exceed " + std::to_string(max_count) + " over " +
                                              Fmt("%.0f", turns) + " turns, but calib.yaml says encoder." +
                                              "counts_per_rev " + std::to_string(cpr) +
                                              ": the angles will be wrong (a " +
                                              std::to_string(max_count + 1 > 4096 ? 14 : 12) + "-bit encoder?)",
                    1});
}

void CheckCalibKeys(const Recording& rec, std::vector<InputWarning>* out) {
  const std::string file = rec.dir + "/calib.yaml";
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::Exception&) {
    return;  // LoadRecording already read it; nothing to add
  }
  for (const char* key : {"T_base_motor", "T_rotor_lidar", "T_base_imu"})
    if (!root[key])
      out->push_back({"calib.pose_missing", file + ": " + key + " is not given: identity assumed (measure it: a "
                                                                "wrong lever arm or axis blurs the map)", 1});
}

bool NoReturns(const LidarPacket& p) {
  for (int b = 0; b < 12; ++b)
    for (int ch = 0; ch < 32; ++ch) {
      const uint8_t* d = p.payload.data() + 100 * b + 4 + 3 * ch;
      if (d[0] != 0 || d[1] != 0) return false;
    }
  return true;
}

// Gaps are counted in timestamp order (after the core's own reordering), so reordered packets are not "lost".
class LidarStreamCheck {
 public:
  void Push(const LidarPacket& packet) {
    orderer_.Push(packet, &ordered_);
    Drain();
  }
  void Finish(const std::string& dir, std::vector<InputWarning>* out) {
    orderer_.Flush(&ordered_);
    Drain();
    if (in_blind_) EndBlind();
    if (gaps_.lost() > 0)
      out->push_back({"lidar.lost_packets", dir + "/lidar.pcap: " + std::to_string(gaps_.lost()) +
                                                " data packet(s) missing from the timestamp sequence", gaps_.lost()});
    if (blind_runs_ > 0)
      out->push_back({"lidar.blind", dir + "/lidar.pcap: " + std::to_string(blind_runs_) + " stretch(es) of " +
                                         Fmt("%.1f s", kBlindS) + " or more without a single return (the longest " +
                                         Fmt("%.2f s", longest_blind_) + "): a covered or failed sensor",
                      blind_runs_});
  }

 private:
  void Drain() {
    for (const LidarPacket& p : ordered_) Add(p);
    ordered_.clear();
  }
  void Add(const LidarPacket& p) {
    uint32_t stamp = 0;
    uint8_t mode = 0;
    if (p.udp_port == kVlp16PositionPort || !Vlp16DataTimestamp(p.payload.data(), p.payload.size(), &stamp, &mode))
      return;
    gaps_.Add(stamp, mode);
    const bool blind = NoReturns(p);
    if (blind && !in_blind_) blind_start_ = p.t_capture_s;
    if (!blind && in_blind_) EndBlind();
    in_blind_ = blind;
    last_t_ = p.t_capture_s;
  }
  void EndBlind() {
    if (last_t_ - blind_start_ < kBlindS) return;
    ++blind_runs_;
    longest_blind_ = std::max(longest_blind_, last_t_ - blind_start_);
  }

  PacketOrderer orderer_;
  std::vector<LidarPacket> ordered_;
  Vlp16GapCounter gaps_;
  std::size_t blind_runs_ = 0;
  double blind_start_ = 0.0, longest_blind_ = 0.0, last_t_ = 0.0;
  bool in_blind_ = false;
};

Status CheckLidar(const Recording& rec, std::vector<InputWarning>* out) {
  LidarPacketSource source;
  if (Status s = source.Open(rec); !s) return s;
  LidarStreamCheck check;
  while (const LidarPacket* p = source.Next()) check.Push(*p);
  if (!source.status()) return source.status();
  check.Finish(rec.dir, out);
  return Status::Ok();
}

// Runs of one unchanged count while the rotor should turn: a frozen encoder (or a stalled motor).
void CheckFrozenEncoder(const Recording& rec, std::vector<InputWarning>* out) {
  if (rec.calib.motor_speed_radps <= 0.0 || rec.encoder.size() < 2) return;
  std::size_t runs = 0;
  double longest = 0.0;
  std::size_t start = 0;
  for (std::size_t i = 1; i <= rec.encoder.size(); ++i) {
    if (i < rec.encoder.size() && rec.encoder[i].count == rec.encoder[start].count) continue;
    const double span = rec.encoder[i - 1].t_s - rec.encoder[start].t_s;
    if (span >= kFrozenEncoderS) ++runs, longest = std::max(longest, span);
    start = i;
  }
  if (runs > 0)
    out->push_back({"encoder.frozen", rec.dir + "/encoder.csv: the count stood still " + std::to_string(runs) +
                                          " time(s) for " + Fmt("%.2f s", kFrozenEncoderS) + " or more (the longest " +
                                          Fmt("%.2f s", longest) + ") while calib.yaml says the rotor turns at " +
                                          Fmt("%.2f rad/s", rec.calib.motor_speed_radps) +
                                          ": a frozen encoder or a stalled motor", runs});
}

// A clipped IMU repeats its extreme value: the largest |value| of an axis met exactly by several samples, but not
// by most of them.
void CheckImuSaturation(const Recording& rec, std::vector<InputWarning>* out) {
  static const char* kAxes[6] = {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"};
  for (int axis = 0; axis < 6; ++axis) {
    double peak = 0.0;
    std::size_t at_peak = 0;
    for (const ImuSample& s : rec.imu) {
      const double v = std::abs(axis < 3 ? s.gyro_radps[axis] : s.accel_mps2[axis - 3]);
      if (v > peak) peak = v, at_peak = 1;
      else if (v == peak && v > 0.0) ++at_peak;
    }
    // Half the samples or more at one value is a constant signal (a noise-free IMU at rest), not a clip.
    if (at_peak >= kSaturatedSamples && 2 * at_peak < rec.imu.size())
      out->push_back({"imu.saturated", rec.dir + "/imu.csv: " + kAxes[axis] + " sits at its extreme " +
                                           Fmt("%.4g", peak) + " on " + std::to_string(at_peak) +
                                           " samples: a clipped (saturated) sensor", at_peak});
  }
}

}  // namespace

Status CheckRecording(const Recording& recording, const InputCheckConfig& config, std::vector<InputWarning>* out) {
  CheckImu(recording, config, out);
  CheckEncoder(recording, config, out);
  CheckCalibKeys(recording, out);
  if (Status s = CheckLidar(recording, out); !s) return s;
  CheckFrozenEncoder(recording, out);
  CheckImuSaturation(recording, out);
  return Status::Ok();
}

std::vector<InputWarning> CheckRecording(const Recording& recording, const InputCheckConfig& config) {
  std::vector<InputWarning> out;
  // Packets in memory were read whole by LoadRecording; only a streamed lidar.pcap can fail here.
  if (Status s = CheckRecording(recording, config, &out); !s)
    out.push_back({"lidar.unreadable", s.message, 1});
  return out;
}

std::string InputWarningsText(const std::vector<InputWarning>& warnings) {
  std::string text;
  for (const InputWarning& w : warnings) text += "warning [" + w.code + "]: " + w.message + "\n";
  return text;
}

}  // namespace rotolidar::bench
