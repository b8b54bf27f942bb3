// `rotolidar bench lidar|decode`: VLP-16 casting and decoding speed (contract in lidar_perf.hpp).
#include "bench/perf/lidar_perf.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>

#include "core/wire/pcap.hpp"
#include "core/wire/scan_splitter.hpp"
#include "sim/lidar/position_source.hpp"
#include "core/io/yaml_fields.hpp"
#include "sim/lidar/lidar_realism.hpp"
#include "sim/lidar/vlp16_caster.hpp"
#include "sim/rig/carrier_paths.hpp"
#include "sim/rig/motor.hpp"
#include "sim/sim_config.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"
#include "core/util/log.hpp"

namespace rotolidar::bench {
namespace {

constexpr double kSequencesPerSecond = 1.0 / kVlp16SequencePeriodS;  // 18,084.3

double CpuNowS() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double WallNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Accumulates the wall and CPU time between Start and Stop.
class Stopwatch {
 public:
  void Start() { wall0_ = WallNowS(), cpu0_ = CpuNowS(); }
  void Stop() { total_.wall_s += WallNowS() - wall0_, total_.cpu_s += CpuNowS() - cpu0_; }
  const Timing& total() const { return total_; }

 private:
  double wall0_ = 0.0, cpu0_ = 0.0;
  Timing total_;
};

/// The default rig moved kinematically (the carrier's target path, a constant-speed rotor: no physics, which
/// the casting speed does not depend on) and its true calibration.
struct KinematicRig {
  RigCalib calib;
  std::unique_ptr<sim::BaseMotion> carrier;
  std::unique_ptr<sim::ProfileRotor> rotor;
  Pose3 T_world_lidar(Seconds t) const { return carrier->At(t).T_world_base * calib.T_base_lidar(rotor->AngleAt(t)); }
};

Status MakeKinematicRig(const sim::SimConfig& config, KinematicRig* rig) {
  rig->calib = config.TrueCalib();
  if (Status s = sim::MakeCarrierMotion(config.carrier, &rig->carrier); !s) return s;
  rig->rotor = std::make_unique<sim::ProfileRotor>(
      sim::ConstantProfile(config.motor.profile.speed_radps, config.motor.profile.theta0_rad));
  return Status::Ok();
}

Status BuildEmbree(const std::string& scene_name, std::unique_ptr<sim::EmbreeScene>* out) {
  sim::Scene scene;
  if (Status s = sim::LoadScene(sim::ResolveScenePath(scene_name), &scene); !s) return s;
  return sim::EmbreeScene::Create(sim::BuildMesh(scene), out);
}

const char* ModeName(Vlp16ReturnMode mode) {
  return mode == Vlp16ReturnMode::kDual ? "dual" : mode == Vlp16ReturnMode::kLast ? "last" : "strongest";
}

/// Simulated packets of the default rig (data and position, in capture-time order), for the decode bench.
Status SimulatePackets(double seconds, Vlp16ReturnMode mode, std::vector<LidarPacket>* packets) {
  sim::SimConfig config = sim::DefaultSimConfig();
  std::unique_ptr<sim::EmbreeScene> embree;
  if (Status s = BuildEmbree(config.scene, &embree); !s) return s;
  KinematicRig rig;
  if (Status s = MakeKinematicRig(config, &rig); !s) return s;
  const auto pose = [&](Seconds t) { return rig.T_world_lidar(t); };
  config.lidar.return_mode = mode;
  sim::Vlp16Caster caster(*embree, rig.calib.lidar, config.lidar, config.seed);
  Vlp16PacketEncoder encoder(mode, rig.calib.lidar_clock_offset_s);
  sim::Vlp16PositionConfig position_config;
  position_config.lidar_clock_offset_s = rig.calib.lidar_clock_offset_s;
  std::string why;
  if (!position_config.Validate(&why)) position_config.pps_status = 0;  // the rig's clock is not UTC-locked
  sim::Vlp16PositionSource positions(position_config);
  std::vector<Vlp16FiringSequence> seqs;
  const long total = static_cast<long>(seconds * kSequencesPerSecond);
  for (long done = 0; done < total; done += encoder.SequencesPerPacket()) {
    seqs.clear();
    caster.Fire(encoder.SequencesPerPacket(), pose, &seqs, nullptr);
    for (const Vlp16FiringSequence& seq : seqs) {
      if (auto packet = encoder.Add(seq)) {
        positions.EmitUntil(packet->t_capture_s, packets);
        packets->push_back(std::move(*packet));
      }
    }
  }
  std::stable_sort(packets->begin(), packets->end(),
                   [](const LidarPacket& a, const LidarPacket& b) { return a.t_capture_s < b.t_capture_s; });
  return Status::Ok();
}

Status LoadPackets(const DecodeBenchOptions& o, std::vector<LidarPacket>* packets) {
  if (o.input.empty()) return SimulatePackets(o.seconds, o.mode, packets);
  if (o.raw) return ReadRawVlp16Payloads(o.input, packets);
  PcapReader reader;
  if (Status s = reader.Open(o.input); !s) return s;
  LidarPacket packet;
  Status status;
  while (reader.Next(&packet, &status)) packets->push_back(packet);
  return status;
}

}  // namespace

Timing MedianTiming(std::vector<Timing> runs) {
  ROTOLIDAR_CHECK(!runs.empty(), "no timings");
  auto median = [&](double Timing::*field) {
    std::sort(runs.begin(), runs.end(), [&](const Timing& a, const Timing& b) { return a.*field < b.*field; });
    const std::size_t n = runs.size();
    return n % 2 ? runs[n / 2].*field : 0.5 * (runs[n / 2 - 1].*field + runs[n / 2].*field);
  };
  Timing m;
  m.wall_s = median(&Timing::wall_s);
  m.cpu_s = median(&Timing::cpu_s);
  return m;
}

bool LidarBenchOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) { return (error ? *error = "bench lidar: " + m : m), false; };
  if (!(seconds > 0.0 && seconds <= 600.0)) return fail("--seconds must be in (0, 600]");
  if (repetitions < 1 || repetitions > 1000) return fail("--reps must be in 1..1000");
  if (!(rpm >= 300.0 && rpm <= 1200.0)) return fail("--rpm must be in [300, 1200]");
  if (beam_rings < 0 || beam_rings > 4) return fail("--beam-rings must be in 0..4");
  return true;
}

