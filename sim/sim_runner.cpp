#include "sim/sim_runner.hpp"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>

#include <yaml-cpp/yaml.h>

#include "core/io/recording.hpp"
#include "sim/camera/camera_stream.hpp"
#include "sim/faults/faults.hpp"
#include "sim/lidar/position_source.hpp"
#include "sim/rig/rig_errors.hpp"
#include "sim/rig/rig_physics.hpp"
#include "sim/rig/rig_trace.hpp"
#include "sim/scene_carrier.hpp"
#include "sim/truth/truth.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {
namespace {

/// Everything one run owns, built from the config: the world (scene + Embree), the rig model and its physics
/// state, the carrier's target path, the motor drive and the sensor models.
struct SimWorld {
  Scene scene;
  std::unique_ptr<EmbreeScene> embree;
  size_t triangles = 0;  ///< static plus dynamic-object triangles
  std::unique_ptr<RigModel> rig;
  std::unique_ptr<BaseMotion> carrier;
  CarrierConfig carrier_config;  ///< the config's carrier with the scene's default path filled in
  Vlp16CasterConfig lidar;       ///< the config's lidar plus the scene's transmissive materials
};

/// The scene's materials with a transmittance (glass, porous foliage) join lidar.material_transmittance unless
/// the config lists the material already (the config wins); scenes without any leave the config as it is.
void AddSceneTransmittance(const Scene& scene, Vlp16CasterConfig* lidar) {
  for (const Material& m : scene.materials) {
    if (!(m.transmittance > 0.0)) continue;
    const auto listed = [&](const std::pair<std::string, double>& e) { return e.first == m.name; };
    auto& list = lidar->material_transmittance;
    if (std::none_of(list.begin(), list.end(), listed)) list.emplace_back(m.name, m.transmittance);
  }
}

/// The run's carrier: the scene's default when the config asks for it, its path filled from the scene where the
/// config leaves it empty, checked against the scene's bounds and static geometry before anything runs.
Status ResolveCarrier(const SimConfig& config, const std::string& scene_path, SimWorld* world) {
  CarrierConfig& c = world->carrier_config;
  c = config.carrier;
  if (config.carrier_from_scene) ChooseSceneCarrier(world->scene, &c);
  if (Status s = FillScenePath(world->scene, &c); !s) return Status::Error(scene_path + ": " + s.message);
  std::string why;
  if (!c.Validate(&why)) return Status::Error(scene_path + ": carrier: " + why);
  if (Status s = MakeCarrierMotion(c, &world->carrier); !s) return s;
  Status s = CheckCarrierPath(c, *world->carrier, config.duration_s, world->scene, *world->embree);
  if (!s && config.carrier_from_scene && c.type == CarrierType::kScriptedLoop)
    return Status::Error(s.message + ". The scene offers no carrier paths (`paths:` in " + scene_path +
                         "), and the scripted loop does not fit it: give --carrier with waypoints in --config");
  return s;
}

Status BuildWorld(const SimConfig& config, SimWorld* world) {
  std::string path;
  if (Status s = FindSceneFile(config.scene, &path); !s) return s;
  if (Status s = LoadScene(path, &world->scene); !s) return s;
  if (Status s = EmbreeScene::Create(world->scene, &world->embree); !s) return s;
  world->triangles = world->embree->num_triangles();
  world->lidar = config.lidar;
  AddSceneTransmittance(world->scene, &world->lidar);
  if (Status s = CheckCasterMaterials(world->lidar, world->embree->materials()); !s) return s;
  if (Status s = RigModel::Create(config.rig_model, &world->rig); !s) return s;
  return ResolveCarrier(config, path, world);
}

Status WriteText(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text;
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

/// Writes the config as run: the carrier's path resolved from the scene where the config left it empty.
Status WriteResolvedConfig(const SimConfig& config, const SimWorld& world, const std::string& dir) {
  SimConfig resolved = config;
  resolved.carrier = world.carrier_config;
  resolved.lidar = world.lidar;
  const RigModel& rig = *world.rig;
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  EmitSimConfig(out, resolved);
  if (Status s = WriteText(dir + "/sim_config.yaml", std::string("# Resolved configuration of this simulation "
                                                                  "run (rotolidar sim).\n") + out.c_str() + "\n");
      !s)
    return s;
  return WriteText(dir + "/rig_model.xml", rig.mjcf());  // the exact MJCF the physics ran
}

/// True when a reported echo of the firing (either slot) is the central ray's first surface: its noise-free
/// range lies within half the echo separation of that surface's (echoes closer than the separation merge, so
/// such an echo formed on it; a strongest echo from a wall behind a walker's edge does not count).
bool ReportsFirstSurface(const LidarTruthPoint& p, double echo_separation_m) {
  const bool returned[2] = {p.returned, p.returned2};
  for (int s = 0; s < 2; ++s)
    if (returned[s] && std::abs(p.echo_range_m[s] - p.true_range_m) < 0.5 * echo_separation_m) return true;
  return false;
}

/// The LiDAR stream: fires the head packet by packet along the true lidar pose (interpolated from the physics
/// trace) and writes VLP-16 data packets plus position packets. Fires every packet whose last firing lies within
/// the trace; returns the time before which the trace is no longer needed. With dynamic objects in the scene it
/// also writes each return of a packet that came from one to truth/dynamic_hits.csv (every fired sequence goes
/// out in a packet: one Fire call fills exactly one).
class LidarStream {
 public:
  LidarStream(const SimConfig& config, const SimWorld& world, const RigCalib& calib, TruthWriter* truth)
      : config_(config),
        calib_(calib),
        kinematics_(calib, config.rig_errors.wobble),
        embree_(*world.embree),
        caster_(*world.embree, calib.lidar, world.lidar, config.seed),
        encoder_(config.return_mode, calib.lidar_clock_offset_s, config.clocks.Lidar().drift_ppm),
        positions_(PositionConfig(calib, config.clocks)),
        capture_(config.clocks.lidar_capture, config.seed),
        truth_(truth),
        echo_separation_m_(world.lidar.echo_separation_m) {}

  Status FireCovered(const RigTrace& trace, FaultyWriter* writer, SimSummary* summary) {
    const int per_packet = encoder_.SequencesPerPacket();
    const auto T_world_lidar_at = [&](Seconds t) {
      const RigTraceSample s = trace.At(t);
      return s.T_world_base * kinematics_.T_base_lidar(s.theta_rad);
    };
    while (true) {
      // The caster may ask for the pose up to the start of the sequence after the packet (it interpolates within one).
      const Seconds t_last = caster_.FiringTime(caster_.sequences_fired() + per_packet, 0);
      if (t_last > config_.duration_s || !trace.Covers(NextFiringTime(), t_last)) break;
      embree_.SetTime(NextFiringTime());  // dynamic objects at the packet's time (moving < 1 mm in 1.3 ms)
      sequences_.clear();
      truth_points_.clear();
      const bool dynamic = embree_.num_dynamic_objects() > 0;
      caster_.Fire(per_packet, T_world_lidar_at, &sequences_, dynamic ? &truth_points_ : nullptr);
      if (Status s = WriteDynamicHits(); !s) return s;
      for (const Vlp16FiringSequence& seq : sequences_) {
        for (uint16_t d : seq.distance_2mm) summary->lidar_returns += d != 0;
        summary->lidar_rays += 16;
        if (auto packet = encoder_.Add(seq)) {
          if (Status s = WritePositionsUntil(packet->t_capture_s, writer); !s) return s;
          packet->t_capture_s = capture_.Apply(packet->t_capture_s);
          if (Status s = writer->Write(*packet); !s) return s;
          ++summary->lidar_packets;
        }
      }
    }
    return Status::Ok();
  }
  Seconds NextFiringTime() const { return caster_.FiringTime(caster_.sequences_fired(), 0); }

 private:
  static Vlp16PositionConfig PositionConfig(const RigCalib& calib, const ClockConfig& clocks) {
    Vlp16PositionConfig c;
    c.epoch_unix_s = calib.epoch_unix_s;
    c.lidar_clock_offset_s = calib.lidar_clock_offset_s;
    c.clock_drift_ppm = clocks.Lidar().drift_ppm;
    // A PPS-synced head (clocks.lidar_pps_synced) reports PPS locked and a $GPRMC fix when its clock reads UTC
    // (lidar_clock_offset_s = -(epoch mod 1 h)), as a real head wired to a GPS receiver does; otherwise, and for
    // a free-running head, no PPS and no fix.
    c.pps_status = 2;
    c.gps_fix = true;
    std::string why;
    if (!clocks.lidar_pps_synced || !c.Validate(&why)) c.pps_status = 0, c.gps_fix = false;
    return c;
  }
  Status WriteDynamicHits() {
    for (const LidarTruthPoint& p : truth_points_) {
      if (!p.hit || p.object_id < 0 || !ReportsFirstSurface(p, echo_separation_m_)) continue;
      if (Status s = truth_->WriteDynamicHit({p.t_s, p.object_id, p.p_world}); !s) return s;
    }
    return Status::Ok();
  }
  Status WritePositionsUntil(Seconds t_s, FaultyWriter* writer) {
    position_packets_.clear();
    positions_.EmitUntil(t_s - Vlp16PositionConfig{}.transmit_latency_s, &position_packets_);
    for (LidarPacket& p : position_packets_) {
      p.t_capture_s = capture_.Apply(p.t_capture_s);  // in write order: capture times stay monotonic
      if (Status s = writer->Write(p); !s) return s;
    }
    return Status::Ok();
  }

  const SimConfig& config_;
  const RigCalib& calib_;
  TrueRotorKinematics kinematics_;  // the true rotor geometry, wobble included
  EmbreeScene& embree_;
  Vlp16Caster caster_;
  Vlp16PacketEncoder encoder_;
  Vlp16PositionSource positions_;
  CaptureJitter capture_;  // host receive delay of every packet written
  std::vector<Vlp16FiringSequence> sequences_;
  std::vector<LidarPacket> position_packets_;
  TruthWriter* truth_;
  double echo_separation_m_;
  std::vector<LidarTruthPoint> truth_points_;  ///< of the packet being fired (only with dynamic objects)
};

/// Truth on its own channel at truth_rate_hz, interpolated from the physics trace.
class TruthStream {
 public:
  TruthStream(const SimConfig& config, const RigCalib& calib, TruthWriter* writer)
      : config_(config), kinematics_(calib, config.rig_errors.wobble), writer_(writer) {}

  Status WriteCovered(const RigTrace& trace) {
    while (true) {
      const Seconds t = double(next_) / config_.truth_rate_hz;
      if (t > config_.duration_s || !trace.Covers(t, t)) return Status::Ok();
      const RigTraceSample s = trace.At(t);
      if (Status st = writer_->WriteBase({t, s.T_world_base}); !st) return st;
      const Pose3 T_world_lidar = s.T_world_base * kinematics_.T_base_lidar(s.theta_rad);
      if (Status st = writer_->WriteLidar({t, T_world_lidar}); !st) return st;
      if (Status st = writer_->WriteRotor({t, s.theta_rad}); !st) return st;
      ++next_;
    }
  }
  Seconds NextTime() const { return double(next_) / config_.truth_rate_hz; }

 private:
  const SimConfig& config_;
  TrueRotorKinematics kinematics_;  // the true rotor geometry, wobble included
  TruthWriter* writer_;
  long next_ = 0;
};

/// The camera stream when the config enables it (else *out stays null); its extrinsic is the rig's cam site.
Status MakeCameraStream(const SimConfig& config, SimWorld& world, const RigCalib& calib,
                        std::unique_ptr<CameraStream>* out) {
  if (!config.camera.enabled) return Status::Ok();
  std::unique_ptr<CameraSimulator> camera;
  if (Status s = CameraSimulator::Create(config.camera, config.seed, world.scene, world.embree.get(), &camera); !s)
    return s;
  *out = std::make_unique<CameraStream>(std::move(camera), calib.T_base_cam, config.clocks.Camera());
  return Status::Ok();
}

/// The physics loop: steps the rig at its timestep; samples the IMU every whole number of steps (plus the rotor's
/// vibration when rig_errors configures it); streams the encoder samples the drive produced; feeds the trace that
/// the LiDAR and truth streams read behind it. `calib` is the TRUE calibration (the rig as it is).
Status RunPhysics(const SimConfig& config, SimWorld& world, const RigCalib& calib, FaultyWriter* writer,
                  TruthWriter* truth_writer, SimSummary* summary, const ProgressFn& progress,
                  const std::atomic<bool>* stop) {
  RigState state(*world.rig);
  StepperDrive drive(config.motor, config.seed);
  ImuModel imu(config.imu.noise, calib.T_base_imu, config.seed, config.imu.errors);
  const MotorReference ref0 = drive.profile().Reference(0.0);
  state.Reset(world.carrier->At(0.0), ref0.theta_rad, ref0.omega_radps);
  RigTrace trace;
  trace.Append({0.0, state.T_world_base(), state.rotor_angle_rad()});
  LidarStream lidar(config, world, calib, truth_writer);
  TruthStream truth(config, calib, truth_writer);
  std::unique_ptr<CameraStream> camera;
  if (Status s = MakeCameraStream(config, world, calib, &camera); !s) return s;
  const Eigen::Matrix3d R_imu_motor = calib.T_base_imu.linear().transpose() * calib.T_base_motor.linear();
  const long steps_per_imu = std::lround(1.0 / (config.imu.noise.rate_hz * state.timestep_s()));
  const long n_steps = long(std::ceil(config.duration_s / state.timestep_s() - 1e-9)) + 1;
  std::vector<EncoderSample> encoder_samples;
  double next_progress_s = 1.0;
  for (long k = 0; k < n_steps; ++k) {
    const Seconds t = state.time_s();
    if (stop && *stop) {
      summary->stopped = true;
      summary->sim_duration_s = t;
      break;
    }
    const RotorJointState rotor_t = state.rotor_state();  // the rotor at t, for the IMU's vibration
    if (Status s = state.Step(world.carrier->At(t).T_world_base, &drive); !s) return s;
    trace.Append({state.time_s(), state.T_world_base(), state.rotor_angle_rad()});
    if (k % steps_per_imu == 0 && t <= config.duration_s) {  // imu() describes the start of this step: t
      ImuTruth true_imu = state.imu();
      if (config.rig_errors.VibrationEnabled())
        AddRotorVibration(config.rig_errors.vibration, R_imu_motor, rotor_t.theta_rad, rotor_t.omega_radps,
                          &true_imu.angular_rate_imu_radps, &true_imu.specific_force_imu_mps2);
      if (Status s = writer->Write(imu.SampleFromTruth(true_imu.angular_rate_imu_radps,
                                                       true_imu.specific_force_imu_mps2, true_imu.t_s));
          !s)
        return s;
      if (Status s = truth_writer->WriteImuBias({true_imu.t_s, imu.Bias().gyro_radps, imu.Bias().accel_mps2}); !s)
        return s;
      ++summary->imu_samples;
    }
    encoder_samples.clear();
    drive.DrainEncoderSamples(&encoder_samples);
    for (EncoderSample e : encoder_samples) {
      if (e.t_s > config.duration_s) continue;
      e.t_s = config.clocks.Encoder().Stamp(e.t_s);
      if (Status s = writer->Write(e); !s) return s;
      ++summary->encoder_samples;
    }
    if (Status s = truth.WriteCovered(trace); !s) return s;
    if (Status s = lidar.FireCovered(trace, writer, summary); !s) return s;
    if (Status s = camera ? camera->RenderCovered(trace, config.duration_s, writer->inner(), truth_writer) : Status::Ok(); !s)
      return s;
    trace.DropBefore(std::min({lidar.NextFiringTime(), truth.NextTime(),
                               camera ? camera->NextNeededTime() : lidar.NextFiringTime()}));
    if (progress && state.time_s() >= next_progress_s) {
      progress(std::min(1.0, state.time_s() / config.duration_s));
      next_progress_s += 1.0;
    }
  }
  summary->camera_frames = camera ? static_cast<size_t>(camera->frames()) : 0;
  return Status::Ok();
}

}  // namespace

std::vector<std::string> RecordingOutputNames() {
  return {RecordingLayout::kCalib,  RecordingLayout::kLidar,     RecordingLayout::kImu,
          RecordingLayout::kEncoder, RecordingLayout::kCamera,   RecordingLayout::kCameraDir,
          RecordingLayout::kTruthDir, "sim_config.yaml",          "rig_model.xml"};
}

Status PrepareRecordingDir(const std::string& dir, bool force) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return Status::Ok();
  if (!fs::is_directory(dir, ec)) return Status::Error(dir + ": exists and is not a folder");
  if (fs::is_empty(dir, ec)) return Status::Ok();
  if (!force)
    return Status::Error(dir + ": folder is not empty (a previous run?); choose another folder, or give --force "
                               "to replace its recording");
  for (const std::string& name : RecordingOutputNames()) {
    fs::remove_all(fs::path(dir) / name, ec);
    if (ec) return Status::Error((fs::path(dir) / name).string() + ": cannot remove: " + ec.message());
  }
  return Status::Ok();
}

