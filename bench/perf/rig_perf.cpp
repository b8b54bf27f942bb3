// `rotolidar bench rig|allan`: the rig twin without the LiDAR (contract in rig_perf.hpp).
#include "bench/perf/rig_perf.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <memory>

#include "sim/rig/rig_physics.hpp"

namespace rotolidar::bench {
namespace {

struct Clock {
  std::clock_t cpu0 = std::clock();
  std::chrono::steady_clock::time_point wall0 = std::chrono::steady_clock::now();
  double Cpu() const { return double(std::clock() - cpu0) / CLOCKS_PER_SEC; }
  double Wall() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count(); }
};

/// Steps the rig for `duration_s`, handing every IMU sample to `on_imu`. `drive` may be null (motor unpowered).
template <typename OnImu>
Status StepRig(const sim::SimConfig& config, const sim::RigModel& model, const sim::BaseMotion& carrier,
               sim::RotorDrive* drive, double theta0, double omega0, RigBenchResult* r, OnImu on_imu) {
  sim::RigState state(model);
  sim::ImuModel imu(config.imu.noise, model.geometry().T_base_imu, config.seed, config.imu.errors);
  state.Reset(carrier.At(0.0), theta0, omega0);
  const long steps_per_imu = std::lround(1.0 / (config.imu.noise.rate_hz * state.timestep_s()));
  const long n_steps = long(std::ceil(config.duration_s / state.timestep_s() - 1e-9));
  std::vector<EncoderSample> encoder;
  for (long k = 0; k < n_steps; ++k) {
    if (Status s = state.Step(carrier.At(state.time_s()).T_world_base, drive); !s) return s;
    if (k % steps_per_imu == 0) {
      const sim::ImuTruth t = state.imu();
      on_imu(imu.SampleFromTruth(t.angular_rate_imu_radps, t.specific_force_imu_mps2, t.t_s));
      ++r->imu_samples;
    }
    if (drive) {
      encoder.clear();
      drive->DrainEncoderSamples(&encoder);
      r->encoder_samples += long(encoder.size());
    }
    ++r->physics_steps;
  }
  r->sim_s = state.time_s();
  return Status::Ok();
}

double RelError(double fitted, double configured) { return std::abs(fitted / configured - 1.0); }

}  // namespace

Status RunRigBench(const sim::SimConfig& config, RigBenchResult* result) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error("sim config: " + why);
  std::unique_ptr<sim::RigModel> model;
  if (Status s = sim::RigModel::Create(config.rig_model, &model); !s) return s;
  std::unique_ptr<sim::BaseMotion> carrier;
  if (Status s = sim::MakeCarrierMotion(config.carrier, &carrier); !s) return s;
  sim::StepperDrive drive(config.motor, config.seed);
  const sim::MotorReference ref0 = drive.profile().Reference(0.0);
  *result = RigBenchResult{};
  const Clock clock;
  double checksum = 0.0;  // keeps the IMU samples observable
  Status s = StepRig(config, *model, *carrier, &drive, ref0.theta_rad, ref0.omega_radps, result,
                     [&](const ImuSample& m) { checksum += m.accel_mps2.z(); });
  result->cpu_s = clock.Cpu();
  result->wall_s = clock.Wall();
  if (!std::isfinite(checksum)) return Status::Error("rig bench: non-finite IMU output");
  return s;
}

AllanSensorFit SensorFit(const std::array<AllanAxis, 3>& axes, double n_cfg, double k_cfg) {
  AllanSensorFit f;
  for (const AllanAxis& a : axes) {
    f.white_density += a.fit.white_density / 3.0;
    f.random_walk += a.fit.random_walk / 3.0;
    f.worst_axis_n_error = std::max(f.worst_axis_n_error, RelError(a.fit.white_density, n_cfg));
    f.worst_axis_k_error = std::max(f.worst_axis_k_error, RelError(a.fit.random_walk, k_cfg));
  }
  f.n_error = RelError(f.white_density, n_cfg);
  f.k_error = RelError(f.random_walk, k_cfg);
  return f;
}

Status RunAllanBench(const sim::SimConfig& base, double hours, AllanBenchResult* result) {
  sim::SimConfig config = base;
  config.duration_s = hours * 3600.0;
  config.rig_model.physics.timestep_s = 1.0 / config.imu.noise.rate_hz;  // at rest: one step per IMU sample
  config.carrier.type = sim::CarrierType::kScriptedLoop;
  std::string why;
  if (!(hours > 0 && hours <= 24)) return Status::Error("allan: --hours must be in (0, 24]");
  if (!config.rig_model.Validate(&why)) return Status::Error("rig_model: " + why);
  std::unique_ptr<sim::RigModel> model;
  if (Status s = sim::RigModel::Create(config.rig_model, &model); !s) return s;
  // A carrier that stands still: the scripted loop's pose at t = 0, held.
  struct Still final : sim::BaseMotion {
    Pose3 T;
    sim::BaseKinematics At(Seconds) const override { sim::BaseKinematics k; k.T_world_base = T; return k; }
  } still;
  still.T = sim::ScriptedBaseMotion(config.carrier.scripted_loop).At(0.0).T_world_base;
  std::vector<ImuSample> samples;
  samples.reserve(size_t(config.duration_s * config.imu.noise.rate_hz) + 1);
  *result = AllanBenchResult{};
  const Clock clock;
  if (Status s = StepRig(config, *model, still, nullptr, 0.0, 0.0, &result->run,
                         [&](const ImuSample& m) { if (m.t_s >= 1.0) samples.push_back(m); });
      !s)
    return s;
  result->run.cpu_s = clock.Cpu();
  result->run.wall_s = clock.Wall();
  result->report = FitImuAllan(samples, config.imu.noise.rate_hz);
  result->configured = config.imu.noise;
  const ImuNoise& n = result->configured;
  result->gyro = SensorFit(result->report.gyro, n.gyro_noise_density, n.gyro_random_walk);
  result->accel = SensorFit(result->report.accel, n.accel_noise_density, n.accel_random_walk);
  return Status::Ok();
}

}  // namespace rotolidar::bench
