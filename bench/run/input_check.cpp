// Recording checks before a run (contract in input_check.hpp).
#include "bench/run/input_check.hpp"

#include <algorithm>
#include <cstdio>

#include <yaml-cpp/yaml.h>

#include "core/wire/packet_gaps.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench {
namespace {

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

void CheckLidar(const Recording& rec, std::vector<InputWarning>* out) {
  Vlp16GapCounter gaps;
  for (const LidarPacket& p : rec.lidar_packets) {
    if (p.udp_port == kVlp16PositionPort || p.payload.size() != kVlp16PacketBytes) continue;
    const uint8_t* b = p.payload.data() + 1200;
    gaps.Add(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24, p.payload[1204]);
  }
  if (gaps.lost() > 0)
    out->push_back({"lidar.lost_packets", rec.dir + "/lidar.pcap: " + std::to_string(gaps.lost()) +
                                              " data packet(s) missing from the timestamp sequence", gaps.lost()});
}

}  // namespace

std::vector<InputWarning> CheckRecording(const Recording& recording, const InputCheckConfig& config) {
  std::vector<InputWarning> out;
  CheckImu(recording, config, &out);
  CheckEncoder(recording, config, &out);
  CheckCalibKeys(recording, &out);
  CheckLidar(recording, &out);
  return out;
}

std::string InputWarningsText(const std::vector<InputWarning>& warnings) {
  std::string text;
  for (const InputWarning& w : warnings) text += "warning [" + w.code + "]: " + w.message + "\n";
  return text;
}

}  // namespace rotolidar::bench