Status RunSimulation(const SimConfig& config, const std::string& recording_dir, SimSummary* summary,
                     const ProgressFn& progress, const std::atomic<bool>* stop) {
  const auto wall0 = std::chrono::steady_clock::now();
  std::string why;
  if (!config.Validate(&why)) return Status::Error("sim config: " + why);
  SimWorld world;
  if (Status s = BuildWorld(config, &world); !s) return s;
  *summary = SimSummary{};
  summary->scene_triangles = world.triangles;
  summary->recording_dir = recording_dir;

  // The sim runs the true rig; calib.yaml holds what its owner believes (truth + drawn calibration errors, no
  // IMU clock offset).
  const RigCalib calib = config.TrueCalib();
  const CalibErrors calib_errors = DrawCalibErrors(config.rig_errors.calibration, config.seed);
  RecordingWriter writer;
  if (Status s = writer.Open(recording_dir, config.BelievedCalib()); !s) return s;
  TruthWriter truth;
  if (Status s = truth.Open(recording_dir); !s) return s;
  if (config.rig_errors.Enabled())
    if (Status s = WriteRigErrorTruth(recording_dir, config.rig_errors, calib_errors, calib); !s) return s;
  if (Status s = WriteClockTruth(recording_dir, config.TrueClocks()); !s) return s;
  if (Status s = WriteResolvedConfig(config, world, recording_dir); !s) return s;
  FaultyWriter faulty(config.faults, config.seed, &writer);  // passes everything through when no fault is on
  if (Status s = RunPhysics(config, world, calib, &faulty, &truth, summary, progress, stop); !s) return s;
  if (Status s = faulty.Close(); !s) return s;
  if (Status s = truth.Close(); !s) return s;
  if (config.faults.Enabled()) {
    if (Status s = WriteFaultTruth(recording_dir, faulty.truth()); !s) return s;
    const FaultTruth& f = faulty.truth();
    summary->lidar_packets = summary->lidar_packets - f.lidar.data_packets_in + f.lidar.data_packets_out;
    summary->imu_samples -= f.imu.dropped_interval + f.imu.dropped_random;
  }
  if (!summary->stopped) summary->sim_duration_s = config.duration_s;
  summary->wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  if (progress) progress(1.0);
  return Status::Ok();
}

}  // namespace rotolidar::sim