Status RunLidarBench(const LidarBenchOptions& o, LidarBenchResult* result) {
  std::string error;
  if (!o.Validate(&error)) return Status::Error(error);
  sim::SimConfig config = sim::DefaultSimConfig();
  std::unique_ptr<sim::EmbreeScene> embree;
  if (Status s = BuildEmbree(o.scene, &embree); !s) return s;
  KinematicRig rig;
  if (Status s = MakeKinematicRig(config, &rig); !s) return s;
  const auto pose = [&](Seconds t) { return rig.T_world_lidar(t); };
  config.lidar.rpm = o.rpm;
  config.lidar.return_mode = o.return_mode;
  config.lidar.beam_rings = o.beam_rings;
  config.lidar.pose_per_firing = o.pose_per_firing;
  if (!o.realism.empty()) {
    sim::Realism realism;
    if (!yaml::EnumFromWord(o.realism, &realism)) return Status::Error("--realism: ideal, typical or harsh");
    sim::ApplyLidarRealism(realism, &config.lidar);
  }
  *result = LidarBenchResult();
  std::vector<Timing> cast_runs, total_runs;
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<sim::LidarTruthPoint> truth;
  long returned = 0;
  for (int rep = 0; rep < o.repetitions; ++rep) {
    sim::Vlp16Caster caster(*embree, rig.calib.lidar, config.lidar, o.seed);
    Vlp16PacketEncoder encoder(o.return_mode, rig.calib.lidar_clock_offset_s);
    const int per_packet = encoder.SequencesPerPacket();
    const long packets = static_cast<long>(o.seconds * kSequencesPerSecond) / per_packet;
    Stopwatch cast, encode;
    returned = 0;
    for (long p = 0; p < packets; ++p) {
      seqs.clear();
      truth.clear();
      cast.Start();
      caster.Fire(per_packet, pose, &seqs, o.truth ? &truth : nullptr);
      cast.Stop();
      encode.Start();
      for (const Vlp16FiringSequence& seq : seqs) encoder.Add(seq);
      encode.Stop();
      for (const Vlp16FiringSequence& seq : seqs)
        for (uint16_t d : seq.distance_2mm) returned += d != 0;
    }
    cast_runs.push_back(cast.total());
    total_runs.push_back({cast.total().wall_s + encode.total().wall_s, cast.total().cpu_s + encode.total().cpu_s});
    result->firings = packets * per_packet * 16;
    result->rays = result->firings * caster.rays_per_firing();
    result->simulated_s = static_cast<double>(packets * per_packet) * kVlp16SequencePeriodS;
  }
  result->returned_fraction = result->firings > 0 ? static_cast<double>(returned) / result->firings : 0.0;
  result->cast = MedianTiming(cast_runs);
  result->cast_and_encode = MedianTiming(total_runs);
  return Status::Ok();
}

