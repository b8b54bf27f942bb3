#include "sim/sim_runner.hpp"

#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>

#include <yaml-cpp/yaml.h>

#include "core/io/recording.hpp"
#include "sim/truth/truth.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {
namespace {

/// Everything one run owns, built from the config.
struct SimWorld {
  Scene scene;
  std::unique_ptr<EmbreeScene> embree;
  size_t triangles = 0;
};

Status BuildWorld(const SimConfig& config, SimWorld* world) {
  const std::string path = ResolveScenePath(config.scene);
  if (Status s = LoadScene(path, &world->scene); !s) return s;
  const TriangleMesh mesh = BuildMesh(world->scene);
  world->triangles = mesh.triangles.size();
  return EmbreeScene::Create(mesh, &world->embree);
}

Status WriteResolvedConfig(const SimConfig& config, const std::string& dir) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  EmitSimConfig(out, config);
  const std::string path = dir + "/sim_config.yaml";
  std::ofstream file(path);
  file << "# Resolved configuration of this simulation run (rotolidar sim).\n" << out.c_str() << "\n";
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

/// The LiDAR stream: fires the head packet by packet along the true lidar pose and writes VLP-16 packets.
Status SimulateLidar(const SimConfig& config, const SimWorld& world, const BaseMotion& motion,
                     const RotorMotion& rotor, RecordingWriter* writer, SimSummary* summary,
                     const ProgressFn& progress) {
  Vlp16Caster caster(*world.embree, config.rig.lidar, config.lidar, config.seed);
  Vlp16PacketEncoder encoder(config.return_mode, config.rig.lidar_clock_offset_s);
  const auto T_world_lidar_at = [&](Seconds t) {
    return motion.At(t).T_world_base * config.rig.T_base_lidar(rotor.AngleAt(t));
  };
  std::vector<Vlp16FiringSequence> sequences;
  const int per_packet = encoder.SequencesPerPacket();
  double next_progress_s = 1.0;
  while (caster.FiringTime(caster.sequences_fired() + per_packet, 0) <= config.duration_s) {
    sequences.clear();
    caster.Fire(per_packet, T_world_lidar_at, &sequences, nullptr);
    for (const Vlp16FiringSequence& seq : sequences) {
      for (uint16_t d : seq.distance_2mm) summary->lidar_returns += d != 0;
      summary->lidar_rays += 16;
      if (auto packet = encoder.Add(seq)) {
        if (Status s = writer->Write(*packet); !s) return s;
        ++summary->lidar_packets;
      }
    }
    if (progress && sequences.back().t_s >= next_progress_s) {
      progress(sequences.back().t_s / config.duration_s);
      next_progress_s += 1.0;
    }
  }
  return Status::Ok();
}

/// IMU, encoder and truth streams on their own clocks (each sensor samples at its own rate).
Status SimulateRig(const SimConfig& config, const BaseMotion& motion, const RotorMotion& rotor,
                   RecordingWriter* writer, TruthWriter* truth, SimSummary* summary) {
  ImuModel imu(config.rig.imu, config.rig.T_base_imu, config.seed, config.imu_bias);
  const long n_imu = long(std::floor(config.duration_s * config.rig.imu.rate_hz));
  for (long i = 0; i <= n_imu; ++i) {
    const Seconds t = double(i) / config.rig.imu.rate_hz;
    if (Status s = writer->Write(imu.Sample(motion.At(t), t)); !s) return s;
    if (Status s = truth->WriteImuBias({t, imu.Bias().gyro_radps, imu.Bias().accel_mps2}); !s) return s;
    ++summary->imu_samples;
  }
  EncoderModel encoder(config.encoder, config.seed);
  for (const EncoderSample& e : encoder.SampleRange(rotor, 0.0, config.duration_s)) {
    if (Status s = writer->Write(e); !s) return s;
    ++summary->encoder_samples;
  }
  const long n_truth = long(std::floor(config.duration_s * config.truth_rate_hz));
  for (long i = 0; i <= n_truth; ++i) {
    const Seconds t = double(i) / config.truth_rate_hz;
    const Pose3 T_world_base = motion.At(t).T_world_base;
    const double theta = rotor.AngleAt(t);
    if (Status s = truth->WriteBase({t, T_world_base}); !s) return s;
    if (Status s = truth->WriteLidar({t, T_world_base * config.rig.T_base_lidar(theta)}); !s) return s;
    if (Status s = truth->WriteRotor({t, theta}); !s) return s;
  }
  return Status::Ok();
}

}  // namespace

Status RunSimulation(const SimConfig& config, const std::string& recording_dir, SimSummary* summary,
                     const ProgressFn& progress) {
  const auto wall0 = std::chrono::steady_clock::now();
  std::string why;
  if (!config.Validate(&why)) return Status::Error("sim config: " + why);
  SimWorld world;
  if (Status s = BuildWorld(config, &world); !s) return s;
  *summary = SimSummary{};
  summary->scene_triangles = world.triangles;
  summary->recording_dir = recording_dir;

  RigCalib calib = config.rig;  // what the rig's owner would have calibrated: here, the truth
  calib.encoder = config.encoder.ToCalib();
  calib.motor_speed_radps = config.motor.speed_radps;
  RecordingWriter writer;
  if (Status s = writer.Open(recording_dir, calib); !s) return s;
  TruthWriter truth;
  if (Status s = truth.Open(recording_dir); !s) return s;
  if (Status s = WriteResolvedConfig(config, recording_dir); !s) return s;

  const ScriptedBaseMotion motion(config.motion);
  const ConstantSpeedRotor rotor(config.motor);
  if (Status s = SimulateRig(config, motion, rotor, &writer, &truth, summary); !s) return s;
  if (Status s = SimulateLidar(config, world, motion, rotor, &writer, summary, progress); !s) return s;
  if (Status s = writer.Close(); !s) return s;
  if (Status s = truth.Close(); !s) return s;
  summary->sim_duration_s = config.duration_s;
  summary->wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  if (progress) progress(1.0);
  return Status::Ok();
}

}  // namespace rotolidar::sim
