#pragma once
// Allan deviation of inertial-sensor rate data and the fit of Kalibr's noise model to it
// (IEEE Std 952-1997 Annex C; docs/noise_models.md).
//
// Overlapping Allan variance of a rate series y_k sampled at rate r (tau0 = 1 / r), cluster size m, tau = m tau0:
//   theta_k = tau0 * sum_{i<k} y_i   (integrated signal, theta_0 = 0)
//   AVAR(tau) = 1 / (2 tau^2 (N - 2m)) * sum_{k=0}^{N-2m} (theta_{k+2m} - 2 theta_{k+m} + theta_k)^2
// Model fitted per axis (weighted least squares on AVAR, non-negative coefficients):
//   AVAR(tau) = N^2 / tau + K^2 tau / 3 [+ (2 ln 2 / pi) B^2]
//   N: white-noise density (Kalibr *_noise_density; rad/s/sqrt(Hz) or m/s^2/sqrt(Hz))
//   K: bias random walk (Kalibr *_random_walk; rad/s^2/sqrt(Hz) or m/s^3/sqrt(Hz))
//   B: bias instability (the flat floor; rad/s or m/s^2), only when AllanOptions::fit_bias_instability.
// Pure functions, thread-safe; no I/O except WriteAllanTable.
#include <array>
#include <ostream>
#include <vector>

#include "core/types/messages.hpp"

namespace rotolidar::bench {

struct AllanOptions {
  int points_per_decade = 10;         ///< log spacing of the cluster sizes m (unique integers, m >= 1)
  double max_cluster_fraction = 0.1;  ///< largest tau = this * series duration (few clusters beyond it)
  bool fit_bias_instability = false;  ///< add the B term to the fit
};

/// Allan deviation table of one series: tau_s[i] = m_i / rate, adev[i] = sqrt(AVAR(tau_s[i])), ascending tau.
struct AllanCurve {
  std::vector<double> tau_s;
  std::vector<double> adev;
  std::vector<long> cluster_size;  ///< m_i
  long samples = 0;                ///< N
};

/// The fitted noise terms of one axis. converged is false (values 0) when fewer than 3 tau points exist.
struct AllanFit {
  bool converged = false;
  double white_density = 0.0;      ///< N
  double random_walk = 0.0;        ///< K
  double bias_instability = 0.0;   ///< B (0 unless fitted)
  double rms_log_residual = 0.0;   ///< RMS of ln(model / AVAR) over the fitted points
  int points = 0;                  ///< tau points used
};

/// Overlapping Allan deviation of `series` sampled at rate_hz over log-spaced cluster sizes
/// 1 <= m <= max_cluster_fraction * N. Requires rate_hz > 0 (ROTOLIDAR_CHECK); fewer than 4 samples give an
/// empty curve. O(N) per tau point.
AllanCurve OverlappingAllanDeviation(const std::vector<double>& series, double rate_hz,
                                     const AllanOptions& options = {});

/// Weighted least-squares fit of the model above to `curve`: each AVAR point is weighted by its relative
/// uncertainty (~ sqrt(m / N)), so the many short-tau clusters pin N and the long-tau ones K; coefficients
/// that would come out negative are dropped (the best non-negative subset is kept).
AllanFit FitAllan(const AllanCurve& curve, const AllanOptions& options = {});

struct AllanAxis {
  AllanCurve curve;
  AllanFit fit;
};

/// Per-axis Allan analysis of an IMU record (imu frame axes x, y, z).
struct AllanReport {
  double rate_hz = 0.0;
  double duration_s = 0.0;  ///< samples / rate_hz
  std::array<AllanAxis, 3> gyro, accel;
};

/// Runs OverlappingAllanDeviation + FitAllan on each gyro and accel axis. The samples are taken as evenly
/// spaced at rate_hz (their stamps are not used); a static record is assumed (constant true signal).
AllanReport FitImuAllan(const std::vector<ImuSample>& samples, double rate_hz, const AllanOptions& options = {});

/// Writes the tau/adev table as CSV with a header: tau_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z
/// (adev in rad/s and m/s^2), then one "# fit" comment line per sensor axis with N, K, B.
void WriteAllanTable(std::ostream& out, const AllanReport& report);

}  // namespace rotolidar::bench
