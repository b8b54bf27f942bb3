#include "bench/perf/rig_perf.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <memory>

#include "bench/cli/options.hpp"
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

int BenchRig(int argc, char** argv) {
  sim::SimConfig config = sim::DefaultSimConfig();
  OptionParser p("bench rig", "Rig twin speed without the LiDAR: MuJoCo physics + stepper drive (PID, encoder) + "
                              "IMU model, one thread. Prints simulated seconds per CPU second (target >= 100x).");
  p.Add("config", "", "-", "sim config YAML (carrier, motor, rig_model, imu); default: built-in");
  p.Add("duration", "60", "s", "simulated time");
  p.Add("repeat", "3", "-", "repetitions (the median is reported)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  long repeat = 3;
  if (Status s = p.GetDouble("duration", &config.duration_s); !s) return std::cerr << "error: " << s.message << "\n", 2;
  if (Status s = p.GetInt("repeat", &repeat); !s || repeat < 1) return std::cerr << "error: --repeat >= 1\n", 2;
  if (!p.Get("config").empty()) {
    const double duration = config.duration_s;
    if (Status s = sim::LoadSimConfig(p.Get("config"), &config); !s) return std::cerr << "error: " << s.message << "\n", 1;
    config.duration_s = duration;
  }
  std::vector<double> ratios;
  for (long i = 0; i < repeat; ++i) {
    RigBenchResult r;
    if (Status s = RunRigBench(config, &r); !s) return std::cerr << "error: " << s.message << "\n", 1;
    std::printf("run %ld: %.1f s simulated, %ld steps, %ld IMU, %ld encoder samples in %.2f s CPU (%.2f s wall): "
                "%.1fx real time\n", i + 1, r.sim_s, r.physics_steps, r.imu_samples, r.encoder_samples, r.cpu_s,
                r.wall_s, r.RealTimeRatio());
    ratios.push_back(r.RealTimeRatio());
  }
  std::sort(ratios.begin(), ratios.end());
  std::printf("rig physics + IMU + encoder: median %.1fx real time on 1 core\n", ratios[ratios.size() / 2]);
  return 0;
}

int BenchAllan(int argc, char** argv) {
  sim::SimConfig config = sim::DefaultSimConfig();
  OptionParser p("bench allan", "Static rig through physics + IMU model; recovers the configured noise densities "
                                "and random walks from the Allan deviation (bar: within 10 %).");
  p.Add("hours", "24", "h", "static record length (BMI055 gyro K: 24 h gives 10 % at > 95 % confidence, docs)");
  p.Add("seed", "1", "-", "run seed");
  p.Add("table", "", "-", "write the tau/adev table (CSV) here");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  double hours = 24;
  long seed = 1;
  if (Status s = p.GetDouble("hours", &hours); !s) return std::cerr << "error: " << s.message << "\n", 2;
  if (Status s = p.GetInt("seed", &seed); !s) return std::cerr << "error: " << s.message << "\n", 2;
  config.seed = uint64_t(seed);
  AllanBenchResult r;
  if (Status s = RunAllanBench(config, hours, &r); !s) return std::cerr << "error: " << s.message << "\n", 1;
  if (!p.Get("table").empty()) {
    std::ofstream table(p.Get("table"));
    WriteAllanTable(table, r.report);
  }
  const ImuNoise& n = r.configured;
  std::printf("%.1f h static (%ld samples) in %.1f s CPU (%.0fx real time)\n", hours, r.run.imu_samples, r.run.cpu_s,
              r.run.RealTimeRatio());
  for (int a = 0; a < 3; ++a)
    std::printf("axis %c: gyro N %.4g (cfg %.4g) K %.4g (cfg %.4g) | accel N %.4g (cfg %.4g) K %.4g (cfg %.4g)\n",
                "xyz"[a], r.report.gyro[a].fit.white_density, n.gyro_noise_density, r.report.gyro[a].fit.random_walk,
                n.gyro_random_walk, r.report.accel[a].fit.white_density, n.accel_noise_density,
                r.report.accel[a].fit.random_walk, n.accel_random_walk);
  const auto row = [](const char* name, const AllanSensorFit& f, double n_cfg, double k_cfg) {
    std::printf("%-5s (3-axis mean): N %.4g (cfg %.4g, %+.1f %%)  K %.4g (cfg %.4g, %+.1f %%)  | worst axis: N %.1f %%, "
                "K %.1f %%\n", name, f.white_density, n_cfg, 100 * (f.white_density / n_cfg - 1), f.random_walk, k_cfg,
                100 * (f.random_walk / k_cfg - 1), 100 * f.worst_axis_n_error, 100 * f.worst_axis_k_error);
  };
  row("gyro", r.gyro, n.gyro_noise_density, n.gyro_random_walk);
  row("accel", r.accel, n.accel_noise_density, n.accel_random_walk);
  const bool pass = r.Pass(0.1);
  std::printf("%s\n", pass ? "PASS: each sensor's N and K within 10 %" : "FAIL: some term outside 10 %");
  return pass ? 0 : 1;
}

}  // namespace rotolidar::bench