void PrintLidarBench(const LidarBenchOptions& o, const LidarBenchResult& r, std::ostream& os) {
  char line[256];
  os << "VLP-16 ray casting: scene " << o.scene << ", " << o.rpm << " rpm, " << ModeName(o.return_mode)
     << " return, beam_rings " << o.beam_rings << (o.truth ? ", with truth" : "")
     << (o.pose_per_firing ? ", pose per firing" : "") << "; " << r.simulated_s << " s simulated x "
     << o.repetitions << " repetitions, 1 thread\n";
  std::snprintf(line, sizeof(line), "firings %ld (%.0f /s), rays %ld, returned %.1f %%\n", r.firings,
                r.firings / r.simulated_s, r.rays, 100.0 * r.returned_fraction);
  os << line;
  os << "stage              median wall [s]  x real time (wall)  median CPU [s]  x real time (CPU)\n";
  for (const auto& [name, t] : {std::pair<const char*, Timing>{"cast", r.cast}, {"cast + encode", r.cast_and_encode}}) {
    std::snprintf(line, sizeof(line), "%-18s %15.4f %19.1f %15.4f %18.1f\n", name, t.wall_s,
                  r.simulated_s / t.wall_s, t.cpu_s, r.simulated_s / t.cpu_s);
    os << line;
  }
}

bool DecodeBenchOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) { return (error ? *error = "bench decode: " + m : m), false; };
  if (input.empty() && !(seconds > 0.0 && seconds <= 600.0)) return fail("--seconds must be in (0, 600]");
  if (repetitions < 1 || repetitions > 1000) return fail("--reps must be in 1..1000");
  if (raw && input.empty()) return fail("--raw needs --input");
  return true;
}

Status RunDecodeBench(const DecodeBenchOptions& o, DecodeBenchResult* result) {
  std::string error;
  if (!o.Validate(&error)) return Status::Error(error);
  std::vector<LidarPacket> packets;
  if (Status s = LoadPackets(o, &packets); !s) return s;
  *result = DecodeBenchResult();
  for (const LidarPacket& p : packets) {
    const bool position = p.udp_port == kVlp16PositionPort || p.payload.size() == kVlp16PositionPacketBytes;
    if (position) {
      ++result->position_packets;
      continue;
    }
    ++result->data_packets;
    const bool dual = p.payload.size() == kVlp16PacketBytes &&
                      p.payload[1204] == static_cast<uint8_t>(Vlp16ReturnMode::kDual);
    result->stream_s += (dual ? 12 : 24) * kVlp16SequencePeriodS;
  }
  if (result->data_packets == 0) return Status::Error("bench decode: no VLP-16 data packets in the input");
  std::vector<Timing> runs;
  std::vector<LidarPoint> points;
  std::vector<LidarScan> finished;
  points.reserve(384);
  for (int rep = 0; rep < o.repetitions; ++rep) {
    Vlp16Decoder decoder(LidarIntrinsics{}, Vlp16DecoderConfig{});
    RevolutionSplitter splitter;
    long n = 0, scans = 0;
    Stopwatch watch;
    watch.Start();
    for (const LidarPacket& p : packets) {
      points.clear();
      if (Status s = decoder.Decode(p, &points); !s) return s;
      n += static_cast<long>(points.size());
      if (o.split) {
        finished.clear();
        splitter.Add(points, &finished);
        scans += static_cast<long>(finished.size());
      }
    }
    watch.Stop();
    runs.push_back(watch.total());
    result->points = n;
  }
  result->decode = MedianTiming(runs);
  return Status::Ok();
}

void PrintDecodeBench(const DecodeBenchOptions& o, const DecodeBenchResult& r, std::ostream& os) {
  char line[256];
  const std::string what =
      o.input.empty() ? "simulated default rig (" + std::string(ModeName(o.mode)) + ")" : o.input;
  os << "VLP-16 decoding: " << what
     << (o.split ? ", with revolution splitting" : "") << "; " << o.repetitions << " repetitions, 1 thread\n";
  std::snprintf(line, sizeof(line), "data packets %ld, position packets %ld, points %ld, stream %.3f s\n",
                r.data_packets, r.position_packets, r.points, r.stream_s);
  os << line;
  std::snprintf(line, sizeof(line),
                "median wall %.5f s = %.1f x real time (%.2f M points/s); median CPU %.5f s = %.1f x real time\n",
                r.decode.wall_s, r.stream_s / r.decode.wall_s, 1e-6 * r.points / r.decode.wall_s, r.decode.cpu_s,
                r.stream_s / r.decode.cpu_s);
  os << line;
}

}  // namespace rotolidar::bench
