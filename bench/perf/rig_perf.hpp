#pragma once
// Benchmarks of the rig twin without the LiDAR (`rotolidar bench rig`, `rotolidar bench allan`).
//  - rig:   MuJoCo physics + stepper drive (PID, encoder) + IMU model for a simulated span, single-threaded;
//           the ratio to real time is simulated seconds per second of process CPU time.
//  - allan: a long static run (rig at rest, motor unpowered) through the same physics and IMU model; the Allan
//           deviation of the record recovers the configured white-noise densities N and random walks K.
#include <string>

#include "bench/eval/allan.hpp"
#include "core/util/status.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::bench {

struct RigBenchResult {
  double sim_s = 0.0;         ///< simulated time [s]
  double cpu_s = 0.0;         ///< process CPU time spent [s] (one thread)
  double wall_s = 0.0;        ///< wall time [s]
  long physics_steps = 0;
  long imu_samples = 0;
  long encoder_samples = 0;
  double RealTimeRatio() const { return cpu_s > 0 ? sim_s / cpu_s : 0.0; }
};

/// Runs `config` (its carrier, motor and IMU) for config.duration_s without the LiDAR.
Status RunRigBench(const sim::SimConfig& config, RigBenchResult* result);

/// One sensor's noise terms read from the Allan fits of its three axes. The noise is configured per sensor (one
/// N and one K, as in Kalibr's imu.yaml), so the sensor's estimate is the mean over the three axes (as
/// allan_variance_ros's analysis reports it); the per-axis spread is kept for the record.
struct AllanSensorFit {
  double white_density = 0.0;  ///< mean of the axes' N
  double random_walk = 0.0;    ///< mean of the axes' K
  double n_error = 0.0, k_error = 0.0;                   ///< |mean / configured - 1|: the pass criterion
  double worst_axis_n_error = 0.0, worst_axis_k_error = 0.0;  ///< max over axes of |axis / configured - 1|
};

struct AllanBenchResult {
  RigBenchResult run;
  AllanReport report;
  ImuNoise configured;
  AllanSensorFit gyro, accel;
  bool Pass(double tolerance) const {
    return gyro.n_error < tolerance && gyro.k_error < tolerance && accel.n_error < tolerance &&
           accel.k_error < tolerance;
  }
};

/// A static run of `hours` with `config`'s IMU (rig at rest at the origin, motor unpowered), physics at the IMU
/// period. The first second (the hinge settling against the imbalance) is discarded.
Status RunAllanBench(const sim::SimConfig& config, double hours, AllanBenchResult* result);

}  // namespace rotolidar::bench
